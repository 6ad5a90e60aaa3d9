"""Batched throughput per core: paths per second of each reduced model, one by one and in a batch.

The same path (a scene's load case, default the open chain under f+) is traced N times: one
by one through the model's runner (:func:`flexval.reducedmodels.models.run_reduced`: build,
trace, record), and as one batch of N copies
(:func:`flexval.reducedmodels.core.batch.run_batch`: the copies share one System, one assembly
and one factorisation per Newton iteration; ``ee``'s linear responses are solved and recorded
together; their connectors are built once, since the copies are of one mechanism). With
``--distinct`` every copy is a mechanism of its own (each flexure's section scaled by a factor
within 1e-3 of 1), as in a sweep: the batch then builds every copy's connectors. With
``--spread 0.02`` the factors are drawn from N(1, 0.02), as in the tolerance study: copies
then disagree on their steps now and then, and those that leave a batch go on as smaller
ones (the batch sizes column). The one-by-one paths are the first copies'. Both in this
process, on one core (BLAS limited to one thread), median of ``--repeats`` runs: wall time,
and the process's CPU time (what a path costs a core, whatever else shares the machine; on a
busy machine the wall time is that over the share of a core the process gets). The speed-up
is of the CPU times. The batch's end values are checked against the solo run's (they must
agree to 1e-12 of the path's motion) before anything is timed, and one untimed batch runs
first: a process's first batch of a size grows its heap (a 1000-copy ``prbm`` batch about a
third slower), which a sweep's worker pays once, not per batch.

Run: ``python benchmarks/bench_batch.py [--scene open_chain] [--case f+] [--n 1000]
[--distinct] [--spread S]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import time

import numpy as np

from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.batch import run_batch
from flexval.reducedmodels.core.threads import limit_threads
from flexval.reducedmodels.models import run_reduced

MODELS = ("ee", "dcmm:1", "dcmm:3", "prbm", "beam:20", "beam:100")
"""The reduced models timed (the paper's four, at their usual resolutions)."""

SOLO_PATHS = 200
"""Paths timed one by one per repeat (beam:100: a tenth): enough for a stable median."""


def check(mech, spec, case) -> None:
    """The batch gives the solo path (end displacement and rotation to 1e-12 of the motion)."""
    solo = run_reduced(mech, spec, case)
    batched = run_batch([mech] * 3, spec, [case] * 3)[1]
    scale = max(np.hypot(solo.dx, solo.dy).max(), 1e-300)
    worst = max(abs(solo.dx[-1] - batched.dx[-1]), abs(solo.dy[-1] - batched.dy[-1])) / scale
    if worst > 1e-12 or abs(solo.rotation[-1] - batched.rotation[-1]) > 1e-12 * max(
        abs(solo.rotation[-1]), 1e-300
    ):
        raise SystemExit(f"{spec.id}: the batch's path differs from the solo run's ({worst:.2e})")


def distinct(mech, n: int, spread: float | None = None) -> list:
    """n mechanisms of their own: every flexure's section scaled by 1 + 1e-3 (k / n - 1/2),
    or with ``spread`` by factors drawn from N(1, spread) (seed 1; a tolerance study's)."""
    if spread is None:
        factors = 1.0 + 1e-3 * (np.arange(n) / n - 0.5)
    else:
        factors = np.random.default_rng(1).normal(1.0, spread, n)
    return [
        dataclasses.replace(
            mech,
            flexures=tuple(
                dataclasses.replace(f, section=f.section.scaled(float(factor)))
                for f in mech.flexures
            ),
        )
        for factor in factors
    ]


def per_path(run, count: int, repeats: int) -> tuple[float, float]:
    """Medians over ``repeats`` of the wall and the CPU seconds per path of ``run()`` (``count``
    paths)."""
    wall, cpu = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        run()
        wall.append((time.perf_counter() - t0) / count)
        cpu.append((time.process_time() - c0) / count)
    return statistics.median(wall), statistics.median(cpu)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="open_chain")
    ap.add_argument("--case", default="f+")
    ap.add_argument("--n", type=int, default=1000, help="copies per batch (default 1000)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--models", default=",".join(MODELS))
    ap.add_argument(
        "--distinct", action="store_true", help="every copy a mechanism of its own (a sweep's)"
    )
    ap.add_argument(
        "--spread",
        type=float,
        default=None,
        help="distinct copies whose sections are scaled by N(1, SPREAD) draws (0.02: the "
        "tolerance study's h ~ N(0.1, 0.002) mm); each copy then takes its own steps",
    )
    args = ap.parse_args()
    limit_threads()
    sc = load_scene(args.scene)
    mech = sc.mechanism
    case = next(c for c in sc.load_cases if c.name == args.case)
    spread = args.spread
    copies = distinct(mech, args.n, spread) if args.distinct or spread else [mech] * args.n
    print(
        f"{args.scene} {args.case}; batches of {args.n} "
        f"{'distinct ' if args.distinct or spread else ''}copies"
        f"{f' (sections scaled by N(1, {spread}))' if spread else ''}; median of {args.repeats}; "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    print(
        f"{'model':10s} {'one by one':>22s} {'batched':>22s} {'batched, CPU':>22s} "
        f"{'speed-up':>9s}  batch sizes"
    )
    for model in args.models.split(","):
        spec = parse_model(model)
        check(mech, spec, case)
        heavy = spec.family == "beam" and (spec.resolution or 0) >= 100
        n_solo = SOLO_PATHS // 10 if heavy else SOLO_PATHS
        solo, solo_cpu = per_path(
            lambda spec=spec, n_solo=n_solo: [
                run_reduced(copies[k], spec, case) for k in range(n_solo)
            ],
            n_solo,
            args.repeats,
        )
        sizes: set = set()

        def batch(spec=spec, sizes=sizes) -> None:
            paths = run_batch(copies, spec, [case] * args.n)
            sizes.update(p.stats["batch"] for p in paths)

        batch()  # the heap grown once (see the module text)
        batched, batched_cpu = per_path(batch, args.n, args.repeats)
        print(
            f"{model:10s} {1e3 * solo:8.3f} ms {1 / solo:8.0f}/s {1e3 * batched:8.3f} ms "
            f"{1 / batched:8.0f}/s {1e3 * batched_cpu:8.3f} ms {1 / batched_cpu:8.0f}/s "
            f"{solo_cpu / batched_cpu:8.1f}x  {sorted(sizes)}",
            flush=True,
        )


if __name__ == "__main__":
    main()
