"""A failure is a result: a report on a scene where one model passes its own limit point.

The scene is a shallow arch of two 30 deg arcs (one closed loop) pressed near
its crown with 0.15 N. `dcmm:2` has a limit point at 0.126 N (84 % of the
load), the beams' is at about 0.21 N (beyond the load): the report must
complete, keep the other models' results, and name dcmm:2's failure (how far,
why, at which load) in every table where dcmm:2 appears, in the findings and
in the discussion. The limit load it prints is checked against an
independent arc-length trace; the load reached against the partial path.
"""

from __future__ import annotations

import dataclasses
import json
import re

import pytest

from flexval.geometry import load_scene
from flexval.geometry.graph import independent_loops
from flexval.reducedmodels import build_system, catalogue
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.continuation import limit_loads, solve_arclength
from flexval.validation.cli import main
from flexval.validation.failures import LIMIT_POINT, LIMIT_SETTINGS
from flexval.validation.report import figures
from flexval.validation.report.data import compute_report
from flexval.validation.report.writer import write_report

ARCH = """
name = "arch"
description = "shallow arch of two curved flexures (one closed loop) pressed near its crown"
[material]
youngs_modulus = 2000.0
poisson_ratio = 0.3
[section]
depth = 1.0
thickness = 0.3
[ground]
name = "g"
points = [[-10.0, 0.0], [10.0, 0.0]]
[target]
body = "c"
point = [0.0, 2.0]
[[bodies]]
name = "c"
points = [[0.0, 2.0]]
[[flexures]]
name = "left"
bodies = ["g", "c"]
center = [-1.267949192431122, -17.66025403784439]
radius = 19.701098547724776
axis_deg = 101.30993247402021
width_deg = 30
[[flexures]]
name = "right"
bodies = ["g", "c"]
center = [1.267949192431122, -17.66025403784439]
radius = 19.701098547724776
axis_deg = 78.69006752597979
width_deg = 30
[[load_cases]]
name = "down"
kind = "force"
body = "c"
point = [0.0, 2.0]
angle_deg = -80.0
value = 0.15
levels = 11
"""
MODELS = ["beam:100", "beam:10", "dcmm:1", "dcmm:2", "ee"]


@pytest.fixture(scope="module")
def arch(tmp_path_factory):
    d = tmp_path_factory.mktemp("arch")
    path = d / "arch.toml"
    path.write_text(ARCH)
    data = compute_report(
        [str(path)], MODELS, repeats=1, use_cache=False, progress=False, bench=False, converge=False
    )
    return path, data, write_report(data, d / "out")


def test_the_failure_is_recorded_with_its_limit_load(arch):
    path, data, _ = arch
    (res,) = data.scenes
    (fail,) = res.failures
    assert (fail.model, fail.load_case, fail.reason) == ("dcmm:2", "down", LIMIT_POINT)
    # independent: arc length through the limit point of the same model
    scene = load_scene(path)
    case = scene.load_case("down")
    system = build_system(scene.mechanism, parse_model("dcmm:2"), LIMIT_SETTINGS)
    lp = solve_arclength(
        system,
        case,
        1.0,
        20,
        model="dcmm:2",
        max_steps=2000,
        stop=lambda p: bool(p.stats["limit_points"]),
    )
    assert fail.load == pytest.approx(limit_loads(lp)[0], rel=1e-12)
    # load control stops just below the limit: the partial path ends at the load reached
    partial = res.paths[("dcmm:2", "down")]
    assert not partial.converged
    assert partial.load[-1] <= fail.factor * case.magnitude * (1 + 1e-12)
    assert fail.factor * case.magnitude == pytest.approx(fail.load, rel=2e-3)
    assert 0.5 < fail.factor < 1.0
    # every other model reached the full load
    for m in MODELS:
        if m != "dcmm:2":
            assert res.converged(m, "down") is not None, m


def test_every_table_names_the_failure(arch):
    _, data, md = arch
    fail = data.scenes[0].failures[0]
    text = md.read_text()
    summary = fail.summary()
    assert re.fullmatch(r"fails at \d+ % \(limit point, [\d.]+ N\)", summary)
    timings = (md.parent / "timings.md").read_text()
    rows = [
        line
        for line in (text + timings).splitlines()
        if line.startswith("| dcmm:2 |") and not line.startswith("| dcmm:2 | follower |")
    ]  # another model: it passes
    # paper-convention table, metrics table, frame table (leader row), timing table
    assert len(rows) == 4 and all(summary in r for r in rows), rows
    findings = text.split("### Findings")[1].split("## Discussion")[0]
    assert f"`dcmm:2` on `down` {summary}" in findings
    assert f"`dcmm:2` on `down` of arch {summary}" in text.split("## Discussion")[1]
    # the failing model is no candidate for "within x %" or "cheapest within x %"
    assert "`dcmm:2` (" not in findings and "**dcmm:2**" not in timings


