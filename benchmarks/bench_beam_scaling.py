"""How the corotational beam model's cost grows with the number of elements N.

Traces one load case (11 levels) of the open chain with beam:N for
N = 20 ... 2000 elements per flexure and prints, per N, the unknowns, the
Newton iterations, the median wall time of the whole load path over the
repeats (model build included), the time per element and per Newton
iteration. Wall time per path is what the validation reports compare, and
time per iteration separates the cost of one assembly and solve (expected
~linear in N: the tangent is banded) from the iteration count the adaptive
stepping needs.

Usage::

    python benchmarks/bench_beam_scaling.py [--case f+] [--repeats 5] [--sizes 20 50 ...]
"""

from __future__ import annotations

import argparse
import statistics

from geometry import load_scene
from reducedmodels.catalogue import parse_model
from reducedmodels import run_reduced

SIZES = (20, 50, 100, 200, 500, 1000, 2000)


def measure(n: int, case_name: str, repeats: int) -> tuple[int, int, float]:
    """Unknowns, Newton iterations and median wall seconds of beam:n on one open-chain load case."""
    scene = load_scene("open_chain")
    case = scene.load_case(case_name)
    runs = [run_reduced(scene.mechanism, parse_model(f"beam:{n}"), case) for _ in range(repeats)]
    stats = runs[-1].stats
    return stats["unknowns"], stats["newton_iterations"], statistics.median(r.seconds for r in runs)


def main() -> None:
    """Print the scaling table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="f+", help="open-chain load case (default f+)")
    parser.add_argument("--repeats", type=int, default=5, help="runs per N; the median is shown")
    parser.add_argument("--sizes", type=int, nargs="+", default=SIZES, help="element counts N")
    args = parser.parse_args()
    print(f"open_chain, load case {args.case}, 11 levels, median of {args.repeats} runs")
    print(f"{'N':>6} {'unknowns':>9} {'newton':>7} {'seconds':>9} {'s/N':>10} {'ms/iter':>8}")
    for n in args.sizes:
        unknowns, iterations, seconds = measure(n, args.case, args.repeats)
        print(f"{n:>6} {unknowns:>9} {iterations:>7} {seconds:>9.4f} {seconds / n:>10.2e} "
              f"{1e3 * seconds / max(iterations, 1):>8.3f}")


if __name__ == "__main__":
    main()
