"""Throughput of `flexval sweep` on Dask: 1 vs 2 workers, and Dask's overhead vs a plain loop.

Run: ``python benchmarks/bench_sweep.py [--n 1000] [--continuum-n 10] [--batch 10]``.

The sweep: ``--n`` random variants of the open chain (flexure thickness h
uniform in 0.08..0.12 mm, Young's modulus lognormal about 2100 MPa with
sigma 0.05, the force of f+ uniform in 2..4 mN), zipped, load cases m+ and
f+, the reduced models ee, dcmm:1, dcmm:2, prbm, beam:20 against beam:100.
The same rows are computed three ways, each timed from submission to the
last Parquet part written (point generation and cluster start-up excluded):

- a plain loop in this process (the task functions called one after the other);
- :func:`validation.sweep.run_sweep` on a LocalCluster of 1 worker process;
- the same on 2 worker processes.

Printed: runs (load paths) per second of each, Dask's overhead against the
loop (1 worker; target < 20 %), the scaling efficiency from 1 to 2
workers, T1 / (2 T2) (target >= 80 %), and the same on ``--continuum-n``
points with continuum:0 as the reference. The load average is printed too:
on a machine shared with other jobs, 2 workers cannot get 2 cores. So each
configuration also prints its *busy fraction*: the seconds spent inside the
models' runs (summed over the rows) over wall time x workers. Contention
slows both alike, so the busy fractions show what Dask itself costs (idle
workers, scheduling, result transfer, Parquet writes) even on a loaded
machine.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time

from distributed import Client

from validation.cache import code_version
from validation.sweep import local_cluster, parse_sweep, results_store, run_sweep
from validation.sweep.engine import chunks
from validation.sweep.tasks import TaskInfo, run_model_batch, run_reference

MODELS = ["ee", "dcmm:1", "dcmm:2", "prbm", "beam:20"]


def variants(n: int, reference: str, batch: int) -> dict:
    """Sweep data of ``n`` random open-chain variants (zipped axes, seeds fixed)."""
    return {"name": f"bench_{n}", "base": "open_chain", "models": MODELS,
            "reference": reference, "load_cases": ["m+", "f+"], "combine": "zip",
            "batch": batch,
            "axes": [{"path": "section.thickness", "sample": "uniform", "low": 0.08,
                      "high": 0.12, "count": n, "seed": 1},
                     {"path": "material.youngs_modulus", "sample": "lognormal",
                      "median": 2100.0, "sigma": 0.05, "count": n, "seed": 2},
                     {"path": "load_cases.f+.value", "sample": "uniform", "low": 2e-3,
                      "high": 4e-3, "count": n, "seed": 3}]}


def _busy(rows: list[dict]) -> float:
    """Seconds spent inside the models' runs (the useful work of the rows)."""
    return sum(r["seconds"] for r in rows if r["seconds"] is not None)


def plain_loop(sweep) -> tuple[float, int, float]:
    """Wall seconds, rows and model seconds of the same tasks called one after the other."""
    info = TaskInfo(sweep.name, sweep.reference.id, code_version())
    t0 = time.perf_counter()
    ref = run_reference(list(sweep.valid_points), sweep.reference, sweep.load_cases, info,
                        use_cache=False)
    rows = list(ref["rows"])
    for spec in sweep.models:
        for chunk in chunks(list(sweep.valid_points), sweep.batch):
            rows += run_model_batch(chunk, spec, sweep.load_cases, info, [ref])
    return time.perf_counter() - t0, len(rows), _busy(rows)


def on_dask(sweep, workers: int) -> tuple[float, int, int, float]:
    """Wall seconds, rows, tasks and model seconds of run_sweep on a fresh LocalCluster."""
    out = tempfile.mkdtemp(prefix="bench_sweep_")
    try:
        with local_cluster(workers) as cluster, Client(cluster) as client:
            client.wait_for_workers(workers)
            stats = run_sweep(sweep, out, client, use_cache=False)
        rows = results_store(sweep, out).rows()
        return stats.seconds, stats.rows_written, stats.tasks, _busy(rows)
    finally:
        shutil.rmtree(out)


def report(label: str, sweep, loop: bool) -> None:
    """Time the sweep the three ways (two without the loop) and print the ratios."""
    print(f"\n{label}: {len(sweep.valid_points)} points x ({len(sweep.models)} models + "
          f"{sweep.reference.id}) x {len(sweep.load_cases)} cases; batch {sweep.batch}; "
          f"load average {os.getloadavg()[0]:.2f}")
    if loop:
        t_loop, rows, busy = plain_loop(sweep)
        print(f"  plain loop : {t_loop:8.2f} s  {rows / t_loop:8.1f} runs/s  "
              f"busy {100 * busy / t_loop:5.1f} %")
    t1, rows1, tasks, busy1 = on_dask(sweep, 1)
    print(f"  dask 1 wkr : {t1:8.2f} s  {rows1 / t1:8.1f} runs/s  busy {100 * busy1 / t1:5.1f} %"
          f"  ({tasks} tasks)")
    t2, rows2, _, busy2 = on_dask(sweep, 2)
    print(f"  dask 2 wkr : {t2:8.2f} s  {rows2 / t2:8.1f} runs/s  "
          f"busy {100 * busy2 / (2 * t2):5.1f} %")
    if loop:
        print(f"  Dask overhead vs loop (1 worker): {100 * (t1 / t_loop - 1):+.1f} % wall, "
              f"{100 * (busy / t_loop - busy1 / t1):+.1f} points of busy fraction  "
              f"({1e3 * (t1 - t_loop) / tasks:+.1f} ms per task)")
    print(f"  scaling efficiency 1 -> 2 workers: {100 * t1 / (2 * t2):.0f} % wall, "
          f"{100 * (busy2 / (2 * t2)) / (busy1 / t1):.0f} % of 1 worker's busy fraction")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000, help="variants (default 1000)")
    ap.add_argument("--continuum-n", type=int, default=10,
                    help="variants with the continuum:0 reference (default 10; 0: skip)")
    ap.add_argument("--batch", type=int, default=10, help="points per reduced-model task")
    args = ap.parse_args()
    t0 = time.perf_counter()
    sweep = parse_sweep(variants(args.n, "beam:100", args.batch), "<bench>")
    print(f"{args.n} points generated and checked in {time.perf_counter() - t0:.1f} s; "
          f"{os.cpu_count()} cores")
    report("reduced models vs beam:100", sweep, loop=True)
    if args.continuum_n:
        sub = parse_sweep(variants(args.continuum_n, "continuum:0", args.batch), "<bench>")
        report("reduced models vs continuum:0", sub, loop=False)


if __name__ == "__main__":
    main()
