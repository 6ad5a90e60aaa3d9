"""A small report on a tiny scene: results.json holds the models' own paths, every
table cell agrees with them (found by row and column), and every linked figure exists."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from builders import tiny_scene

from flexval.geometry import load_scene
from flexval.reducedmodels import parse_model
from flexval.validation.report.data import read_results
from flexval.validation.report.writer import build_report
from flexval.validation.run import run_model
from flexval.validation.studies.compare import errors

TINY = tiny_scene()


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    d = tmp_path_factory.mktemp("rep")
    scene = d / "tiny.toml"
    scene.write_text(TINY)
    md = build_report(
        [str(scene)],
        d / "out",
        ["beam:100", "beam:10", "dcmm:1", "ee"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    return md


def test_tables_match_results_json(report):
    text = report.read_text()
    paths = read_results(report.parent)["tiny"]
    rows = re.findall(
        r"^\| (\S+) \| (up|twist) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \| "
        r"([\d.]+) \| ([\d.]+) \|$",
        text,
        flags=re.M,
    )
    assert len(rows) == 3 * 2  # three models against beam:100, two cases
    size = load_scene(report.parent.parent / "tiny.toml").mechanism.size()
    for model, case, *vals in rows:
        e = errors(paths[(model, case)], paths[("beam:100", case)], size)
        expect = [e[k] for k in ("end_disp_vec", "end_disp", "end_rot", "path_disp", "path_rot")]
        for got, ref in zip(map(float, vals), expect):
            assert got == pytest.approx(ref, abs=0.006)  # printed with 2 decimals


def test_results_json_holds_the_models_own_paths(report, tmp_path):
    """results.json is what the models give when run directly (not something the report made)."""
    data = json.loads((report.parent / "results.json").read_text())
    (tmp_path / "tiny.toml").write_text(TINY)
    scene = load_scene(tmp_path / "tiny.toml")
    for r in data["scenes"]["tiny"]["results"]:
        direct = run_model(scene, parse_model(r["model"]), scene.load_case(r["load_case"]))
        for key in ("load", "dx", "dy", "rotation"):
            # deterministic solvers: equal up to round-off
            np.testing.assert_allclose(
                r[key],
                getattr(direct, key),
                rtol=1e-9,
                atol=1e-12,
                err_msg=f"{r['model']} {r['load_case']} {key}",
            )


def test_timing_table_cells_are_each_paths_seconds(report):
    """Each cell of the timing table (in timings.md), found by its row (model) and column
    (case), is the path's median time in timings.json."""
    text = (report.parent / "timings.md").read_text().splitlines()
    data = json.loads((report.parent / "timings.json").read_text())
    seconds = {(r["model"], r["load_case"]): r["seconds"] for r in data["scenes"]["tiny"]["paths"]}
    start = next(k for k, line in enumerate(text) if "ours (s)" in line)
    header = [c.strip() for c in text[start].strip("|").split("|")]
    rows = {}
    for line in text[start + 2 :]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows[cells[0]] = dict(zip(header, cells))
    assert set(rows) == {"beam:100", "beam:10", "dcmm:1", "ee"}
    for model, row in rows.items():
        for case in ("up", "twist"):
            assert row[f"{case} ours (s)"] == f"{seconds[(model, case)]:.4f}", (model, case)
        mean = (seconds[(model, "up")] + seconds[(model, "twist")]) / 2
        ref = (seconds[("beam:100", "up")] + seconds[("beam:100", "twist")]) / 2
        assert row["speed-up vs beam:100, ours"] == f"{ref / mean:.3g}x", model


def test_linked_figures_exist(report):
    text = report.read_text()
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert links
    for name in links:
        assert (report.parent / name).is_file(), name


def test_peak_stress_table_matches_results_json(report):
    text = report.read_text()
    paths = read_results(report.parent)["tiny"]
    section = text.split("### Peak stress")[1].split("###")[0]
    rows = re.findall(r"^\| `(\S+)` \| (.+) \|$", section, flags=re.M)
    assert [m for m, _ in rows] == ["beam:100", "beam:10", "dcmm:1", "ee"]
    for model, cells in rows:
        for case, cell in zip(("up", "twist"), cells.split(" | ")):
            lp, ref = paths[(model, case)], paths[("beam:100", case)]
            value, err = re.match(
                r"([\d.e+-]+) MPa(?: at a@[\d.]+|, uniform) \(([+-][\d.]+) %\)", cell
            ).groups()
            peak, ref_peak = lp.peak_stress["a"][-1], ref.peak_stress["a"][-1]
            assert float(value) == pytest.approx(peak, rel=5e-4)  # 4 significant digits
            assert float(err) == pytest.approx(100 * (peak - ref_peak) / ref_peak, abs=0.006)
    assert "Winkler-Bach" in section and "r/h = 10.0" in section


