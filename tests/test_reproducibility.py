"""Results are bit-reproducible: in one process and from process to process, static and
dynamic, with one Dask worker or several, from the cache or recomputed.

``benchmarks/paper_protocol.py`` sets its ramp times in periods of the reference's
first natural mode; the reference (beam:100) has more coordinates than
:data:`flexval.reducedmodels.analyses.modes.DENSE_MODES_LIMIT`, so its modes come from ARPACK, whose
default starting vector is drawn from the operating system's entropy: the frequencies
would differ in the 9th digit between processes, and the adaptive time stepping carries
such a difference into end-of-ramp errors that move by up to 0.8 percentage points, so
the start vector is seeded (:data:`flexval.reducedmodels.analyses.modes.LANCZOS_START_SEED`).
The first test repeats that chain (sparse modes, a ramp in periods of them, an adaptive
run) in one process and in two. The others run the command line in separate processes,
each with its own cache, and compare every number exactly (floats by their hex form; wall
times left out): the protocol's damped beam:20 path, static paths of every kind of model,
a sweep on one and on two workers, and a report with and without the cache.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

RUN = """
import hashlib, json
import numpy as np
from flexval.geometry.timelaw import TimeLaw
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.analyses.dynamics import DynamicSettings, Rayleigh, solve_dynamic
from flexval.reducedmodels.models import build_system
from flexval.reducedmodels.analyses.modes import DENSE_MODES_LIMIT, natural_modes
from tests.builders import tip_moment
from tests.test_modes import RHO, straight

system = build_system(straight(density=RHO), parse_model("beam:201"))
f = natural_modes(system, count=2).frequencies_hz
ramp = 2.0 / f[0]
histories = []
for _ in range(2):
    lp = solve_dynamic(system, tip_moment(1e-3), TimeLaw("eq15", 0.0, ramp), ramp,
                       Rayleigh.from_ratio(0.05, f[0], f[1]),
                       DynamicSettings(first_step=0.01, max_step=0.05))
    history = np.array([lp.time, lp.dx, lp.dy, lp.rotation])
    histories.append(hashlib.sha256(history.tobytes()).hexdigest())
print(json.dumps({"sparse": system.n_dofs > DENSE_MODES_LIMIT,
                  "frequencies": [x.hex() for x in f], "histories": histories,
                  "steps": lp.stats["steps"], "rejected": lp.stats["rejected_steps"]}))
