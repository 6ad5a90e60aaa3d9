"""Kernels are compiled where they are first called, and path times leave that out.

A run compiles (or loads from numba's on-disk cache) only the kernels it calls: a
first ``dcmm:1`` run on an empty cache writes no band, beam, chain or batch kernel
into it. The clock paths are timed on (:mod:`flexval.reducedmodels.kernels.clock`)
stands still while numba compiles: checked against the wall clock around a
compilation, independently of flexval's kernels.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numba
import numpy as np
import pytest

from flexval.reducedmodels.kernels import clock

ROOT = Path(__file__).resolve().parents[1]


def _fresh_function():
    """A function numba has never seen (compiled without the disk cache)."""

    def summed(values):
        total = 0.0
        for k in range(values.size):
            total += values[k] * values[k]
        return total

    return numba.njit(summed)


def test_the_path_clock_stands_still_while_numba_compiles():
    from flexval.reducedmodels.kernels.jit import initialise

    initialise()  # numba's own set-up done (the count starts with the import)
    compiled = _fresh_function()
    wall0, path0, held0 = time.perf_counter(), clock.path_clock(), clock.kernel_seconds()
    assert compiled(np.arange(4.0)) == 14.0
    wall = time.perf_counter() - wall0
    held = clock.kernel_seconds() - held0
    path = clock.path_clock() - path0
    assert wall > 0.01  # a compilation took place
    assert 0.0 <= path and held <= wall
    assert path < 0.25 * wall  # the compilation is almost all of the call (~5 % is not)
    # a call of machine code already there leaves the count as it is
    held1 = clock.kernel_seconds()
    compiled(np.arange(4.0))
    assert clock.kernel_seconds() == held1


def test_the_count_is_per_thread():
    import threading

    import flexval.reducedmodels.kernels.jit  # noqa: F401

    seen = {}

    def compile_elsewhere():
        before = clock.kernel_seconds()
        _fresh_function()(np.ones(3))
        seen["other"] = clock.kernel_seconds() - before

    here = clock.kernel_seconds()
    worker = threading.Thread(target=compile_elsewhere)
    worker.start()
    worker.join()
    assert seen["other"] > 0.0
    assert clock.kernel_seconds() == here


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="no thread signal masks")
def test_signals_wait_while_numba_compiles():
    """SIGINT and SIGTERM are blocked in a thread while it compiles (the process gets them
    elsewhere, or after), and unblocked again after."""
    from numba.core import event

    import flexval.reducedmodels.kernels.jit  # noqa: F401  (registers the count first)

    def blocked() -> set:
        return signal.pthread_sigmask(signal.SIG_BLOCK, [])

    seen = []

    class Probe(event.Listener):
        def on_start(self, ev):
            seen.append({signal.SIGINT, signal.SIGTERM} <= blocked())

        def on_end(self, ev):
            pass

    before = blocked()
    probe = Probe()
    event.register("numba:compiler_lock", probe)
    try:
        _fresh_function()(np.ones(2))
    finally:
        event.unregister("numba:compiler_lock", probe)
    assert seen and all(seen)
    assert blocked() == before


def test_a_first_run_compiles_only_the_kernels_it_calls(tmp_path):
    """dcmm:1 on the closed chain (9 unknowns: a dense tangent, no chain of cut bodies): its
    DCMM kernels are compiled into the empty cache, and nothing of the beams, the chains, the
    narrow band or a batch's blocks and stresses."""
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
        "FLEXVAL_CACHE": str(tmp_path / "results"),
        "OPENBLAS_NUM_THREADS": "1",
    }
    done = subprocess.run(
        [sys.executable, "-m", "flexval.validation.cli", "run", "closed_chain"]
        + ["--model", "dcmm:1", "--load-case", "f+"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    written = {p.name.split("-")[0] for p in (tmp_path / "numba").rglob("*.nbi")}
    modules = {name.split(".")[0] for name in written}
    assert "dcmmkernel" in modules
    assert not modules & {"beamkernel", "chainkernel", "bandkernel", "stresskernel"}
    assert not {"ldlkernel.block_factor", "ldlkernel.block_solve"} & written
