"""How the batched cost per path falls with the number of copies in a batch.

Runs one load case of a scene with each model alone (median of the repeats)
and as batches of N identical copies through the report's own timing code
(:func:`flexval.validation.studies.batchtiming.batch_paths`: the copies' Systems built,
traced together and recorded inside the clock), and prints per N the
median wall time of the batch divided by N, in ms, with the fastest repeat
beside it. Where that cost stops falling, the per-batch costs are spread thin:
the figures behind :data:`flexval.validation.studies.batchtiming.BATCH_COPIES`,
:data:`~flexval.validation.studies.batchtiming.BATCH_LADDER`,
:data:`~flexval.validation.studies.batchtiming.BATCH_GAIN` and
:data:`~flexval.validation.studies.batchtiming.BATCH_UNKNOWNS`. Each model is warmed up
first (one path alone, one batch of two) so that loading its compiled kernels
is not timed.

Usage::

    python benchmarks/bench_batch_copies.py [--scene open_chain] [--case f+] [--repeats 3]
        [--models dcmm:1 beam:20 beam:100 prbm] [--sizes 10 30 100 300 1000]
"""

from __future__ import annotations

import argparse
import statistics

from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.run import run_model
from flexval.validation.studies.batchtiming import batch_paths

MODELS = ("dcmm:1", "beam:20", "beam:100", "prbm")
SIZES = (10, 30, 100, 300, 1000)
MOST_UNKNOWNS = 300_000
"""Largest batch timed (unknowns of all copies): beyond, a batch of a large model takes
seconds and tells nothing new (its per-path cost is flat long before)."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="open_chain")
    ap.add_argument("--case", default="f+")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--models", nargs="+", default=list(MODELS))
    ap.add_argument("--sizes", nargs="+", type=int, default=list(SIZES))
    args = ap.parse_args()
    scene = load_scene(args.scene)
    case = scene.load_case(args.case)
    print(
        f"{scene.name} {case.name}: ms per path, median of {args.repeats} "
        "(fastest in parentheses); alone, then in batches of N copies"
    )
    print(
        f"{'model':10s} {'unknowns':>8s} {'alone':>15s} "
        + " ".join(f"{'N=' + str(n):>15s}" for n in args.sizes)
    )
    for model in args.models:
        spec = parse_model(model)
        batch_paths(scene, spec, case, 2)  # warm-up: kernels loaded, caches filled
        alone = [run_model(scene, spec, case) for _ in range(args.repeats + 1)][1:]
        unknowns = alone[0].stats["unknowns"]
        cells = [_cell([lp.seconds for lp in alone])]
        for n in args.sizes:
            if n * unknowns > MOST_UNKNOWNS:
                cells.append(f"{'-':>15s}")
                continue
            cells.append(
                _cell([batch_paths(scene, spec, case, n)[1] / n for _ in range(args.repeats)])
            )
        print(f"{model:10s} {unknowns:8d} " + " ".join(cells), flush=True)


def _cell(seconds: list[float]) -> str:
    return f"{1e3 * statistics.median(seconds):7.3f} ({1e3 * min(seconds):.3f})".rjust(15)


if __name__ == "__main__":
    main()