def test_limit_table_has_no_bifurcation_rows_without_bifurcations(arch):
    _, data, md = arch
    assert data.scenes[0].bifurcations() == []
    text = md.read_text()
    table = text.split("### Limit loads against `beam:100`")[1].split("###")[0]
    rows = [line for line in table.splitlines() if line.startswith("| `")]
    assert rows == [f"| `dcmm:2` | {data.scenes[0].failures[0].load:.5g} N |"]
    scene_part = text.split("\n## arch", 1)[1]  # the setup lists bifurcation as a reason
    assert "bifurcation" not in scene_part.lower()


def test_results_json_carries_the_failure(arch):
    _, data, md = arch
    dump = json.loads((md.parent / "results.json").read_text())["scenes"]["arch"]
    (fail,) = dump["failures"]
    assert fail == data.scenes[0].failures[0].to_dict()
    partial = next(r for r in dump["results"] if r["model"] == "dcmm:2")
    assert partial["converged"] is False and len(partial["load"]) >= 2


def test_rendering_runs_no_model(arch, tmp_path, monkeypatch):
    """Renderers only format: with every model runner broken, the report is rewritten
    identically from the computed data."""
    _, data, md = arch

    def broken(*args, **kwargs):
        raise AssertionError("a renderer ran a model")

    monkeypatch.setattr(
        catalogue,
        "_FAMILIES",
        {f.name: dataclasses.replace(f, run=broken) for f in catalogue.families()},
    )
    again = write_report(data, tmp_path)
    assert again.read_text() == md.read_text()


def test_report_from_the_command_line_exits_0(arch, tmp_path):
    path, _, _ = arch
    args = [
        "report",
        str(path),
        "--out",
        str(tmp_path),
        "--no-bench",
        "--no-converge",
        "--no-cache",
        "--quiet",
        "--repeats",
        "1",
    ]
    for m in MODELS:
        args += ["--model", m]
    assert main(args) == 0
    assert "fails at" in (tmp_path / "report.md").read_text()


def test_topology_is_the_cycle_rank_of_the_body_graph(arch):
    path, _, md = arch
    assert independent_loops(load_scene("open_chain").mechanism) == 0
    assert independent_loops(load_scene("closed_chain").mechanism) == 1
    assert independent_loops(load_scene(path).mechanism) == 1
    assert "a closed chain (1 independent loop)" in md.read_text()


def test_converge_records_the_failure_and_carries_on(arch, tmp_path):
    path, _, _ = arch
    out = tmp_path / "conv.json"
    assert (
        main(["converge", str(path), "--model", "dcmm", "--levels", "1,2,4", "--json", str(out)])
        == 3
    )
    (st,) = json.loads(out.read_text())["studies"]
    assert [r["model"] for r in st["rows"]][0] == "dcmm:1"
    assert "dcmm:2" in [f["model"] for f in st["failures"]]
    assert len(st["rows"]) + len(st["failures"]) == 3


def test_load_path_figure_draws_the_traced_branch(arch):
    """The arc-length path through dcmm:2's limit point is kept and drawn (dashed, labelled)."""
    _, data, _ = arch
    (res,) = data.scenes
    (fail,) = res.failures
    paths = {m: res.paths[(m, "down")] for m in res.models if (m, "down") in res.paths}
    curves = figures.load_path_curves(paths, res.traces("down"))
    (traced,) = [c for c in curves if c["label"] == "dcmm:2 (arc length)"]
    assert traced["style"]["ls"] == "--"
    assert traced["style"]["color"] == figures.style("dcmm:2")["color"]
    assert list(traced["load"]) == [abs(v) for v in fail.trace.load]
    # the recorded limit load is this branch's own peak, refined by the parabola through the
    # traced peak and its neighbours: at or above the traced maximum, by less than the load
    # step that led to it; the branch passes the peak (its last load is lower)
    assert fail.load == pytest.approx(limit_loads(fail.trace)[0], rel=1e-12)
    k = int(traced["load"].argmax())
    peak = traced["load"][k]
    assert 0 <= fail.load - peak < peak - traced["load"][k - 1]
    assert traced["load"][-1] < peak
    # no other model failed: no other trace
    assert [c["label"] for c in curves if "arc length" in c["label"]] == ["dcmm:2 (arc length)"]
