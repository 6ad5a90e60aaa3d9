"""How the corotational beam model's cost grows with the number of elements N.

Traces one load case (11 levels) of the open chain with beam:N for
N = 10 ... 2000 elements per flexure and prints, per N, the unknowns, the
Newton iterations, the median wall time of the whole load path over the
repeats (model build included; after one warm-up path that loads the
compiled kernels, see README.md here, "Compiled kernels"), the path time per
Newton iteration, and the
time of one Newton iteration alone (assembly, factorisation and solve of the
correction at the path's end state, fastest of many) in total and per
unknown. Wall time per path is what the validation reports compare; the
iteration alone separates the cost of one assembly and solve (expected
linear in the unknowns: the tangent is banded) from the iteration count and
the per-level work (predictor, recording). The last column is that cost per
unknown relative to the cheapest N's, and the last line their spread (1:
proportional to the unknowns).

Usage::

    python benchmarks/bench_beam_scaling.py [--case f+] [--repeats 5] [--sizes 10 20 ...]
"""

from __future__ import annotations

import argparse
import statistics
import time

from flexval.geometry import load_scene
from flexval.reducedmodels import run_reduced
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.newton import FixedLoad
from flexval.reducedmodels.core.tracer import LoadControl, trace
from flexval.reducedmodels.models import build_system

SIZES = (10, 20, 50, 100, 200, 500, 1000, 2000)
ITERATION_BUDGET = 0.2
"""Seconds spent timing one Newton iteration per N (the fastest of as many as fit)."""


def iteration_seconds(n: int, case_name: str) -> float:
    """Fastest wall time of one Newton iteration of beam:n at the load path's end state, s."""
    scene = load_scene("open_chain")
    case = scene.load_case(case_name)
    system = build_system(scene.mechanism, parse_model(f"beam:{n}"))
    loads = system.loads(case)
    for point in trace(system, loads, LoadControl(case.factors())):
        q = point.state
    problem = FixedLoad(system, loads, 1.0)
    best, spent = float("inf"), 0.0
    while spent < ITERATION_BUDGET:
        t0 = time.perf_counter()
        g, K = problem.assemble(q)
        problem.correction(q, g, K)
        dt = time.perf_counter() - t0
        best, spent = min(best, dt), spent + dt
    return best


def measure(n: int, case_name: str, repeats: int) -> tuple[int, int, float]:
    """Unknowns, Newton iterations and median wall seconds of beam:n on one open-chain load case."""
    scene = load_scene("open_chain")
    case = scene.load_case(case_name)
    spec = parse_model(f"beam:{n}")
    run_reduced(scene.mechanism, spec, case)  # warm-up: the compiled kernels loaded once
    runs = [run_reduced(scene.mechanism, spec, case) for _ in range(repeats)]
    stats = runs[-1].stats
    return stats["unknowns"], stats["newton_iterations"], statistics.median(r.seconds for r in runs)


def main() -> None:
    """Print the scaling table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="f+", help="open-chain load case (default f+)")
    parser.add_argument("--repeats", type=int, default=5, help="runs per N; the median is shown")
    parser.add_argument("--sizes", type=int, nargs="+", default=SIZES, help="element counts N")
    args = parser.parse_args()
    rows = []
    for n in args.sizes:
        unknowns, iterations, seconds = measure(n, args.case, args.repeats)
        rows.append((n, unknowns, iterations, seconds, iteration_seconds(n, args.case)))
    cheapest = min(one / unknowns for _, unknowns, _, _, one in rows)
    print(
        f"open_chain, load case {args.case}, 11 levels, median of {args.repeats} runs; "
        f"one iteration: fastest in {ITERATION_BUDGET} s"
    )
    print(
        f"{'N':>6} {'unknowns':>9} {'newton':>7} {'path s':>9} {'path ms/iter':>13} "
        f"{'iteration us':>13} {'us/unknown':>11} {'rel.':>6}"
    )
    for n, unknowns, iterations, seconds, one in rows:
        print(
            f"{n:>6} {unknowns:>9} {iterations:>7} {seconds:>9.4f} "
            f"{1e3 * seconds / max(iterations, 1):>13.3f} {1e6 * one:>13.1f} "
            f"{1e6 * one / unknowns:>11.4f} {one / unknowns / cheapest:>6.2f}"
        )
    spread = max(one / unknowns for _, unknowns, _, _, one in rows) / cheapest
    print(
        f"cost of one iteration per unknown: largest / smallest = {spread:.2f} "
        "(1: proportional to the unknowns)"
    )


if __name__ == "__main__":
    main()
