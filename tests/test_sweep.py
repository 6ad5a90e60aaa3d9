"""`flexval sweep`: sweep files, the Dask engine, the Parquet store, resume and failures."""

import dataclasses
import math
import re
import textwrap
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from builders import in_process_client

from flexval.reducedmodels import parse_model
from flexval.validation.cli import main
from flexval.validation.run import run_model
from flexval.validation.studies.compare import errors
from flexval.validation.sweep import load_sweep, results_store, run_sweep, sweep_rows, write_outputs
from flexval.validation.sweep import tasks as sweep_tasks
from flexval.validation.sweep.builtin import BUILTIN_SWEEPS
from flexval.validation.sweep.engine import MAX_AUTO_BATCH, TASKS_PER_WORKER, auto_batch

SCENES = Path(__file__).parent / "scenes"
DA_DEPPO_SCHMIDT = 8.97
"""P R^2 / EI at the limit point of the 215 deg clamped-hinged arch (Da Deppo and Schmidt 1975)."""

TINY = """
name = "tiny"
base = "open_chain"
models = ["ee", "dcmm:1"]
reference = "prbm"
load_cases = ["m+", "f+"]
batch = 2

[[axes]]
path = "section.thickness"
values = [0.09, 0.11]

[[axes]]
path = "material.youngs_modulus"
values = [2000.0, 2200.0]
"""


