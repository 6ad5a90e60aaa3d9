"""The batched cost per path: it times the real paths, and the run-time tables show it.

The reference of every timing is the same path run alone (:func:`flexval.validation.run.run_model`):
a small batch through the report's own code (:func:`time_batch`, :func:`batch_paths`) must give
every copy the solo path's end values, to the batch's round-off. The tables are read back
against ``timings.json``, and rescaling every batched time must leave the result files as
they are.
"""

from __future__ import annotations

import copy
import json
import math
import statistics
from pathlib import Path

import numpy as np
import pytest
from test_report import TINY

from flexval.geometry import load_scene
from flexval.reducedmodels import SolverError
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.report.data import PAPER_REFERENCE, compute_report
from flexval.validation.report.tables import sig
from flexval.validation.report.timings import render_timings
from flexval.validation.report.writer import render_markdown, write_report
from flexval.validation.run import run_model
from flexval.validation.studies.batchtiming import (
    AGREEMENT_BAR,
    BATCH_COPIES,
    BATCH_SECONDS,
    BATCH_UNKNOWNS,
    REFERENCE_COPIES,
    SPEED_REFERENCE,
    BatchMemo,
    batch_copies,
    batch_paths,
    end_agreement,
    time_batch,
)
from flexval.validation.studies.bench import runtime_vs_error, write_bench

SMALL = 3
"""Copies of the tests' batches: enough for the batch to share one Newton among copies."""


@pytest.mark.parametrize("unknowns", [1, 9, 21, 180, 199, 200, 201, 900, 3600, 20_000, 10**6])
@pytest.mark.parametrize("seconds", [0.0, 1e-4, 1e-3, 2.5e-3, 0.05, 1.0])
def test_copies_fill_a_batch_up_to_its_bounds(unknowns, seconds):
    n = batch_copies(unknowns, "dcmm:1", seconds)
    assert 1 <= n <= BATCH_COPIES
    assert n == 1 or (n * unknowns <= BATCH_UNKNOWNS and n * seconds <= BATCH_SECONDS * (1 + 1e-12))
    # the most that fit
    assert (
        n == BATCH_COPIES
        or (n + 1) * unknowns > BATCH_UNKNOWNS
        or (n + 1) * seconds > BATCH_SECONDS
    )
    # the reference of the speed-ups, the tables' beam:100, is timed on its plateau
    assert SPEED_REFERENCE == PAPER_REFERENCE
    assert batch_copies(unknowns, SPEED_REFERENCE) == REFERENCE_COPIES


@pytest.mark.parametrize(
    "model, case_name",
    [("dcmm:1", "f+"), ("dcmm:2", "m-"), ("beam:20", "f-"), ("prbm", "f+"), ("ee", "m+")],
)
def test_a_small_batch_times_the_solo_path(model, case_name):
    scene = load_scene("open_chain")
    spec, case = parse_model(model), scene.load_case(case_name)
    solo = run_model(scene, spec, case)
    paths, wall = batch_paths(scene, spec, case, SMALL)
    assert wall > 0 and len(paths) == SMALL
    size = float(np.max(np.hypot(solo.dx, solo.dy)))
    turn = float(np.max(np.abs(solo.rotation)))
    for lp in paths:
        assert lp.load == solo.load
        assert math.hypot(lp.dx[-1] - solo.dx[-1], lp.dy[-1] - solo.dy[-1]) <= 1e-12 * size
        assert abs(lp.rotation[-1] - solo.rotation[-1]) <= 1e-12 * turn
        assert lp.stats["batch"] == SMALL  # a linear model's copies too: one assembly
    timing = time_batch(scene, spec, case, repeats=2, copies=SMALL)
    assert timing.copies == SMALL and len(timing.samples) == 2
    assert all(math.isfinite(s) and s > 0 for s in timing.samples)
    assert timing.seconds == statistics.median(timing.samples)
    assert timing.agrees and timing.agreement <= AGREEMENT_BAR
    assert timing.batches == [SMALL]


