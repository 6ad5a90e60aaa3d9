"""Throughput of `flexval sweep` on Dask: 1 vs 2 workers, and Dask's overhead vs a plain loop.

Run: ``python benchmarks/bench_sweep.py [--n 1000] [--continuum-n 10] [--batch N]
[--cases f+]`` (about 4.5 minutes on the quiet 2-core machine with the defaults; the
batch defaults to the engine's automatic choice,
:func:`flexval.validation.sweep.engine.auto_batch`).

The sweep: ``--n`` random variants of the open chain (flexure thickness h
uniform in 0.08..0.12 mm, Young's modulus lognormal about 2100 MPa with
sigma 0.05, the force of f+ uniform in 2..4 mN), zipped, load case f+
(``--cases``), the reduced models ee, dcmm:1, dcmm:2, prbm, beam:20 against
beam:100, with the default outputs (errors, times, peak stress). The same
rows are computed three ways, each timed from submission to the last Parquet
part written (point generation and cluster start-up excluded):

- a plain loop in this process (the task functions called one after the other);
- :func:`flexval.validation.sweep.run_sweep` on a LocalCluster of 1 worker process;
- the same on 2 worker processes.

Printed for each: wall time, runs (load paths) per second, and the
workers' *busy fraction*: the seconds Dask's task stream records inside the
tasks, summed over the tasks, over wall time x workers (for the loop: the
seconds inside the task functions over its wall time); for Dask also the
CPU time of the driver process (scheduler, client, Parquet writes) against
the work: on a machine with as many cores as workers it is taken from them. Then Dask's overhead
against the loop on 1 worker (target < 20 %), Dask's cost per task (wall
time not spent inside a task, over the tasks), and the scaling efficiency
from 1 to 2 workers, T1 / (2 T2) (target >= 80 %). The same follows on
``--continuum-n`` points with continuum:0 as the reference (no loop).

On a machine shared with other jobs the wall times measure the neighbours as
much as flexval (the load average is printed before each configuration):
2 workers cannot get 2 cores. The busy fractions are the load-independent
part: contention slows the tasks and the wall alike, so a busy fraction
below 100 % is time the workers spent idle (scheduling, transfers, the
driver writing parts, the tail of the last tasks), which is what Dask
itself costs.

``--tolerance [FILE]`` runs a tolerance sweep (default
``benchmarks/sweeps/tolerance_open_chain.toml``, 20,000 points) as ``flexval sweep
--workers N --no-cache`` runs it and prints its wall time split into loading the sweep,
starting the local cluster, ``run_sweep``, closing the cluster, reading the rows back and
writing the outputs (summary, figures, tolerance study), with the CPU time per point of the
driver (all of it, and in ``run_sweep``) and of the workers; ``--points N`` draws every axis
N times instead. ``--scaling 1,2,4,8,16`` runs such a sweep (default
``benchmarks/sweeps/scaling_open_chain.toml``: 10,000 points, dcmm:2 and prbm against
beam:100; ``--tolerance FILE`` another) once per worker count and prints the strong-scaling
efficiency T1 w1 / (w Tw) against the first count, over the whole wall and over
``run_sweep`` alone; then the machine's own ceiling: w independent plain loops of
``--ceiling-points`` points run at once against one alone (what w cores give w processes that
share nothing: memory bandwidth, turbo and hyper-threads show here, not Dask).
``--cluster-start`` times the local cluster's start, first task and close with its
start method (a forkserver) and with Dask's ``spawn``, each in fresh processes,
alternating.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time

from distributed import Client, get_task_stream

from flexval.validation.sweep import (
    local_cluster,
    parse_sweep,
    results_store,
    run_sweep,
    sweep_models,
)
from flexval.validation.sweep.engine import auto_batch, chunks, task_info
from flexval.validation.sweep.tasks import PointBlock, SweepJob, model_task, reference_task

MODELS = ["ee", "dcmm:1", "dcmm:2", "prbm", "beam:20"]


def variants(n: int, reference: str, batch: int | None, cases: list[str]) -> dict:
    """Sweep data of ``n`` random open-chain variants (zipped axes, seeds fixed)."""
    return {
        "name": f"bench_{n}",
        "base": "open_chain",
        "models": MODELS,
        "reference": reference,
        "load_cases": cases,
        "combine": "zip",
        **({"batch": batch} if batch else {}),
        "axes": [
            {
                "path": "section.thickness",
                "sample": "uniform",
                "low": 0.08,
                "high": 0.12,
                "count": n,
                "seed": 1,
            },
            {
                "path": "material.youngs_modulus",
                "sample": "lognormal",
                "median": 2100.0,
                "sigma": 0.05,
                "count": n,
                "seed": 2,
            },
            {
                "path": "load_cases.f+.value",
                "sample": "uniform",
                "low": 2e-3,
                "high": 4e-3,
                "count": n,
                "seed": 3,
            },
        ],
    }


def _block(sweep, positions: list[int]) -> PointBlock:
    """The parameter block of the points at ``positions`` (as the engine sends it)."""
    values = sweep.points.builder.values(positions)
    digests = tuple(sweep.points.digest(k) for k in positions)
    return PointBlock(tuple(positions), values, digests, (True,) * len(positions))


def plain_loop(sweep) -> tuple[float, int, float]:
    """Wall seconds, rows and seconds inside the task functions, called one after the other
    (their parts are written to a temporary folder)."""
    out = tempfile.mkdtemp(prefix="bench_sweep_loop_")
    b = sweep.points.builder
    job = SweepJob(
        task_info(sweep), b.light(), tuple(a.path for a in sweep.axes), sweep.load_cases, out
    )
    positions = list(range(len(sweep.points)))
    inside = 0.0
    t0 = time.perf_counter()
    try:
        t = time.perf_counter()
        ref = reference_task(_block(sweep, positions), sweep.reference, job, use_cache=False)
        inside += time.perf_counter() - t
        rows = ref["summary"]["rows"]
        for spec in sweep.models:
            for chunk in chunks(positions, _batch(sweep, 1)):
                t = time.perf_counter()
                rows += model_task(_block(sweep, chunk), spec, job, [ref])["rows"]
                inside += time.perf_counter() - t
    finally:
        shutil.rmtree(out)
    return time.perf_counter() - t0, rows, inside


def _batch(sweep, workers: int) -> int:
    """Points per reduced-model task of ``sweep`` on ``workers`` workers."""
    return sweep.batch or auto_batch(len(sweep.valid_points), workers)


def _in_tasks(stream: list[dict]) -> float:
    """Seconds the workers spent computing tasks (Dask's task stream, 'compute' intervals)."""
    return sum(
        s["stop"] - s["start"]
        for task in stream
        for s in task["startstops"]
        if s["action"] == "compute"
    )


def on_dask(sweep, workers: int) -> tuple[float, int, int, float, float]:
    """Wall seconds, rows, tasks, seconds inside tasks, and the CPU seconds of this (driver)
    process, which holds the scheduler and writes the parts, of run_sweep on a fresh
    LocalCluster."""
    out = tempfile.mkdtemp(prefix="bench_sweep_")
    try:
        with local_cluster(workers, sweep_models(sweep)) as cluster, Client(cluster) as client:
            client.wait_for_workers(workers)
            cpu = time.process_time()
            with get_task_stream(client) as stream:
                stats = run_sweep(sweep, out, client, use_cache=False)
            cpu = time.process_time() - cpu
        assert len(results_store(sweep, out).keys()) == stats.rows_written
        return stats.seconds, stats.rows_written, stats.tasks, _in_tasks(stream.data), cpu
    finally:
        shutil.rmtree(out)


def _line(label: str, wall: float, rows: int, busy: float, note: str = "") -> None:
    print(
        f"  {label:<11}: {wall:8.2f} s {rows / wall:8.1f} runs/s  busy {100 * busy:5.1f} %"
        f"{note}  (load average {os.getloadavg()[0]:.1f})",
        flush=True,
    )


def report(label: str, sweep, loop: bool) -> None:
    """Time the sweep the three ways (two without the loop) and print the ratios."""
    print(
        f"\n{label}: {len(sweep.valid_points)} points x ({len(sweep.models)} models + "
        f"{sweep.reference.id}) x {len(sweep.load_cases)} case(s); points per task "
        f"{_batch(sweep, 1)} (1 worker), {_batch(sweep, 2)} (2 workers); "
        f"load average before {os.getloadavg()[0]:.1f}",
        flush=True,
    )
    if loop:
        t_loop, rows, inside = plain_loop(sweep)
        _line("plain loop", t_loop, rows, inside / t_loop)
    t1, rows1, tasks, in1, cpu1 = on_dask(sweep, 1)
    _line(
        "dask 1 wkr",
        t1,
        rows1,
        in1 / t1,
        f"  ({tasks} tasks; driver CPU {100 * cpu1 / in1:.1f} % of the work)",
    )
    t2, rows2, _, in2, cpu2 = on_dask(sweep, 2)
    _line(
        "dask 2 wkr",
        t2,
        rows2,
        in2 / (2 * t2),
        f"  (driver CPU {100 * cpu2 / in2:.1f} % of the work)",
    )
    if loop:
        print(
            f"  Dask overhead vs loop, 1 worker: {100 * (t1 / t_loop - 1):+.1f} % wall "
            f"(measured under the load above); {1e3 * (t1 - in1) / tasks:.1f} ms per task "
            f"outside the tasks = {100 * (t1 - in1) / in1:.1f} % of the work "
            "(load-independent)"
        )
    print(
        f"  scaling efficiency 1 -> 2 workers: {100 * t1 / (2 * t2):.0f} % wall "
        f"(measured under the load above); busy fraction {100 * in2 / (2 * t2):.1f} % "
        f"with 2 workers vs {100 * in1 / t1:.1f} % with 1 (load-independent)",
        flush=True,
    )


TOLERANCE = os.path.join(os.path.dirname(__file__), "sweeps", "tolerance_open_chain.toml")
SCALING = os.path.join(os.path.dirname(__file__), "sweeps", "scaling_open_chain.toml")


def _peak_kb(pid: int | str = "self") -> int:
    """Peak resident memory (VmHWM) of process ``pid``, kB (Linux)."""
    with open(f"/proc/{pid}/status") as f:
        return int(next(line.split()[1] for line in f if line.startswith("VmHWM:")))


def load_file(path: str, points: int | None = None):
    """The sweep file ``path``, every axis drawn ``points`` times instead of its own count
    when ``points`` is given (a random axis's draws; for a zipped sweep the point count)."""
    from flexval.validation.sweep import load_sweep

    if points is None:
        return load_sweep(path)
    import tomllib
    from pathlib import Path

    with open(path, "rb") as f:
        data = tomllib.load(f)
    for axis in data["axes"]:
        axis["count"] = points
    return parse_sweep(data, path, folder=Path(path).parent)


def tolerance_once(path: str, workers: int, points: int | None = None) -> dict:
    """One run of the tolerance sweep ``path`` (``points`` draws, see :func:`load_file`) as
    ``flexval sweep --workers N --no-cache`` runs it (load, cluster start, run, read the
    rows back, write the summary, figures and tolerance study): wall seconds, points, the
    CPU seconds of this driver process (scheduler included) and of the workers, the largest
    peak RSS of them, and the largest task per model."""
    import psutil

    from flexval.validation.sweep import sweep_rows
    from flexval.validation.sweep.summary import write_outputs

    out = tempfile.mkdtemp(prefix="bench_sweep_tol_")
    try:
        wall, cpu = time.perf_counter(), time.process_time()
        split = {}
        sweep = load_file(path, points)
        split["load"] = time.perf_counter() - wall
        cluster = local_cluster(workers, sweep_models(sweep))
        try:
            with Client(cluster) as client:
                client.wait_for_workers(workers)
                split["cluster start"] = time.perf_counter() - wall - sum(split.values())
                in_run = time.process_time()
                stats = run_sweep(sweep, out, client, use_cache=False)
                in_run = time.process_time() - in_run
                split["run_sweep"] = time.perf_counter() - wall - sum(split.values())
                pids = [w.pid for w in cluster.workers.values()]
                work = sum(sum(psutil.Process(p).cpu_times()[:2]) for p in pids)
                peak = max(_peak_kb(p) for p in pids)
        finally:
            cluster.close()
        split["close"] = time.perf_counter() - wall - sum(split.values())
        rows = sweep_rows(sweep, out, stats)
        split["read rows"] = time.perf_counter() - wall - sum(split.values())
        write_outputs(sweep, rows, out, split["run_sweep"])
        split["outputs"] = time.perf_counter() - wall - sum(split.values())
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        assert len(rows) == stats.rows_written and stats.rows_failed == 0
        return {
            "wall": wall,
            "split": split,
            "points": len(sweep.points),
            "driver_cpu": cpu,
            "run_cpu": in_run,
            "worker_cpu": work,
            "peak_mb": max(peak, _peak_kb()) / 1024,
            "tasks": stats.tasks,
            "task_points": stats.task_points,
        }
    finally:
        shutil.rmtree(out)


def split_text(run: dict) -> str:
    """Where a :func:`tolerance_once` run's wall time went, one phase after the other."""
    return ", ".join(f"{phase} {seconds:.2f} s" for phase, seconds in run["split"].items())


def tolerance(path: str, workers: int, repeats: int, points: int | None = None) -> None:
    """Medians over ``repeats`` runs of :func:`tolerance_once`, one line each and the
    medians: points/s, and the driver's CPU time per point against a worker's."""
    import statistics

    runs = []
    for k in range(repeats):
        load = os.getloadavg()[0]
        r = tolerance_once(path, workers, points)
        runs.append(r)
        print(
            f"  run {k + 1}: {r['wall']:.1f} s wall (cluster start included), "
            f"{r['points'] / r['wall']:.0f} points/s, driver CPU "
            f"{1e3 * r['driver_cpu'] / r['points']:.3f} ms/point "
            f"({1e3 * r['run_cpu'] / r['points']:.3f} in run_sweep), worker CPU "
            f"{1e3 * r['worker_cpu'] / r['points']:.3f} ms/point, largest peak RSS "
            f"{r['peak_mb']:.0f} MB, {r['tasks']} tasks (largest {r['task_points']}) "
            f"(load average before {load:.1f})\n    wall: {split_text(r)}",
            flush=True,
        )

    def med(key):
        return statistics.median(r[key] for r in runs)

    n = runs[0]["points"]
    print(
        f"median of {repeats}: {med('wall'):.1f} s, {n / med('wall'):.0f} points/s with "
        f"{workers} workers; driver CPU {1e3 * med('driver_cpu') / n:.3f} ms/point = 1/"
        f"{med('worker_cpu') / med('driver_cpu'):.0f} of the workers' "
        f"{1e3 * med('worker_cpu') / n:.3f} ms/point (run_sweep alone: "
        f"{1e3 * med('run_cpu') / n:.3f} ms/point = 1/{med('worker_cpu') / med('run_cpu'):.0f}); "
        f"largest peak RSS {med('peak_mb'):.0f} MB",
        flush=True,
    )


def ceiling_child(path: str, points: int) -> None:
    """Print the seconds of :func:`plain_loop` on ``points`` points of ``path`` (after a
    20-point warm-up that loads the compiled kernels), for :func:`scaling`."""
    plain_loop(load_file(path, 20))
    sweep = load_file(path, points)
    print(plain_loop(sweep)[0], flush=True)


def ceiling(path: str, points: int, processes: int) -> float:
    """Mean seconds of ``processes`` independent plain loops run at once (no Dask, no
    driver), each on the same ``points`` points: what the machine gives ``processes``
    workers when nothing is shared between them."""
    import subprocess
    import sys

    argv = [sys.executable, __file__, "--ceiling-child", path, "--points", str(points)]
    runs = [subprocess.Popen(argv, stdout=subprocess.PIPE, text=True) for _ in range(processes)]
    seconds = [float(p.communicate(timeout=1800)[0].split()[-1]) for p in runs]
    assert all(p.returncode == 0 for p in runs)
    return sum(seconds) / len(seconds)


def scaling(path: str, workers: list[int], points: int | None, ceiling_points: int) -> None:
    """Strong scaling of the sweep ``path`` (``points`` draws) over ``workers``: one run of
    :func:`tolerance_once` per count, with the efficiency against the first count, T1 w1 /
    (w Tw), over the whole wall (load and cluster start included) and over ``run_sweep``
    alone; then the machine's own ceiling: ``w`` independent plain loops on
    ``ceiling_points`` points each, run at once, against one alone (T1 / Tw; 1 when
    processes do not slow each other down)."""
    base = None
    for w in workers:
        load = os.getloadavg()[0]
        r = tolerance_once(path, w, points)
        run = r["split"]["run_sweep"]
        base = base or (w * r["wall"], w * run)
        print(
            f"  {w:>3} workers: {r['wall']:7.1f} s wall ({r['points'] / r['wall']:,.0f} points/s), "
            f"efficiency {base[0] / (w * r['wall']):5.1%}; run_sweep {run:7.1f} s "
            f"({r['points'] / run:,.0f} points/s), efficiency {base[1] / (w * run):5.1%}; "
            f"driver CPU 1/{r['worker_cpu'] / r['driver_cpu']:.0f} of the workers'; "
            f"{r['tasks']} tasks; largest peak RSS {r['peak_mb']:.0f} MB "
            f"(load average before {load:.1f})\n        wall: {split_text(r)}",
            flush=True,
        )
    if ceiling_points:
        one = ceiling(path, ceiling_points, 1)
        for w in workers[1:]:
            t = ceiling(path, ceiling_points, w)
            print(
                f"  ceiling: {w:>3} independent processes of {ceiling_points} points, "
                f"{t:.2f} s each against {one:.2f} s alone (efficiency {one / t:.0%})",
                flush=True,
            )


CLUSTER_CHILD = r"""
import json, sys, time
from distributed import Client
from flexval.validation.sweep import engine
import flexval.validation.sweep.tasks  # as flexval sweep: the driver has imported them


def first(_):
    import flexval.validation.sweep.tasks  # noqa: F401  (a worker's first task's imports)

    return 1


if __name__ == "__main__":
    engine.START_METHOD, workers = sys.argv[1], int(sys.argv[2])
    t0 = time.perf_counter()
    cluster = engine.local_cluster(workers)
    client = Client(cluster)
    client.wait_for_workers(workers)
    t1 = time.perf_counter()
    client.gather(client.map(first, range(workers), pure=False))
    t2 = time.perf_counter()
    client.close()
    cluster.close()
    t3 = time.perf_counter()
    print(json.dumps({"start": t1 - t0, "first task": t2 - t1, "close": t3 - t2}))
"""


def cluster_start(workers: int, repeats: int) -> None:
    """Start, first task and close of :func:`local_cluster` with its start method and with
    ``spawn``, each in a fresh process (a forkserver lives as long as its process), the two
    alternating, ``repeats`` times: medians."""
    import json
    import statistics
    import subprocess
    import sys

    from flexval.validation.sweep.engine import START_METHOD

    methods = [START_METHOD, "spawn"]
    times: dict[str, list[dict]] = {m: [] for m in methods}
    with tempfile.TemporaryDirectory(prefix="bench_sweep_start_") as tmp:
        child = os.path.join(tmp, "child.py")
        with open(child, "w", encoding="utf-8") as f:
            f.write(CLUSTER_CHILD)
        for k in range(repeats):
            for m in methods if k % 2 == 0 else methods[::-1]:
                done = subprocess.run(
                    [sys.executable, child, m, str(workers)],
                    capture_output=True,
                    text=True,
                    check=True,
                    timeout=300,
                )
                times[m].append(json.loads(done.stdout.strip().splitlines()[-1]))
    for m in methods:
        med = {key: statistics.median(t[key] for t in times[m]) for key in times[m][0]}
        print(
            f"  {m:<10}: "
            + ", ".join(f"{key} {v:.2f} s" for key, v in med.items())
            + f"; total {sum(med.values()):.2f} s (median of {repeats}, {workers} workers, "
            f"load average {os.getloadavg()[0]:.1f})",
            flush=True,
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000, help="variants (default 1000)")
    ap.add_argument(
        "--continuum-n",
        type=int,
        default=10,
        help="variants with the continuum:0 reference (default 10; 0: skip)",
    )
    ap.add_argument(
        "--batch", type=int, default=None, help="points per reduced-model task (default: automatic)"
    )
    ap.add_argument("--cases", default="f+", help="load cases, comma-separated (default f+)")
    ap.add_argument("--no-loop", action="store_true", help="skip the plain loop")
    ap.add_argument(
        "--tolerance",
        nargs="?",
        const=TOLERANCE,
        default=None,
        help="run the tolerance sweep file (default benchmarks/sweeps/tolerance_open_chain.toml: "
        "20,000 points) instead, --workers workers, --repeats times",
    )
    ap.add_argument(
        "--cluster-start",
        action="store_true",
        help="time the local cluster's start, first task and close, against spawn's instead",
    )
    ap.add_argument(
        "--scaling",
        default=None,
        metavar="W1,W2,...",
        help="strong scaling of the sweep file of --tolerance (default "
        "benchmarks/sweeps/scaling_open_chain.toml) over these worker counts",
    )
    ap.add_argument(
        "--points",
        type=int,
        default=None,
        help="draws per axis of --tolerance and --scaling instead of the file's count",
    )
    ap.add_argument(
        "--ceiling-points",
        type=int,
        default=1000,
        help="points of each independent process of --scaling's ceiling (1000; 0: skip)",
    )
    ap.add_argument("--ceiling-child", default=None, help=argparse.SUPPRESS)
    ap.add_argument(
        "--workers", type=int, default=2, help="workers of --tolerance, --cluster-start (2)"
    )
    ap.add_argument(
        "--repeats", type=int, default=3, help="runs of --tolerance, --cluster-start (3)"
    )
    args = ap.parse_args()
    if args.ceiling_child:
        ceiling_child(args.ceiling_child, args.points)
        return
    if args.scaling:
        path = args.tolerance or SCALING
        print(f"{path}; {os.cpu_count()} cores", flush=True)
        counts = [int(w) for w in args.scaling.split(",")]
        scaling(path, counts, args.points, args.ceiling_points)
        return
    if args.cluster_start:
        print(f"local cluster start; {os.cpu_count()} cores", flush=True)
        cluster_start(args.workers, args.repeats)
        return
    if args.tolerance:
        print(f"{args.tolerance}; {os.cpu_count()} cores", flush=True)
        tolerance(args.tolerance, args.workers, args.repeats, args.points)
        return
    cases = args.cases.split(",")
    t0 = time.perf_counter()
    sweep = parse_sweep(variants(args.n, "beam:100", args.batch, cases), "<bench>")
    print(
        f"{args.n} points generated and checked in {time.perf_counter() - t0:.1f} s; "
        f"{os.cpu_count()} cores",
        flush=True,
    )
    report("reduced models vs beam:100", sweep, loop=not args.no_loop)
    if args.continuum_n:
        sub = parse_sweep(variants(args.continuum_n, "continuum:0", args.batch, cases), "<bench>")
        report("reduced models vs continuum:0", sub, loop=False)
    print(f"\nbenchmark total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