def _write(tmp_path, text, name="sw.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def client():
    with in_process_client() as c:
        yield c


def test_points_edit_the_base_scene_through_the_loader(tmp_path):
    sweep = load_sweep(_write(tmp_path, TINY))
    assert len(sweep.points) == 4 and len(sweep.valid_points) == 4
    p = sweep.points[3]
    assert p.params == {"section.thickness": 0.11, "material.youngs_modulus": 2200.0}
    assert all(f.section.thickness == 0.11 for f in p.scene.mechanism.flexures)
    assert p.scene.mechanism.material.youngs_modulus == 2200.0
    assert len({q.digest for q in sweep.points}) == 4


def test_tiny_sweep_matches_a_plain_loop_and_resumes(tmp_path, client):
    sweep = load_sweep(_write(tmp_path, TINY))
    out = tmp_path / "out"
    stats = run_sweep(sweep, out, client, use_cache=False)
    # 2 batches of 2 points for the reference and for each of the 2 models
    assert stats.tasks == 6 and stats.rows_written == 4 * 3 * 2 and stats.rows_failed == 0
    rows = results_store(sweep, out).rows()
    assert {r["status"] for r in rows} == {"ok"}
    # independent check: the errors of a plain in-process loop on the same scenes
    p = sweep.points[2]
    for model in ("ee", "dcmm:1"):
        for case in ("m+", "f+"):
            lc = p.scene.load_case(case)
            want = errors(
                run_model(p.scene, parse_model(model), lc),
                run_model(p.scene, parse_model("prbm"), lc),
                p.scene.mechanism.size(),
            )
            got = next(
                r
                for r in rows
                if r["point"] == 2 and r["model"] == model and r["load_case"] == case
            )
            assert got["param:section.thickness"] == 0.11
            for metric, value in want.items():
                assert got[metric] == pytest.approx(value, rel=1e-9)
    # an interruption loses whole parts only: drop one, and a rerun does only that task
    # (plus the reference task of those points when the lost part is a model's)
    lost = stats.parts[-1]
    lost_rows = pq.read_table(lost).to_pylist()
    lost.unlink()
    lines = []
    again = run_sweep(sweep, out, client, use_cache=False, progress=lines.append)
    n_lost = len(lost_rows)
    # every (point, model) is counted once, as stored or as run, whatever reruns
    done, total = re.search(r"([\d,]+)/([\d,]+) runs", lines[-1]).groups()
    assert done == total == "12", lines
    assert n_lost == 2 * 2 and again.rows_written == n_lost
    assert again.tasks == (1 if lost_rows[0]["model"] == "prbm" else 2)
    assert again.rows_skipped == len(rows) - n_lost

    def results(rs):  # everything but the run times
        return [{k: v for k, v in r.items() if k != "seconds"} for r in rs]

    assert results(results_store(sweep, out).rows()) == results(rows)
    assert run_sweep(sweep, out, client).tasks == 0
    files = write_outputs(sweep, rows, out)
    assert all(f.stat().st_size > 0 for f in files)
    text = (out / "summary.md").read_text()
    assert "| ee | 4/4 |" in text and "None: every run reached full load." in text


class _Interrupt(Exception):
    """Stands for Ctrl-C in the middle of a sweep."""


def test_an_interrupted_sweep_resumes_with_the_missing_rows_only(tmp_path, client):
    sweep = load_sweep(_write(tmp_path, TINY))
    out = tmp_path / "out"
    finished = []

    def stop_after_three(line):
        finished.append(line)
        if len(finished) == 3:
            raise _Interrupt

    with pytest.raises(_Interrupt):
        run_sweep(sweep, out, client, use_cache=False, progress=stop_after_three)
    kept = results_store(sweep, out).rows()
    # three tasks finished, each wrote its part before the progress line
    assert len(results_store(sweep, out).parts()) == 3 and 0 < len(kept) < 4 * 3 * 2
    again = run_sweep(sweep, out, client, use_cache=False)
    assert again.rows_written == 4 * 3 * 2 - len(kept) and again.rows_skipped == len(kept)
    rows = results_store(sweep, out).rows()
    assert len({r["key"] for r in rows}) == len(rows) == 4 * 3 * 2
    assert {r["status"] for r in rows} == {"ok"}


def test_a_failing_task_and_a_failing_model_are_recorded(tmp_path, client, monkeypatch):
    real = sweep_tasks.run_batch

    def crash_on_dcmm(mechanisms, spec, cases, *a, **k):
        if spec.family == "dcmm" and cases[0].name == "f+":
            raise KeyError("injected worker crash")
        return real(mechanisms, spec, cases, *a, **k)

    monkeypatch.setattr(sweep_tasks, "run_batch", crash_on_dcmm)
    text = TINY.replace('reference = "prbm"', 'reference = "beam:20"').replace(
        '"dcmm:1"]', '"dcmm:1", "prbm"]'
    )
    text = text.replace("values = [0.09, 0.11]", "values = [0.11]").replace(
        "values = [2000.0, 2200.0]", "values = [2100.0]"
    )
    text = text.replace('load_cases = ["m+", "f+"]', 'load_cases = ["f+"]')
    sweep = load_sweep(_write(tmp_path, text))
    stats = run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    rows = {r["model"]: r for r in results_store(sweep, tmp_path / "o").rows()}
    assert stats.rows_failed == 1 and rows["dcmm:1"]["status"] == "error"
    assert "KeyError" in rows["dcmm:1"]["reason"] and rows["dcmm:1"]["end_rot"] is None
    assert rows["ee"]["status"] == "ok" and rows["prbm"]["status"] == "ok"


def test_solver_failure_records_the_load_reached(tmp_path, client):
    # m+ of the open chain x1000: beam:20's load stepping gives up at 35 % of the load
    text = (
        TINY.replace('load_cases = ["m+", "f+"]', 'load_cases = ["m+"]')
        .replace('reference = "prbm"', 'reference = "ee"')
        .replace('["ee", "dcmm:1"]', '["beam:20"]')
    )
    text = text.split("[[axes]]")[0] + textwrap.dedent("""
        [[axes]]
        path = "load_cases.m+.value"
        values = [5.0]
        """)
    sweep = load_sweep(_write(tmp_path, text))
    run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    row = next(r for r in results_store(sweep, tmp_path / "o").rows() if r["model"] == "beam:20")
    assert row["status"] == "solver_failure"
    assert 0.3 < row["load_reached"] < 0.4
    assert f"{100 * row['load_reached']:.2f} % of full load" in row["reason"]
    assert row["end_rot"] is None
    # the peak stress is given at the path's last level, at or below the load reached: a pure
    # end moment bends every section alike, 6 M / (b h^2) with M that level's moment
    # (closed form; spread ~1e-13 measured)
    scene = sweep.points[0].scene
    section = scene.mechanism.flexures[0].section
    assert 0.0 < row["peak_stress_load"] <= row["load_reached"]
    m = row["peak_stress_load"] * scene.load_case("m+").magnitude
    assert row["peak_stress"] == pytest.approx(
        6.0 * m / (section.depth * section.thickness**2), rel=1e-9
    )
    assert row["peak_stress_error"] is None  # errors compare full loads only
    write_outputs(sweep, sweep_rows(sweep, tmp_path / "o"), tmp_path / "o")
    summary = (tmp_path / "o" / "summary.md").read_text()
    assert (
        f"(load reached {row['load_reached']:.3g}; peak stress {row['peak_stress']:.4g} "
        f"MPa at load {row['peak_stress_load']:.3g})"
    ) in summary


def test_a_reference_rotation_near_zero_is_measured_against_its_scale(tmp_path, client):
    """The shallow arch pressed on its axis turns its crown by round-off in every model: the
    sweep's rotation errors are those of flexval.validation.studies.compare.errors with the
    mechanism's
    size (about zero, against the rotation scale), not round-off over round-off."""
    from test_compare_scale import _arch

    scene, case, _ = _arch(tmp_path, -90.0, 0.1)
    text = f"""
    base = "{tmp_path / "arch.toml"}"
    models = ["dcmm:1"]
    reference = "beam:20"

    [[axes]]
    path = "section.thickness"
    values = [0.28, 0.3]
    """
    sweep = load_sweep(_write(tmp_path, text))
    run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    rows = [r for r in sweep_rows(sweep, tmp_path / "o") if r["model"] == "dcmm:1"]
    assert len(rows) == 2 and {r["status"] for r in rows} == {"ok"}
    for r in rows:
        p = sweep.points[r["point"]]
        lp = run_model(p.scene, parse_model("dcmm:1"), p.scene.load_case("down"))
        ref = run_model(p.scene, parse_model("beam:20"), p.scene.load_case("down"))
        assert abs(lp.rotation[-1] - ref.rotation[-1]) > 0.01 * abs(ref.rotation[-1])
        want = errors(lp, ref, p.scene.mechanism.size())
        assert r["end_rot"] < 1e-9 and r["path_rot"] < 1e-9
        # the sweep traces its points as batches, each path its solo run's to 1e-12 of the
        # motion: a metric (percent) that is round-off itself agrees to 1e-10 only
        for metric, value in want.items():
            assert r[metric] == pytest.approx(value, rel=1e-9, abs=1e-10)


def test_generated_invalid_points_are_reported_not_fatal(tmp_path, client):
    # h drawn up to 8 mm: above 2 r = 5 mm (e34) the loader refuses the arc, and thick
    # arcs close on themselves or overlap their neighbours well before
    text = TINY.split("[[axes]]")[0] + textwrap.dedent("""
        [[axes]]
        path = "section.thickness"
        sample = "uniform"
        low = 0.05
        high = 8.0
        count = 6
        seed = 3
        """)
    sweep = load_sweep(_write(tmp_path, text))
    bad = [p for p in sweep.points if p.scene is None]
    assert bad and len(bad) < len(sweep.points)
    assert all(p in bad for p in sweep.points if p.params["section.thickness"] >= 5.0)
    assert all(p.reason.startswith("flexures.") for p in bad)
    sweep = dataclasses.replace(sweep, models=sweep.models[:1])
    run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    rows = results_store(sweep, tmp_path / "o").rows()
    assert sum(r["status"] == "invalid_point" for r in rows) == len(bad)


@pytest.mark.parametrize(
    "edit, field, words",
    [
        (("section.thickness", "flexures.e99.thickness"), "axes[0].path", "e99"),
        (("section.thickness", "material.colour"), "material.colour", "unknown field"),
        (("values = [0.09, 0.11]", "values = [0.09, -0.11]"), "section.thickness", "point 2"),
        (("values = [0.09, 0.11]", 'values = [0.09, "thin"]'), "axes[0].values", "thin"),
        (("combine", "combine"), "combine", "'diagonal'"),
        (("batch = 2", 'batch = 2\noutputs = ["peak_stress", "stress"]'), "outputs", "'stress'"),
    ],
)
def test_bad_sweep_files_exit_2_naming_the_field(tmp_path, capsys, edit, field, words):
    text = TINY.replace(*edit)
    if field == "combine":
        text = text.replace("batch = 2", 'batch = 2\ncombine = "diagonal"')
    code = main(["sweep", str(_write(tmp_path, text)), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and field in err and words in err
    assert not (tmp_path / "o").exists()


def test_workers_with_an_existing_cluster_is_refused(tmp_path, capsys):
    args = [
        "sweep",
        str(_write(tmp_path, TINY)),
        "--scheduler",
        "tcp://127.0.0.1:8786",
        "--workers",
        "2",
        "--out",
        str(tmp_path / "o"),
    ]
    assert main(args) == 2 and "--workers" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_cli_sweep_on_a_local_process_cluster(tmp_path, capsys):
    text = TINY.replace('["ee", "dcmm:1"]', '["ee"]').replace(
        'reference = "prbm"', 'reference = "dcmm:1"'
    )
    out = tmp_path / "o"
    args = ["sweep", str(_write(tmp_path, text)), "--out", str(out), "--workers", "1", "--quiet"]
    assert main(args) == 0
    assert "Sweep `tiny`" in capsys.readouterr().out
    assert {p.name for p in out.iterdir()} >= {
        "results",
        "summary.md",
        "timings.md",
        "errors.png",
        "runtime.png",
    }
    assert main(args) == 0
    assert "0 tasks" in capsys.readouterr().err


def test_cantilever_geometry_extremes(tmp_path, client):
    """The geometry extremes (slenderness, arc angle) as built-in sweeps on the sweep engine."""
    slender = load_sweep("slenderness")
    thinnest = min(slender.points, key=lambda p: p.params["section.thickness"])
    angle = load_sweep("arc_angle")
    widest = max(angle.points, key=lambda p: p.params["flexures.f.width_deg"])
    models = tuple(parse_model(m) for m in ("beam:40", "prbm"))
    got = {}
    for sweep, point in ((slender, thinnest), (angle, widest)):
        sweep = dataclasses.replace(sweep, points=(point,), models=models)
        run_sweep(sweep, tmp_path / sweep.name, client, use_cache=False)
        rows = results_store(sweep, tmp_path / sweep.name).rows()
        got[sweep.name] = {r["model"]: r for r in rows}
    # h/r = 1/1000: shear and thickness effects are O((h/r)^2) = 1e-6, so the continuum
    # must meet the thin-beam limit; a locking mesh would be orders of magnitude stiffer.
    # beam:40's own discretisation error is ~ (2.1/40)^2/24 ~ 1e-4: gate 0.2 %
    thin = got["slenderness"]["beam:40"]
    assert thin["end_disp_vec"] < 0.2 and thin["end_rot"] < 0.2
    # 350 deg: the beam still follows the continuum, the table-bound PRBM refuses by name
    closed = got["arc_angle"]
    assert closed["beam:40"]["end_disp_vec"] < 1.0
    assert closed["prbm"]["status"] == "model_invalid"
    assert "outside the fitted range" in closed["prbm"]["reason"]


@pytest.mark.parametrize("name", BUILTIN_SWEEPS)
def test_builtin_sweeps_load(name):
    """Each built-in sweep loads from a fresh checkout (the example's file once was ignored
    by git), with every point valid."""
    sweep = load_sweep(name)
    assert sweep.name == name and sweep.points
    assert len(sweep.valid_points) == len(sweep.points)


def test_cli_help_names_every_builtin_sweep():
    from flexval.validation.cli import build_parser

    sweep_parser = build_parser()._subparsers._group_actions[0].choices["sweep"]
    help_text = sweep_parser.format_help().replace("\n", " ")
    for name in BUILTIN_SWEEPS:
        assert name in help_text


def _peak(lp) -> float:
    """The largest peak stress over the flexures at the last level (MPa), read directly."""
    return max(v[-1] for v in lp.peak_stress.values())


def test_peak_stress_rows_against_the_closed_form_and_the_reference(tmp_path, client):
    sweep = load_sweep(_write(tmp_path, TINY))
    assert sweep.outputs == ("peak_stress",)  # the default
    run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    rows = sweep_rows(sweep, tmp_path / "o")
    assert len(rows) == 4 * 3 * 2 and {r["load_unit"] for r in rows} == {"N", "N mm"}
    for r in rows:
        point = sweep.points[r["point"]]
        assert r["peak_stress"] > 0 and r["peak_stress_flexure"] in ("e12", "e23", "e34")
        assert 0.0 <= r["peak_stress_at"] <= 1.0 and r["peak_stress_load"] == 1.0
        assert r["limit_load"] is None  # not asked for
        if r["load_case"] == "m+":
            # a pure end moment M bends every section alike: 6 M / (b h^2) whatever E and
            # whatever the model (measured spread ~1e-13 relative)
            h = point.params["section.thickness"]
            m = point.scene.load_case("m+").magnitude
            assert r["peak_stress"] == pytest.approx(6.0 * m / (1.0 * h * h), rel=1e-9)
            if r["model"] != "prbm":
                assert abs(r["peak_stress_error"]) < 1e-7
    # f+: the error is the models' own peak stresses compared, run here independently
    p = sweep.points[1]
    lc = p.scene.load_case("f+")
    ref = _peak(run_model(p.scene, parse_model("prbm"), lc))
    for model in ("ee", "dcmm:1"):
        got = next(
            r for r in rows if r["point"] == 1 and r["model"] == model and r["load_case"] == "f+"
        )
        want = _peak(run_model(p.scene, parse_model(model), lc))
        assert got["peak_stress"] == pytest.approx(want, rel=1e-9)
        assert got["peak_stress_error"] == pytest.approx(100 * (want - ref) / ref, rel=1e-6)
    files = write_outputs(sweep, rows, tmp_path / "o")
    assert tmp_path / "o" / "stress.png" in files
    text = (tmp_path / "o" / "summary.md").read_text()
    assert "## Peak stress against `prbm`" in text and "## Limit loads" not in text


def test_limit_loads_of_the_deep_arch(tmp_path, client):
    """Da Deppo and Schmidt's arch (limit P R^2 / EI = 8.97, EI / R^2 = 1 N at E = 120 GPa)
    under 10 N: below E = 120 GPa load control stops at the limit point, which the sweep
    finds by arc length; the limit load is proportional to E; at 240 GPa 10 N is below it."""
    text = f"""
    base = "{SCENES / "deep_arch.toml"}"
    models = ["beam:10", "dcmm:2"]
    reference = "beam:40"
    outputs = ["errors", "limit_load"]

    [[axes]]
    path = "material.youngs_modulus"
    values = [60000.0, 120000.0, 240000.0]
    """
    sweep = load_sweep(_write(tmp_path, text))
    assert sweep.outputs == ("limit_load",)
    run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    rows = {(r["point"], r["model"]): r for r in sweep_rows(sweep, tmp_path / "o")}
    ref = rows[(1, "beam:40")]
    assert ref["status"] == "solver_failure" and ref["load_unit"] == "N"
    assert ref["limit_load"] == pytest.approx(DA_DEPPO_SCHMIDT, rel=5e-3)
    # peak stresses were not asked for: none, even where a run reached full load
    assert all(r["peak_stress"] is None and r["peak_stress_error"] is None for r in rows.values())
    for model in ("beam:40", "beam:10", "dcmm:2"):
        half, full, double = (rows[(i, model)] for i in range(3))
        # the trace's parabola refinement is good to ~1e-5 (flexval.validation.failures)
        assert half["limit_load"] == pytest.approx(full["limit_load"] / 2, rel=1e-4)
        assert double["status"] == "ok" and double["limit_load"] is None
        if model != "beam:40":
            assert full["limit_load_error"] == pytest.approx(
                100 * (full["limit_load"] - ref["limit_load"]) / ref["limit_load"], rel=1e-12
            )
    # beam:10 overestimates the limit load by its discretisation error: 1.5 % (measured)
    assert 0.5 < rows[(1, "beam:10")]["limit_load_error"] < 3.0
    files = write_outputs(sweep, list(rows.values()), tmp_path / "o")
    assert tmp_path / "o" / "limits.png" in files
    summary = (tmp_path / "o" / "summary.md").read_text()
    assert "## Limit loads against `beam:40`" in summary and "## Peak stress" not in summary
    assert "limit point at 8.9" in summary
    # a later summary without limit loads (nor peak stresses) removes the figures an earlier
    # run left, and nothing else: a file of the user's and the other outputs stay
    (tmp_path / "o" / "stress.png").write_bytes(b"an earlier run's")
    (tmp_path / "o" / "mine.png").write_bytes(b"the user's")
    files = write_outputs(
        sweep,
        [r | {"limit_load": None, "limit_load_error": None} for r in rows.values()],
        tmp_path / "o",
    )
    assert not (tmp_path / "o" / "limits.png").exists()
    assert not (tmp_path / "o" / "stress.png").exists()
    assert (tmp_path / "o" / "mine.png").read_bytes() == b"the user's"
    assert all(f.is_file() for f in files) and (tmp_path / "o" / "results").is_dir()


def test_an_older_dataset_is_refused_and_other_code_versions_left_out(tmp_path, capsys):
    text = TINY.replace('["ee", "dcmm:1"]', '["ee"]').replace(
        'reference = "prbm"', 'reference = "dcmm:1"'
    )
    sweep_file = _write(tmp_path, text)
    sweep = load_sweep(sweep_file)
    out = tmp_path / "o"
    args = ["sweep", str(sweep_file), "--out", str(out), "--workers", "1", "--quiet"]
    assert main(args) == 0
    capsys.readouterr()
    store = results_store(sweep, out)
    rows = store.rows()
    # rows stored by an earlier code version: other keys, left out of the summary
    store.append([r | {"key": "old-" + r["key"], "end_rot": 1e3} for r in rows])
    assert sweep_rows(sweep, out) == rows
    assert main(args) == 0
    assert f"{len(rows)} stored rows left out of the summary (of an earlier code version" in (
        capsys.readouterr().err
    )
    # a part without the peak-stress and limit-load columns (written before them)
    old = pq.read_table(store.parts()[0]).drop_columns(["peak_stress", "limit_load"])
    pq.write_table(old, out / "results" / "part-old.parquet")
    summary = (out / "summary.md").stat().st_mtime_ns
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "results" in err and "peak_stress" in err and "another --out" in err
    assert (out / "summary.md").stat().st_mtime_ns == summary


def test_cli_sweep_on_an_existing_scheduler(tmp_path, capsys, client, monkeypatch):
    """--scheduler ADDRESS: the tasks run on that cluster's workers, none is started."""
    import flexval.validation.sweep

    def no_local_cluster(*args, **kwargs):
        raise AssertionError("a local cluster was started despite --scheduler")

    monkeypatch.setattr(flexval.validation.sweep, "local_cluster", no_local_cluster)
    text = TINY.replace('["ee", "dcmm:1"]', '["ee"]').replace(
        'reference = "prbm"', 'reference = "dcmm:1"'
    )
    sweep_file = _write(tmp_path, text)
    address = client.scheduler.address
    args = [
        "sweep",
        str(sweep_file),
        "--scheduler",
        address,
        "--out",
        str(tmp_path / "o"),
        "--quiet",
    ]
    assert main(args) == 0
    assert "4 tasks, 16 rows written (0 failed)" in capsys.readouterr().err
    rows = sweep_rows(load_sweep(sweep_file), tmp_path / "o")
    assert len(rows) == 16 and {r["status"] for r in rows} == {"ok"}


@pytest.mark.parametrize(
    "points, workers", [(1, 1), (6, 2), (30, 2), (200, 8), (1000, 2), (100_000, 64)]
)
def test_automatic_batches_keep_every_worker_fed(points, workers):
    """At most 25 points a task (Dask's ~5 ms a task stays ~1 % of the work), and at least 4
    tasks per worker and model where the points allow it within that cap."""
    batch = auto_batch(points, workers)
    assert 1 <= batch <= MAX_AUTO_BATCH
    tasks = -(-points // batch)
    assert tasks >= min(points, TASKS_PER_WORKER * workers) or batch == MAX_AUTO_BATCH


PRELOAD_PROBE = """
import os
from distributed import Client
from flexval.validation.sweep.engine import local_cluster
from flexval.validation.sweep.preload import MODELS_ENV


def probe(_):
    from flexval.reducedmodels.kernels import dcmmkernel, prbmkernel

    # the machine code each kernel holds in this worker (compiled or loaded from the cache)
    return len(prbmkernel.assemble_chains.signatures), len(dcmmkernel.assemble_sub_arcs.signatures)


if __name__ == "__main__":
    with local_cluster(1, ["prbm", "no-such-model"]) as cluster, Client(cluster) as client:
        print(client.submit(probe, 0).result(), MODELS_ENV in os.environ)
"""


@pytest.mark.skipif(
    "forkserver" not in __import__("multiprocessing").get_all_start_methods(),
    reason="workers are forked from a server only where the platform has one",
)
def test_a_local_clusters_workers_start_with_the_sweeps_models_loaded(tmp_path):
    """The workers of local_cluster(models) are forked with those models' kernels loaded (prbm's,
    not dcmm's, which no model named needs); a model id that does not parse is skipped; the
    driver's environment is left as it was. In a fresh process: one forkserver serves a
    process's clusters."""
    import subprocess
    import sys

    script = tmp_path / "probe.py"
    script.write_text(PRELOAD_PROBE)
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=120, check=True
    )
    assert done.stdout.split("\n")[-2] == "(1, 0) False"


def test_models_load_ahead_by_id_and_bad_ids_are_left_to_their_workers():
    from flexval.validation.sweep.preload import load_models

    assert load_models(["prbm", "beam:3[nonsense]", "ee", "no-such-model"]) == ["prbm", "ee"]


def test_parasitic_rows_are_the_gates_metric_computed_independently(tmp_path, client):
    # the largest parasitic error at full load, each component against the reference's own
    # value: recomputed here from the two paths by hand (across the force and the rotation;
    # a moment's dx and dy)
    sweep = load_sweep(_write(tmp_path, TINY))
    run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    rows = sweep_rows(sweep, tmp_path / "o")
    p = sweep.points[1]
    for case in ("f+", "m+"):
        lc = p.scene.load_case(case)
        ref = run_model(p.scene, parse_model("prbm"), lc)
        got = next(
            r for r in rows if r["point"] == 1 and r["model"] == "ee" and r["load_case"] == case
        )
        ours = run_model(p.scene, parse_model("ee"), lc)
        if case == "f+":
            (force,) = lc.components
            across = np.array([-math.sin(force.angle), math.cos(force.angle)])
            parts = [
                (across @ [ours.dx[-1], ours.dy[-1]], across @ [ref.dx[-1], ref.dy[-1]]),
                (ours.rotation[-1], ref.rotation[-1]),
            ]
        else:
            parts = [(ours.dx[-1], ref.dx[-1]), (ours.dy[-1], ref.dy[-1])]
        want = max(100 * abs(a - b) / abs(b) for a, b in parts)
        assert got["parasitic"] == pytest.approx(want, rel=1e-9)