"""
"""A cantilever beam:201 (603 coordinates: sparse modes), 1e-3 N mm at its tip ramped over
two first periods with 5 % damping: about 30 adaptive steps, a few rejected (the step
size decisions that amplify a difference in the last digits are exercised)."""


def _run_twice_in_two_processes() -> list[dict]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", RUN],
            env=env,
            cwd=ROOT,
            text=True,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        for _ in range(2)
    ]
    outs = []
    for p in procs:
        out, err = p.communicate()
        assert p.returncode == 0, err
        outs.append(json.loads(out))
    return outs


def test_dynamic_run_is_bit_identical_in_one_process_and_across_processes():
    first, second = _run_twice_in_two_processes()
    assert first["sparse"]  # the ARPACK path is the one exercised
    assert first["rejected"] > 0  # and step rejections happen
    assert first["frequencies"] == second["frequencies"]
    assert first["histories"][0] == first["histories"][1]  # same process
    assert first["histories"] == second["histories"]  # another process


CLI = [sys.executable, "-m", "flexval.validation.cli"]
THREAD_VARIABLES = ("FLEXVAL_BLAS_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")


def _env(cache: Path, **extra: str) -> dict[str, str]:
    """This process's environment with its own result/mesh cache, no thread settings
    inherited (flexval's default BLAS cap applies), and ``extra`` on top."""
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    return {**env, "PYTHONPATH": str(ROOT), "FLEXVAL_CACHE": str(cache), **extra}


def _flexval(jobs: list[tuple[list[str], dict[str, str]]], cwd: Path) -> None:
    """Run ``flexval ARGS`` once per (args, environment), all at the same time."""
    procs = [
        subprocess.Popen(
            [*CLI, *args],
            env=env,
            cwd=cwd,
            text=True,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        for args, env in jobs
    ]
    for args, p in zip([a for a, _ in jobs], procs, strict=True):
        _, err = p.communicate()
        assert p.returncode == 0, (args, err)


def numbers(value: object) -> object:
    """``value`` (parsed JSON or a row) with every float as its exact hex form and the
    wall times (``seconds``) left out: what must agree bit for bit between runs."""
    if isinstance(value, dict):
        return {k: numbers(v) for k, v in value.items() if k != "seconds"}
    if isinstance(value, list):
        return [numbers(v) for v in value]
    if isinstance(value, float):
        return value.hex()
    return value


def _dense_open_chain(folder: Path) -> Path:
    """The open chain with PLA flexures (the dynamic protocol's masses) as a scene file."""
    from flexval.geometry.inertia import PLA_DENSITY

    text = (ROOT / "geometry" / "scenes" / "open_chain.toml").read_text(encoding="utf-8")
    dense = text.replace("[material]\n", f"[material]\ndensity = {PLA_DENSITY!r}\n", 1)
    assert dense != text
    path = folder / "open_chain_pla.toml"
    path.write_text(dense, encoding="utf-8")
    return path


def test_damped_dynamic_beam20_path_is_bit_identical_in_three_processes(tmp_path):
    """The dynamic protocol's beam:20 on the open chain's f- case (PLA flexures, damping
    ratio 0.2 at its two lowest frequencies, the protocol's error bound 1e-8: about 1100
    adaptive steps, a fifth of them rejected), three processes at once, each with its own
    cache and another OPENBLAS_NUM_THREADS (the default cap applies): every number of the
    three histories agrees bit for bit."""
    scene = _dense_open_chain(tmp_path)
    args = [
        "run",
        str(scene),
        "--dynamic",
        "--model",
        "beam:20",
        "--load-case",
        "f-",
        "--damping-ratio",
        "0.2",
        "--duration",
        "0.2",
        "--error-tol",
        "1e-8",
    ]
    blas = ({}, {"OPENBLAS_NUM_THREADS": "1"}, {"OPENBLAS_NUM_THREADS": "2"})
    jobs = [
        ([*args, "--json", str(tmp_path / f"run{k}.json")], _env(tmp_path / f"cache{k}", **extra))
        for k, extra in enumerate(blas)
    ]
    _flexval(jobs, tmp_path)
    runs = [json.loads((tmp_path / f"run{k}.json").read_text()) for k in range(len(jobs))]
    (result,) = runs[0]["results"]
    assert result["settings"]["rayleigh_alpha"] > 0 and result["settings"]["rayleigh_beta"] > 0
    assert len(result["time"]) > 500 and result["stats"]["rejected_steps"] > 50
    assert numbers(runs[1]) == numbers(runs[0])
    assert numbers(runs[2]) == numbers(runs[0])


def test_static_paths_are_bit_identical_across_processes_and_mesh_caches(tmp_path):
    """beam:100, dcmm:2, prbm and the continuum (level 1) on f-: a first run meshes the
    flexures into its cache; then one run reads those meshes from it (other
    OPENBLAS_NUM_THREADS) while another meshes them anew in its own cache (with
    OMP_NUM_THREADS=2 for any OpenMP library loaded). The three JSON documents agree bit
    for bit."""
    args = ["run", "open_chain", "--load-case", "f-"]
    for m in ("beam:100", "dcmm:2", "prbm", "continuum:1"):
        args += ["--model", m]
    warm, fresh = tmp_path / "cache", tmp_path / "fresh"
    _flexval([([*args, "--json", str(tmp_path / "first.json")], _env(warm))], tmp_path)
    assert list((warm / "meshes").iterdir())  # the second run reads meshes from here
    _flexval(
        [
            ([*args, "--json", str(tmp_path / "warm.json")], _env(warm, OPENBLAS_NUM_THREADS="2")),
            ([*args, "--json", str(tmp_path / "fresh.json")], _env(fresh, OMP_NUM_THREADS="2")),
        ],
        tmp_path,
    )
    first, *others = (
        numbers(json.loads((tmp_path / f"{name}.json").read_text()))
        for name in ("first", "warm", "fresh")
    )
    assert len(first["results"]) == 4
    assert all(other == first for other in others)


SWEEP = """
name = "repro"
base = "open_chain"
models = ["beam:20", "dcmm:1"]
reference = "prbm"
load_cases = ["f+"]

[[axes]]
path = "section.thickness"
values = [0.09, 0.1, 0.11, 0.12]

[[axes]]
path = "material.youngs_modulus"
values = [2000.0, 2200.0]
"""
"""Eight points, two models and a reference on one load case: 24 rows. No ``batch``: the
automatic one puts two points in a task on one worker and one on two workers
(:func:`flexval.validation.sweep.engine.auto_batch`), so the tasks differ as well."""


def test_a_sweep_gives_identical_rows_with_one_and_two_workers(tmp_path):
    import pyarrow.parquet as pq

    from flexval.validation.sweep.engine import auto_batch

    assert auto_batch(8, 1) != auto_batch(8, 2)  # the points are grouped differently
    sweep = tmp_path / "repro.toml"
    sweep.write_text(SWEEP, encoding="utf-8")
    jobs = [
        (
            ["sweep", str(sweep), "--out", str(tmp_path / f"w{n}"), "--workers", str(n)]
            + ["--no-cache", "--quiet"],
            _env(tmp_path / f"cache{n}"),
        )
        for n in (1, 2)
    ]
    _flexval(jobs, tmp_path)
    tables = []
    for n in (1, 2):
        rows = pq.read_table(tmp_path / f"w{n}" / "results").to_pylist()
        tables.append(sorted((numbers(r) for r in rows), key=lambda r: r["key"]))
    assert len(tables[0]) == 24 and all(r["status"] == "ok" for r in tables[0])
    assert tables[1] == tables[0]


def test_a_report_gives_identical_results_and_gates_with_and_without_the_cache(tmp_path):
    """Two reports of the open chain (beam:100 as reference, beam:20 and dcmm:1): the
    first on two processes filling the cache, the second on one recomputing everything.
    results.json and gates.json are the same bytes."""
    args = ["report", "open_chain", "--no-bench", "--no-converge", "--quiet"]
    for m in ("beam:100", "beam:20", "dcmm:1"):
        args += ["--model", m]
    cache = tmp_path / "cache"
    _flexval([([*args, "--out", str(tmp_path / "a"), "--jobs", "2"], _env(cache))], tmp_path)
    _flexval(
        [([*args, "--out", str(tmp_path / "b"), "--jobs", "1", "--no-cache"], _env(cache))],
        tmp_path,
    )
    gates = json.loads((tmp_path / "a" / "gates.json").read_text())
    assert gates["open_chain"]["beam:100"]["dcmm:1"]  # the comparisons are there
    for name in ("results.json", "gates.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
