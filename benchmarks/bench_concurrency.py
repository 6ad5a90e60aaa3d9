"""Two flexval load paths at once: does each stay close to its time alone?

Runs one load path in a worker process alone, then in two worker processes
started together, and reports each worker's median time and the slow-down
(concurrent time / time alone; about 1 is ideal when the machine has a free
core for each worker, and 1.5 is the bar). Each worker first runs
the path once untimed (imports, mesh cache), reports that it is ready and
waits; the parent starts the timed ``--repeats`` runs of all workers at
once, so the timed phases overlap whatever each worker's start-up took.
The time alone is measured before and after the pair and the smaller is
used, so that a load that changes meanwhile does not pass for a slow-down.
Times are wall seconds: measure on an otherwise idle machine.

It does so twice: with flexval's thread control (the default cap of
``flexval.reducedmodels.core.threads``) and without it (``FLEXVAL_BLAS_THREADS=0``).
``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` and ``MKL_NUM_THREADS`` are
removed from the workers' environment so that flexval's control is what
limits the pools: without it OpenBLAS starts one busy-waiting thread per
core and two processes fight over the cores.

Usage: ``python benchmarks/bench_concurrency.py [--scene closed_chain]
[--case f+] [--model continuum:1] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def worker(scene_name: str, case_name: str, model: str, repeats: int) -> None:
    """Run the path once untimed, then ``repeats`` timed runs; print the median seconds."""
    from flexval.geometry import load_scene
    from flexval.reducedmodels.catalogue import parse_model
    from flexval.validation.run import run_model

    scene = load_scene(scene_name)
    spec, case = parse_model(model, "<benchmark>", "--model"), scene.load_case(case_name)
    run_model(scene, spec, case)
    print("ready", flush=True)
    sys.stdin.readline()  # the parent's "go": all workers start timing together
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        run_model(scene, spec, case)
        times.append(time.perf_counter() - t0)
    print(statistics.median(times))


def run_workers(count: int, args: argparse.Namespace, controlled: bool) -> list[float]:
    """Start ``count`` workers together; return each one's median seconds."""
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    if controlled:
        env.pop("FLEXVAL_BLAS_THREADS", None)
    else:
        env["FLEXVAL_BLAS_THREADS"] = "0"
    command = [
        sys.executable,
        __file__,
        "--worker",
        "--scene",
        args.scene,
        "--case",
        args.case,
        "--model",
        args.model,
        "--repeats",
        str(args.repeats),
    ]
    procs = [
        subprocess.Popen(command, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        for _ in range(count)
    ]
    ready = [p.stdout.readline().strip() for p in procs]
    if ready != ["ready"] * count:
        for p in procs:
            p.kill()
        raise SystemExit(f"a worker failed before its timed runs: {ready}")
    for p in procs:  # start the timed runs of all workers at once
        p.stdin.write("go\n")
        p.stdin.flush()
    outputs = [p.communicate()[0] for p in procs]
    if any(p.returncode for p in procs):
        raise SystemExit(f"a worker failed: {outputs}")
    return [float(out.split()[-1]) for out in outputs]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="closed_chain")
    parser.add_argument("--case", default="f+")
    parser.add_argument("--model", default="continuum:1")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.scene, args.case, args.model, args.repeats)
        return
    print(
        f"{args.scene} {args.case} {args.model}, median of {args.repeats} runs per worker, "
        f"{os.cpu_count()} cores, load average before: {os.getloadavg()[0]:.1f}"
    )
    print(f"{'thread control':<28}{'alone s':>9}{'two at once s':>16}{'slow-down':>11}")
    for controlled, label in ((True, "flexval default (1 thread)"), (False, "none (BLAS default)")):
        before = run_workers(1, args, controlled)[0]
        pair = run_workers(2, args, controlled)
        alone = min(before, run_workers(1, args, controlled)[0])
        print(f"{label:<28}{alone:>9.3f}{pair[0]:>8.3f}{pair[1]:>8.3f}{max(pair) / alone:>10.2f}x")


if __name__ == "__main__":
    main()
