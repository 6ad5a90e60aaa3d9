"""What each ``flexval`` command imports: heavy libraries only where they are used.

Every ``flexval`` call pays for the modules it imports before it does any
work (numpy about 60 ms, scipy's linear algebra 100 ms, scikit-fem 30 ms,
numba 150 ms, matplotlib, pyvista, Dask, pyarrow more). These tests run a
command in a fresh interpreter and check ``sys.modules`` afterwards, so a
module-level import that drags a heavy library into a command that does not
need it fails here instead of slowing every call unnoticed
(``benchmarks/bench_process.py`` measures the times themselves). The end of
the process (``flexval.validation.process.end_process``, no interpreter teardown) is
checked for what a normal exit guarantees: the status, complete output and
files, exit handlers run, C output flushed, running threads waited for.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

_PROBE = """
import contextlib, io, json, sys
from flexval.validation.cli import main
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    try:
        status = main(sys.argv[1:])
    except SystemExit as exc:
        status = exc.code
print(json.dumps({"status": status, "modules": sorted(sys.modules)}))
"""

PLOTTING = {"matplotlib", "pyvista", "vtk", "meshio"}
DISTRIBUTED = {"dask", "distributed", "pyarrow"}
COMPILED = {"numba", "llvmlite"}
MESHING = {"gmsh"}
CONTINUUM = {"skfem", "flexval.validation.continuum.solid"}
SOLVERS = {"scipy", "flexval.reducedmodels.core.system"}
RARE_SCIPY = {
    "scipy.interpolate",
    "scipy.optimize",
    "scipy.integrate",
    "scipy.spatial",
    "scipy.special",
    "scipy.stats",
}
"""scipy parts no ``run`` of a static load path uses."""


def _imports(argv: list[str], cache: Path) -> set[str]:
    """Top-level packages and listed modules a fresh ``flexval ARGV`` imported (exit code 0)."""
    env = {**os.environ, "FLEXVAL_CACHE": str(cache), "OPENBLAS_NUM_THREADS": "1"}
    proc = subprocess.run(
        [sys.executable, "-c", _PROBE, *argv],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["status"] in (0, None), (argv, proc.stderr)
    return set(out["modules"])


def _loaded(modules: set[str], names: set[str]) -> set[str]:
    return {n for n in names if n in modules}


@pytest.mark.parametrize("argv", [["--help"], ["run", "--help"], ["info", "closed_chain"]])
def test_commands_that_only_read_scenes_load_no_solver(argv, tmp_path):
    modules = _imports(argv, tmp_path)
    heavy = SOLVERS | CONTINUUM | COMPILED | MESHING | PLOTTING | DISTRIBUTED
    assert _loaded(modules, heavy) == set()


@pytest.mark.parametrize("model", ["dcmm:1", "ee", "prbm"])
def test_small_models_load_only_the_core_and_their_kernels(model, tmp_path):
    modules = _imports(["run", "closed_chain", "--model", model, "--load-case", "f+"], tmp_path)
    assert "flexval.reducedmodels.core.system" in modules  # the probe did run the model
    assert "numba" in modules  # the connectors' compiled kernels
    heavy = CONTINUUM | MESHING | PLOTTING | DISTRIBUTED | RARE_SCIPY
    assert _loaded(modules, heavy | {"scipy.sparse.linalg", "scipy.sparse.csgraph"}) == set()


def test_plugins_are_looked_up_only_for_unknown_model_ids(tmp_path):
    """Reading the installed packages' entry points (``importlib.metadata``) costs
    milliseconds: a command naming built-in models only never loads the plug-in loader."""
    assert "importlib.metadata" not in _imports(["info", "closed_chain"], tmp_path)
    argv = ["run", "closed_chain", "--model", "dcmm:1", "--load-case", "f+"]
    assert "flexval.reducedmodels.plugins" not in _imports(argv, tmp_path)
    assert "flexval.reducedmodels.plugins" in _imports(["models"], tmp_path)


def test_beam_loads_its_compiled_kernels_only(tmp_path):
    modules = _imports(["run", "closed_chain", "--model", "beam:5", "--load-case", "f+"], tmp_path)
    assert "numba" in modules
    assert _loaded(modules, CONTINUUM | MESHING | PLOTTING | DISTRIBUTED | RARE_SCIPY) == set()


def test_continuum_with_cached_meshes_loads_no_mesher(tmp_path):
    argv = ["run", "closed_chain", "--model", "continuum:0", "--load-case", "f+", "--levels", "2"]
    assert "gmsh" in _imports(argv, tmp_path)  # the first run meshes (and caches)
    modules = _imports(argv, tmp_path)
    assert "skfem" in modules
    assert _loaded(modules, COMPILED | MESHING | PLOTTING | DISTRIBUTED | RARE_SCIPY) == set()


# -- the end of a flexval process (flexval.validation.process.end_process) -------------------------


def _program(code: str, tmp_path: Path, *argv: str) -> subprocess.CompletedProcess:
    """Run ``code`` as a program whose command line is ``argv`` (output piped and buffered)."""
    env = {**os.environ, "FLEXVAL_CACHE": str(tmp_path / "cache"), "OPENBLAS_NUM_THREADS": "1"}
    env.pop("PYTHONUNBUFFERED", None)  # it would unbuffer C's stdout too
    return subprocess.run(
        [sys.executable, "-c", code, *argv], cwd=ROOT, env=env, capture_output=True, text=True
    )


def test_the_program_ends_with_its_status_output_and_files_complete(tmp_path):
    out = tmp_path / "paths.json"
    proc = _program(
        "from flexval.validation.cli import main; main()",
        tmp_path,
        "run",
        "closed_chain",
        "--model",
        "ee",
        "--model",
        "dcmm:1",
        "--json",
        str(out),
    )
    assert proc.returncode == 0, proc.stderr
    rows = [line.split()[0] for line in proc.stdout.splitlines()[1:] if line[:1] not in " "]
    assert rows == ["ee", "ee", "dcmm:1", "dcmm:1"]
    assert len(json.loads(out.read_text())["results"]) == 4
    bad = _program(
        "from flexval.validation.cli import main; main()",
        tmp_path,
        "run",
        "closed_chain",
        "--model",
        "nonsense",
    )
    assert bad.returncode == 2 and "'nonsense'" in bad.stderr and "Traceback" not in bad.stderr


def test_exit_handlers_run_and_c_output_is_flushed(tmp_path):
    """What a normal exit does that can be seen: atexit handlers, C stdio buffers written."""
    code = (
        "import atexit, ctypes; atexit.register(print, 'handler ran'); "
        "ctypes.CDLL(None).printf(b'from C\\n'); "
        "from flexval.validation.cli import main; main(); print('not reached')"
    )
    proc = _program(code, tmp_path, "info", "closed_chain")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "closed_chain" in lines[0] and "not reached" not in lines
    assert "handler ran" in lines and "from C" in lines


def test_main_returns_while_another_thread_runs(tmp_path):
    """A normal exit waits for running threads, so ``main`` leaves the exit to the program."""
    code = (
        "import threading; from flexval.validation.cli import main; done = threading.Event(); "
        "threading.Thread(target=done.wait).start(); "
        "status = main(); print('returned', status); done.set()"
    )
    proc = _program(code, tmp_path, "info", "closed_chain")
    assert proc.returncode == 0 and proc.stdout.rstrip().endswith("returned 0")


def test_a_profiled_run_keeps_its_profile(tmp_path):
    """``python -m cProfile -o FILE -m flexval.validation.cli ...`` writes FILE
    after the program."""
    env = {**os.environ, "FLEXVAL_CACHE": str(tmp_path / "cache")}
    stats = tmp_path / "cli.prof"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "cProfile",
            "-o",
            str(stats),
            "-m",
            "flexval.validation.cli",
            "info",
            "closed_chain",
        ],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    assert stats.stat().st_size > 0


def test_a_reader_that_leaves_early_costs_only_the_rest_of_the_output(tmp_path):
    """``flexval run ... | head -1``: no BrokenPipeError traceback, the files and status intact."""
    out = tmp_path / "paths.json"
    env = {
        **os.environ,
        "FLEXVAL_CACHE": str(tmp_path / "cache"),
        "OPENBLAS_NUM_THREADS": "1",
        "PYTHONUNBUFFERED": "1",
    }  # each row written when printed, as on a terminal
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "flexval.validation.cli",
            "run",
            "closed_chain",
            "--model",
            "ee",
            "--model",
            "dcmm:1",
            "--json",
            str(out),
        ],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout.readline().split()[0] == "model"
    proc.stdout.close()  # the reader leaves after the first line
    stderr = proc.stderr.read()
    assert proc.wait() == 0, stderr
    assert "Traceback" not in stderr and "BrokenPipe" not in stderr
    assert len(json.loads(out.read_text())["results"]) == 4
