"""A first run on a fresh machine: a whole ``flexval run`` with numba's cache empty, then full.

For each model, ``flexval run SCENE --model M --load-case CASE`` runs in a new process
with ``NUMBA_CACHE_DIR`` set to an empty folder (every kernel the run calls is
compiled and written there), then again with that folder filled (the kernels are
loaded). Reported: the whole process's wall seconds of each (median of
``--repeats``, each repeat with a folder of its own), the seconds the run printed
for its path (kernel compilation is left out of them), and the kernels the first
run compiled (numba's index files in the folder). ``run`` computes its path (no
result cache).

Run: ``python benchmarks/bench_cold_start.py [--models beam:100 prbm dcmm:1 ee]
[--scene open_chain] [--case f+] [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MODELS = ("beam:100", "prbm", "dcmm:1", "ee")


def run_once(scene: str, model: str, case: str, numba_cache: Path) -> tuple[float, str]:
    """Wall seconds of one whole ``flexval run`` process, and the seconds it printed."""
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(numba_cache),
        "FLEXVAL_CACHE": str(numba_cache / "flexval"),
        "OPENBLAS_NUM_THREADS": "1",
    }
    command = [sys.executable, "-m", "flexval.validation.cli", "run", scene]
    command += ["--model", model, "--load-case", case]
    t0 = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t0
    rows = [line.split() for line in done.stdout.splitlines() if line.startswith(model + " ")]
    printed = rows[-1][-2] if rows else "-"
    return wall, printed


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", nargs="+", default=list(MODELS))
    ap.add_argument("--scene", default="open_chain")
    ap.add_argument("--case", default="f+")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    print(
        f"{args.scene} {args.case}; whole process, median of {args.repeats}; "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    print(f"{'model':10s} {'cold s':>8s} {'warm s':>8s} {'printed':>9s}  kernels compiled")
    for model in args.models:
        cold, warm, printed, compiled = [], [], "", []
        for _ in range(args.repeats):
            with tempfile.TemporaryDirectory() as folder:
                cache = Path(folder)
                wall, _ = run_once(args.scene, model, args.case, cache)
                cold.append(wall)
                wall, printed = run_once(args.scene, model, args.case, cache)
                warm.append(wall)
                compiled = sorted(p.name.split("-")[0] for p in cache.rglob("*.nbi"))
        names = ", ".join(compiled)
        print(
            f"{model:10s} {statistics.median(cold):8.2f} {statistics.median(warm):8.2f} "
            f"{printed:>9s}  {len(compiled)}: {names}",
            flush=True,
        )


if __name__ == "__main__":
    main()