def test_agreement_sees_another_path():
    scene = load_scene("open_chain")
    spec, case = parse_model("dcmm:1"), scene.load_case("f+")
    solo, size = run_model(scene, spec, case), scene.mechanism.size()
    assert end_agreement(solo, [copy.deepcopy(solo)], size) == 0.0
    moved = copy.deepcopy(solo)
    moved.dx[-1] += 1e-9 * size
    assert end_agreement(solo, [solo, moved], size) == pytest.approx(1e-9, rel=1e-6)
    turned = copy.deepcopy(solo)
    turned.rotation[-1] += 1e-10  # rad
    assert end_agreement(solo, [turned], size) == pytest.approx(1e-10, rel=1e-5)
    assert end_agreement(solo, [SolverError("stopped", 0.5)], size) is None
    short = copy.deepcopy(solo)
    short.load = short.load[:-1]
    assert end_agreement(solo, [short], size) is None


def test_a_path_of_little_motion_agrees_to_round_off():
    """The stage's platform moves 0.5 um without turning under the vertical load: its end
    values are round-off of positions some 40 mm large, which the batch's copies reproduce
    within the solver's scale (the mechanism's size), not within their own size."""
    scene = load_scene("filleted_stage")
    spec, case = parse_model("dcmm:1"), scene.load_case("v-")
    solo, size = run_model(scene, spec, case), scene.mechanism.size()
    assert float(np.max(np.hypot(solo.dx, solo.dy))) < 1e-5 * size
    assert float(np.max(np.abs(solo.rotation))) < 1e-12
    timing = time_batch(scene, spec, case, repeats=1, copies=SMALL)
    assert timing.agrees and timing.agreement < 1e-13


def test_each_model_gets_its_own_repeats():
    scene = load_scene("open_chain")
    case = scene.load_case("f+")
    memo = BatchMemo(2, None, repeats_for=lambda spec: 2 if spec.id == "dcmm:1" else 1)
    assert len(memo.get(scene, parse_model("dcmm:1"), case).samples) == 2
    assert len(memo.get(scene, parse_model("dcmm:2"), case).samples) == 1


def test_the_reference_and_failing_paths_are_not_batched():
    scene = load_scene("open_chain")
    case = scene.load_case("f+")
    assert time_batch(scene, parse_model("continuum:0"), case, copies=SMALL) is None
    memo = BatchMemo(1)
    assert memo.get(scene, parse_model("continuum:0"), case) is None
    assert BatchMemo(1, enabled=False).get(scene, parse_model("dcmm:1"), case) is None
    # Lee's frame: load control stops at the limit point, alone and so in a batch
    lee = load_scene(Path(__file__).parent / "scenes" / "lee_frame.toml")
    with pytest.raises(SolverError):
        run_model(lee, parse_model("beam:10"), lee.load_cases[0])
    assert time_batch(lee, parse_model("beam:10"), lee.load_cases[0], copies=SMALL) is None


MODELS = ["continuum:0", "beam:100", "dcmm:1", "ee"]


@pytest.fixture(scope="module")
def computed(tmp_path_factory):
    path = tmp_path_factory.mktemp("batched") / "tiny.toml"
    path.write_text(TINY)
    data = compute_report(
        [str(path)], MODELS, repeats=1, use_cache=False, progress=False, bench=False, converge=False
    )
    return data, write_report(data, tmp_path_factory.mktemp("out")).parent


def _table(text: str) -> dict[str, dict[str, str]]:
    """The run-time table of ``timings.md``: {model: {column: cell}}."""
    lines = text.splitlines()
    start = next(k for k, line in enumerate(lines) if "ours (s)" in line)
    header = [c.strip() for c in lines[start].strip("|").split("|")]
    rows = {}
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows[cells[0]] = dict(zip(header, cells))
    return rows


