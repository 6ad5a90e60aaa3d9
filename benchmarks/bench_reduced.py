"""Speed of the reduced models: median wall time of one load path (11 levels).

Run: ``python benchmarks/bench_reduced.py [--repeats 7]``. Prints, for each
built-in scene, load case and model, the median seconds of the whole load
path (model build included), Newton iterations and the end values, so time
is always read next to what it buys. The figures to aim at: dcmm:1, dcmm:2
and prbm at most 1 ms, ee at most 0.2 ms on every case (README.md here has
the current ones).
"""

from __future__ import annotations

import argparse
import statistics

from flexval.geometry import load_scene
from flexval.reducedmodels import run_reduced
from flexval.reducedmodels.catalogue import parse_model

MODELS = ("ee", "dcmm:1", "dcmm:2", "dcmm:3", "prbm", "beam:20", "beam:100")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    args = ap.parse_args()
    print(
        f"{'scene':<13} {'case':<5} {'model':<9} {'median ms':>10} {'min ms':>8} "
        f"{'newton':>7} {'|d| mm':>9} {'rot rad':>9}"
    )
    for name in ("open_chain", "closed_chain"):
        scene = load_scene(name)
        for case in scene.load_cases:
            for m in args.models:
                spec = parse_model(m)
                times = []
                for _ in range(args.repeats):
                    lp = run_reduced(scene.mechanism, spec, case)
                    times.append(lp.seconds)
                print(
                    f"{name:<13} {case.name:<5} {m:<9} {1e3 * statistics.median(times):>10.2f} "
                    f"{1e3 * min(times):>8.2f} {lp.stats['newton_iterations']:>7} "
                    f"{lp.displacement[-1]:>9.4f} {lp.rotation[-1]:>9.4f}"
                )


if __name__ == "__main__":
    main()