def test_limit_load_table_of_a_scene_with_a_limit_point(tmp_path):
    # Lee's frame: load control stops at the limit point, which arc length finds
    from pathlib import Path

    scene = Path(__file__).parent / "scenes" / "lee_frame.toml"
    md = build_report(
        [str(scene)],
        tmp_path / "out",
        ["beam:10", "prbm"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    text = md.read_text()
    data = json.loads((md.parent / "results.json").read_text())["scenes"]["lee_frame"]
    limits = {f["model"]: f for f in data["failures"] if f["reason"] == "limit point"}
    assert set(limits) == {"beam:10", "prbm"}
    table = text.split("### Limit loads")[1].split("###")[0]
    for model, f in limits.items():
        assert f"| `{model}` | {f['load']:.5g} N |" in table
    # beam:10 (10 elements per member) is 0.55 % above Lee's published 1.855 N
    assert limits["beam:10"]["load"] == pytest.approx(1.855, rel=1e-2)


@pytest.fixture(scope="module")
def builtin_report(tmp_path_factory):
    """Both built-in scenes with one reduced model (the reference beam:100 is added)."""
    from flexval.validation.report.data import compute_report
    from flexval.validation.report.writer import write_report

    data = compute_report(
        ["open_chain", "closed_chain"],
        ["dcmm:1"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    return data, write_report(data, tmp_path_factory.mktemp("builtin") / "out")


def _frequency_rows(text: str, scene: str) -> dict[str, list[tuple[str, float]]]:
    """{model: [(printed Hz, printed % error)]} of ``scene``'s natural-frequency table."""
    part = text.split(f"\n## {scene}\n")[1].split("\n## ")[0]
    table = part.split("### Natural frequencies against `beam:100`")[1].split("###")[0]
    rows = {}
    for model, cells in re.findall(r"^\| `(\S+)` \| (.+) \|$", table, flags=re.M):
        rows[model] = [
            (v, float(e))
            for v, e in (
                re.fullmatch(r"(\S+) \(([+-][\d.]+) %\)", c).groups() for c in cells.split(" | ")
            )
        ]
    return rows


@pytest.mark.parametrize("scene_name", ["open_chain", "closed_chain"])
def test_frequency_table_equals_direct_modal_analysis(builtin_report, scene_name):
    """Each scene's table: the reference's own row at 0 %, every cell the frequency of a
    direct modal analysis (PLA flexures, massless links) and its error against the reference's."""
    from flexval.reducedmodels.analyses.modes import natural_modes
    from flexval.reducedmodels.models import build_system
    from flexval.validation.report.frequencies import DEFAULT_DENSITY, MODE_COUNT
    from flexval.validation.studies.modes import with_density

    data, md = builtin_report
    res = next(r for r in data.scenes if r.scene.name == scene_name)
    assert res.frequencies.errors["beam:100"] == [0.0] * MODE_COUNT
    rows = _frequency_rows(md.read_text(), scene_name)
    assert list(rows) == ["beam:100", "dcmm:1"]
    mechanism = with_density(load_scene(scene_name), DEFAULT_DENSITY).mechanism
    direct = {
        m: natural_modes(build_system(mechanism, parse_model(m)), count=MODE_COUNT).frequencies_hz
        for m in rows
    }
    for model, cells in rows.items():
        for (value, err), f, f_ref in zip(cells, direct[model], direct["beam:100"]):
            assert value == f"{f:.5g}", (model, value, f)
            assert err == pytest.approx(100 * (f - f_ref) / f_ref, abs=0.006)  # 2 decimals
    assert all(e == 0.0 for _, e in rows["beam:100"])


def test_a_failed_modal_analysis_is_a_row_of_the_table(monkeypatch, tmp_path):
    """A model whose modal analysis raises is recorded as a failure; the others are kept."""
    from flexval.reducedmodels import SolverError
    from flexval.validation.report import frequencies

    real = frequencies.run_modes

    def failing_for_dcmm(scene, spec, case, fraction, count):
        if spec.id == "dcmm:1":
            raise SolverError("equilibrium for the modal analysis: no convergence", 0.25)
        return real(scene, spec, case, fraction, count)

    monkeypatch.setattr(frequencies, "run_modes", failing_for_dcmm)
    (tmp_path / "tiny.toml").write_text(TINY)
    table = frequencies.frequency_data(
        load_scene(tmp_path / "tiny.toml"), ["dcmm:1", "ee"], "beam:100"
    )
    assert table.models == ["beam:100", "dcmm:1", "ee"]
    assert [(f.model, f.factor) for f in table.failures] == [("dcmm:1", 0.25)]
    assert set(table.frequencies) == {"beam:100", "ee"}
    text = "\n".join(frequencies.section(table))
    assert "| `dcmm:1` | fails (below) | — | — | — |" in text
    assert (
        "- `dcmm:1`: modal analysis failed: equilibrium for the modal analysis: "
        "no convergence" in text
    )


def test_findings_name_the_levels_a_model_leaves_its_validity(tmp_path):
    """A twist that turns the tip by ~0.47 rad: the linear ee leaves its range (body
    rotations above sqrt(2 MAX_STRAIN)) at the first level whose own rotation passes
    the limit, found here from a direct run; beam:10 stays inside and gets no line."""
    from flexval.reducedmodels.core.validity import MAX_LINEAR_ROTATION

    scene_file = tmp_path / "tiny.toml"
    scene_file.write_text(TINY.replace("value = 0.02", "value = 0.1"))
    md = build_report(
        [str(scene_file)],
        tmp_path / "out",
        ["beam:10", "ee"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    text = Path(md).read_text()
    scene = load_scene(scene_file)
    ee = run_model(scene, parse_model("ee"), scene.load_case("twist"))
    first = next(k for k, r in enumerate(ee.rotation) if abs(r) > MAX_LINEAR_ROTATION)
    assert (
        f"- `ee` on `twist` leaves its range of validity from {ee.load[first]:.4g} N mm "
        f"({len(ee.load) - first} of {len(ee.load)} levels)"
    ) in text
    assert "`beam:10` on `twist` leaves" not in text


def test_peak_stress_in_a_uniform_field_has_no_place():
    # Under the open chain's pure end moment every section carries the same moment: the
    # peak's place is round-off, so the table says "uniform"; under f+ it names the place.
    from flexval.geometry import load_scene
    from flexval.reducedmodels.catalogue import parse_model
    from flexval.validation.report.strength import peak_at_full_load, peak_stress_table
    from flexval.validation.run import run_model

    scene = load_scene("open_chain")
    cases = {c.name: c for c in scene.load_cases}
    bent = peak_at_full_load(run_model(scene, parse_model("dcmm:2"), cases["m+"]))
    pulled = peak_at_full_load(run_model(scene, parse_model("dcmm:2"), cases["f+"]))
    assert bent["uniform"] and not pulled["uniform"]
    table = "\n".join(peak_stress_table({"dcmm:2": {"m+": bent, "f+": pulled}}, ["m+", "f+"]))
    assert f"| `dcmm:2` | {bent['stress']:.4g} MPa, uniform | " in table
    assert f"{pulled['stress']:.4g} MPa at {pulled['flexure']}@{pulled['at']:.2f}" in table


PROTOCOL_HEADING = "## Dynamics: the paper's protocol (open chain f−)"


def test_protocol_section_sits_before_the_discussion_of_an_open_chain_report(
    builtin_report, tmp_path
):
    """Without --protocol the section says how to include it; with a protocol.json of this
    code version it renders it, links the table next to it and calls nothing stale."""
    from test_protocol_section import _document

    from flexval.validation.outputs import write_json
    from flexval.validation.report.writer import render_markdown

    data, md = builtin_report
    text = md.read_text()
    assert text.count(PROTOCOL_HEADING) == 1
    assert (
        text.index("\n## closed_chain\n")
        < text.index(PROTOCOL_HEADING)
        < text.index("\n## Discussion\n")
    )
    assert "Not included in this report (no `--protocol` file)" in text
    path = tmp_path / "dynamics" / "protocol.json"
    path.parent.mkdir()
    write_json(path, _document(code=data.code))
    out = tmp_path / "paper"
    section = render_markdown(data, out, lambda *args: None, path).split(PROTOCOL_HEADING)[1]
    section = section.split("\n## ")[0]
    assert "- **beam:20** (paper 10.7 % disp" in section
    assert "[../dynamics/protocol.md](../dynamics/protocol.md)" in section
    assert "Stale" not in section