def test_the_timing_table_shows_the_batched_cost_and_speed_ups(computed):
    _, out = computed
    rows = _table((out / "timings.md").read_text())
    timed = json.loads((out / "timings.json").read_text())["scenes"]["tiny"]["batched"]
    batched = {(t["model"], t["load_case"]): t for t in timed}
    assert {m for m, _ in batched} == {"beam:100", "dcmm:1", "ee"}
    cases = ("up", "twist")
    for t in timed:
        assert math.isfinite(t["seconds"]) and t["seconds"] > 0
        assert t["agreement"] <= AGREEMENT_BAR and not t["cached"]
        assert rows[t["model"]][f"{t['load_case']} batched (s)"] == sig(t["seconds"], 3)
        assert rows[t["model"]]["copies"] == str(t["copies"])
    for case in cases:
        assert rows["continuum:0"][f"{case} batched (s)"] == "not batched"
    assert rows["continuum:0"]["speed-up vs beam:100, batched"] == "–"
    assert rows["beam:100"]["speed-up vs beam:100, ours"] == "1x"
    assert rows["beam:100"]["speed-up vs beam:100, batched"] == "1x"
    ref = statistics.mean(batched[("beam:100", c)]["seconds"] for c in cases)
    for model in ("dcmm:1", "ee"):
        mean = statistics.mean(batched[(model, c)]["seconds"] for c in cases)
        assert rows[model]["speed-up vs beam:100, batched"] == f"{ref / mean:.3g}x"
    # the copies follow the rule from each model's unknowns
    paths = json.loads((out / "results.json").read_text())["scenes"]["tiny"]["results"]
    unknowns = {r["model"]: r["stats"]["unknowns"] for r in paths}
    for (model, _), t in batched.items():
        # the rule's bounds; the time alone of the batch's own solo run may lower it
        assert 1 <= t["copies"] <= batch_copies(unknowns[model], model)
        if model == SPEED_REFERENCE:
            assert t["copies"] == REFERENCE_COPIES
        assert t["batches"] == [t["copies"]]


def _no_figure(*args) -> None:
    """A figure drawer that draws nothing (the texts are compared, not the pictures)."""


def _bench(scene, models: tuple[str, ...]):
    """The runtime-versus-error rows (and failures) of ``models`` against ``beam:40``, one
    repeat."""
    return runtime_vs_error(
        scene, parse_model("beam:40"), [parse_model(m) for m in models], repeats=1, progress=False
    )


def test_batched_times_change_only_the_timings_files(computed, tmp_path):
    data, _ = computed
    scene = data.scenes[0].scene
    rows, _ = _bench(scene, ("beam:100", "dcmm:1"))
    data = copy.deepcopy(data)
    data.scenes[0].bench_rows = rows
    slower = copy.deepcopy(data)
    for t in slower.scenes[0].batched.values():
        t.seconds *= 7.3
    for row in slower.scenes[0].bench_rows:
        row["batched_seconds"] *= 7.3
    a, b = tmp_path / "a", tmp_path / "b"
    assert json.dumps(data.results()) == json.dumps(slower.results())
    assert json.dumps(data.gates()) == json.dumps(slower.gates())
    assert render_markdown(data, a, _no_figure) == render_markdown(slower, b, _no_figure)
    assert render_timings(data, {}, 1.0) != render_timings(slower, {}, 1.0)
    bench_a = write_bench(scene, rows, "beam:40", a, draw=_no_figure)
    bench_b = write_bench(scene, slower.scenes[0].bench_rows, "beam:40", b, draw=_no_figure)
    assert bench_a.read_text() != bench_b.read_text()
    for r in data.results()["scenes"]["tiny"]["bench"]:
        assert "batched_seconds" not in r and "copies" not in r and "seconds" not in r


def test_the_bench_table_has_the_batched_columns(computed, tmp_path):
    data, _ = computed
    scene = data.scenes[0].scene
    rows, failures = _bench(scene, ("beam:100", "dcmm:1", "ee"))
    assert not failures
    for r in rows:
        assert math.isfinite(r["batched_seconds"]) and r["batched_seconds"] > 0
    text = write_bench(scene, rows, "beam:40", tmp_path).read_text()
    lines = [line for line in text.splitlines() if line.startswith("|")]
    header = [c.strip() for c in lines[0].strip("|").split("|")]
    cells = {
        c[0]: dict(zip(header, c))
        for c in ([x.strip() for x in line.strip("|").split("|")] for line in lines[2:])
    }
    by_model = {r["model"]: r for r in rows}
    assert cells["beam:100"]["speed-up vs beam:100"] == "1x"
    assert cells["beam:100"]["batched speed-up"] == "1x"
    ref = by_model["beam:100"]["batched_seconds"]
    for model, r in by_model.items():
        assert cells[model]["batched (s/path)"] == sig(r["batched_seconds"], 3)
        assert len(set(r["copies"])) == 1 and r["batches"] == [1, 1]  # one batch per case
        assert cells[model]["copies × batches"] == f"{r['copies'][0]} × 1"
        assert cells[model]["batched speed-up"] == f"{ref / r['batched_seconds']:.3g}x"
