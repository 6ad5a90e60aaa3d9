"""First yield and safety factors: the crossing of the recorded peak stress with the yield
strength, against a closed form (a straight cantilever under an end moment, whose fibre
stress is M h/(2I) exactly) and against an independent interpolation of a path's series;
the strengths' input checks and the run JSON."""

from __future__ import annotations

import json
import tomllib
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from builders import cantilever, in_process_client, tiny_scene, tip_moment

from flexval.geometry import Material, Segment, load_scene
from flexval.reducedmodels import run_reduced
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.cli import main
from flexval.validation.run import run_model
from flexval.validation.studies.yieldpoint import (
    first_crossing,
    first_yield,
    path_yield,
    scene_yield,
)


def _scene_file(tmp_path, **material) -> str:
    """The built-in open chain with ``material`` fields added, as a scene file."""
    text = resources.files("flexval.geometry").joinpath("scenes", "open_chain.toml").read_text()
    assert tomllib.loads(text)["material"]  # the table the fields go into
    lines = "".join(f"{k} = {v!r}\n" for k, v in material.items())
    path = tmp_path / "strong.toml"
    path.write_text(text.replace("[material]\n", "[material]\n" + lines, 1))
    return str(path)


def test_first_crossing_interpolates_and_handles_ends():
    assert first_crossing([0.0, 1.0, 3.0], 2.0) == (2, 0.5)
    assert first_crossing([0.0, 1.0, 3.0], 3.0) == (2, 1.0)  # reached exactly at a level
    assert first_crossing([0.0, 1.0, 3.0], 3.5) is None
    assert first_crossing([4.0, 5.0], 2.0) == (0, 1.0)  # the first level already yields
    # the first crossing counts, not a later one after the stress fell
    assert first_crossing([0.0, 2.0, 0.5, 4.0], 1.0) == (1, 0.5)
    fy = first_yield([0.0, 1.0, 2.0], [0.0, 4.0, 8.0], ["a", "b", "c"], [1.0, 2.0, 3.0], 6.0, 4.0)
    assert fy == {"load": 1.5, "fraction": 0.375, "flexure": "c", "at": 3.0}


def test_cantilever_end_moment_yields_at_closed_form():
    # a straight cantilever under an end moment: every section carries M, and the outer fibre
    # M h/(2I); with I = b h^3/12 it yields at M_y = 2 I sigma_y / h = b h^2 sigma_y / 6
    b, h, E, length = 1.0, 0.1, 2100.0, 10.0
    sigma_y = 4.0
    mech = cantilever(Segment((0.0, 0.0), (length, 0.0)), E=E, b=b, h=h)
    moment_y = b * h**2 * sigma_y / 6.0
    full = moment_y / 0.37  # not on a level
    case = tip_moment(full, levels=11)
    material = Material(E, 0.3, sigma_y, 0.5 * sigma_y)
    for model in ("beam:20", "dcmm:2", "prbm", "ee"):
        lp = run_reduced(mech, parse_model(model), case)
        got = path_yield(lp, material, {"f": length}, full)
        fy = got["first_yield"]
        assert fy is not None and fy["flexure"] == "f", model
        assert fy["load"] == pytest.approx(moment_y, rel=1e-9), model
        assert fy["fraction"] == pytest.approx(0.37, rel=1e-9), model
        assert 0.0 <= fy["at"] <= length
        # safety factors at full load: sigma / (6 M / (b h^2))
        assert got["safety_factor"]["yield"] == pytest.approx(0.37, rel=1e-9), model
        assert got["safety_factor"]["fatigue"] == pytest.approx(0.185, rel=1e-9), model
        assert got["yield_note"] is None


def test_open_chain_first_yield_matches_recorded_series(tmp_path):
    # beam:100 on f+ with sigma_y = 5 MPa: recompute the crossing from the path's own
    # per-flexure peak-stress series
    scene = load_scene(_scene_file(tmp_path, yield_strength=5.0))
    case = scene.load_case("f+")
    lp = run_reduced(scene.mechanism, parse_model("beam:100"), case)
    fy = scene_yield(scene, lp)["first_yield"]
    names = list(lp.peak_stress)
    table = np.array([lp.peak_stress[n] for n in names])
    peak = table.max(axis=0)
    k = int(np.argmax(peak >= 5.0))
    assert peak[k - 1] < 5.0 <= peak[k] and k >= 2
    load = np.interp(5.0, peak[k - 1 : k + 1], lp.load[k - 1 : k + 1])
    assert fy["load"] == pytest.approx(load, rel=1e-12)
    assert fy["fraction"] == pytest.approx(load / case.magnitude, rel=1e-12)
    holder = names[int(np.argmax(table[:, k]))]
    length = next(f.shape.length for f in scene.mechanism.flexures if f.name == holder)
    assert fy["flexure"] == holder
    assert fy["at"] == pytest.approx(lp.peak_stress_at[holder][k] * length, rel=1e-12)
    rot = np.interp(5.0, peak[k - 1 : k + 1], lp.rotation[k - 1 : k + 1])
    assert fy["rotation"] == pytest.approx(rot, rel=1e-12)


def test_strength_above_every_stress_gives_none_and_safety_above_one(tmp_path):
    scene = load_scene(_scene_file(tmp_path, yield_strength=1000.0, fatigue_strength=500.0))
    lp = run_reduced(scene.mechanism, parse_model("dcmm:1"), scene.load_case("f+"))
    got = scene_yield(scene, lp)
    peak = max(v[-1] for v in lp.peak_stress.values())
    assert got["first_yield"] is None and got["yield_note"] is None
    assert got["safety_factor"]["yield"] == pytest.approx(1000.0 / peak, rel=1e-12)
    assert got["safety_factor"]["fatigue"] == pytest.approx(500.0 / peak, rel=1e-12)
    assert got["safety_factor"]["yield"] > 1.0


def test_path_without_stress_or_full_load_says_why():
    mech = cantilever(Segment((0.0, 0.0), (10.0, 0.0)))
    lp = run_reduced(mech, parse_model("beam:4"), tip_moment(0.01))
    material = Material(2100.0, 0.3, 1e-3)
    lp.peak_stress = None
    got = path_yield(lp, material, {"f": 10.0}, 0.01)
    assert got["first_yield"] is None and got["safety_factor"]["yield"] is None
    assert "no stress" in got["yield_note"]
    lp = run_reduced(mech, parse_model("beam:4"), tip_moment(0.01))
    lp.converged = False  # a path that stopped: it yielded, but its full load is unknown
    got = path_yield(lp, material, {"f": 10.0}, 0.01)
    assert got["first_yield"] is not None and got["safety_factor"]["yield"] is None
    assert "short of full load" in got["yield_note"]


def test_strengths_decide_no_path_and_no_cache_key(tmp_path):
    from flexval.validation.cache import result_key

    plain = load_scene("open_chain")
    strong = load_scene(_scene_file(tmp_path, yield_strength=5.0, fatigue_strength=2.0))
    assert strong.mechanism.material.yield_strength == 5.0
    assert strong.mechanism.material == plain.mechanism.material
    assert result_key(strong, "ee", "f+", None, {}) == result_key(plain, "ee", "f+", None, {})


@pytest.mark.parametrize(
    ("fields", "field", "value"),
    [
        ({"yield_strength": -1.0}, "material.yield_strength", "-1"),
        ({"yield_strength": 0.0}, "material.yield_strength", "0"),
        ({"yield_strength": "high"}, "material.yield_strength", "high"),
        ({"yield_strength": 5.0, "fatigue_strength": 5.0}, "material.fatigue_strength", "5"),
        ({"yield_strength": 5.0, "fatigue_strength": -2.0}, "material.fatigue_strength", "-2"),
        ({"fatigue_strength": 2.0}, "material.fatigue_strength", "2"),
    ],
)
def test_bad_strength_exits_2_naming_field(tmp_path, capsys, fields, field, value):
    code = main(["run", _scene_file(tmp_path, **fields), "--model", "ee"])
    err = capsys.readouterr().err
    assert code == 2
    assert field in err and value in err and "Traceback" not in err


def test_run_json_carries_first_yield(tmp_path, capsys):
    out = tmp_path / "run.json"
    scene = _scene_file(tmp_path, yield_strength=5.0, fatigue_strength=2.0)
    args = ["run", scene, "--model", "ee", "--load-case", "f+", "--load-case", "m+"]
    assert main([*args, "--json", str(out)]) == 0
    assert "first yield: load" in capsys.readouterr().out
    f_plus, m_plus = json.loads(out.read_text())["results"]
    assert set(f_plus["first_yield"]) == {
        "load",
        "fraction",
        "flexure",
        "at",
        "dx",
        "dy",
        "rotation",
    }
    assert 0.0 < f_plus["first_yield"]["fraction"] < 1.0
    assert f_plus["safety_factor"]["yield"] < 1.0 < m_plus["safety_factor"]["yield"]
    assert m_plus["first_yield"] is None  # the pure moments stay at 3 MPa
    # without a strength the results are the load paths' fields only
    plain = tmp_path / "plain.json"
    assert main(["run", "open_chain", "--model", "ee", "--json", str(plain)]) == 0
    assert all("first_yield" not in r for r in json.loads(plain.read_text())["results"])


TINY = tiny_scene("tiny_strong", "yield_strength = 40.0\nfatigue_strength = 20.0", force=0.05)


def test_report_tabulates_first_yield_against_the_continuum(tmp_path):
    from flexval.validation.report.data import read_results
    from flexval.validation.report.writer import build_report

    path = tmp_path / "tiny_strong.toml"
    path.write_text(TINY)
    md = build_report(
        [str(path)],
        tmp_path / "out",
        ["continuum:0", "beam:40", "dcmm:1"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    text = md.read_text()
    table = text.split("### Load and target displacement at first yield against `continuum:0`")[1]
    table = table.split("###")[0]
    paths = read_results(md.parent)["tiny_strong"]
    scene = load_scene(path)
    ref = scene_yield(scene, paths[("continuum:0", "up")])["first_yield"]
    assert ref is not None and 0.0 < ref["fraction"] < 1.0
    for model in ("continuum:0", "beam:40", "dcmm:1"):
        got = scene_yield(scene, paths[(model, "up")])
        fy = got["first_yield"]
        row = next(line for line in table.splitlines() if line.startswith(f"| `{model}` |"))
        assert f"{fy['load']:.4g} N ({100 * fy['fraction']:.1f} %)" in row
        assert f"{np.hypot(fy['dx'], fy['dy']):.4g} mm" in row
        if model != "continuum:0":
            err = 100.0 * (fy["load"] - ref["load"]) / ref["load"]
            assert f"load {err:+.2f} %" in row
        assert row.split("|")[3].strip() == "none"  # twist: 0.02 N mm stays at 3 MPa
        safety = f"{got['safety_factor']['yield']:.3g} / {got['safety_factor']['fatigue']:.3g}"
        assert safety in table.split("Safety factor")[1]


def test_continuum_notch_hinge_yields_by_its_true_peak(tmp_path):
    # a circular notch hinge under an end moment M: the section resultants' beam formula at the
    # root is 6 M / (b t^2) exactly (statics), so a model judged by it yields at
    # M_y = b t^2 sigma_y / 6; the continuum is judged by its true fibre peak K 6 M / (b t^2)
    # (K the stress concentration at each level) and yields at M_y / K
    text = (Path(__file__).parent / "scenes" / "notch_hinge.toml").read_text()
    path = tmp_path / "notch.toml"
    path.write_text(text.replace("[material]\n", "[material]\nyield_strength = 60.0\n", 1))
    scene = load_scene(path)
    flexure = scene.mechanism.flexures[0]
    b, t = flexure.section.depth, flexure.section.thickness
    moment_y = b * t**2 * 60.0 / 6.0
    case = scene.load_case("moment")
    reduced = run_model(scene, parse_model("dcmm:4[eb]"), case)  # plain: the beam formula
    assert scene_yield(scene, reduced)["first_yield"]["load"] == pytest.approx(moment_y, rel=1e-6)
    # calibrated (the default): the beam formula times the hinge's calibrated concentration,
    # largest at the waist of a circular hinge under a moment, where the table's K(s) is its
    # waist K (the surface peak over 6 M / (b t^2)) to the peak's offset: measured 1.3e-6
    from flexval.reducedmodels.notchcorrection import factors_of

    concentrated = factors_of(flexure, scene.mechanism.material.poisson_ratio).stress
    calibrated = run_model(scene, parse_model("dcmm:4"), case)
    calibrated_yield = scene_yield(scene, calibrated)["first_yield"]["load"]
    assert calibrated_yield == pytest.approx(moment_y / concentrated, rel=1e-5)
    assert calibrated.fibre_stress["hinge"]["at"] == pytest.approx(0.5, abs=1e-12)
    lp = run_model(scene, parse_model("continuum:0"), case)
    true = np.asarray(lp.fibre_stress["hinge"]["path_stress"])
    assert true[-1] == lp.fibre_stress["hinge"]["stress"]  # the full-load peak, level by level
    fy = scene_yield(scene, lp)["first_yield"]
    k = int(np.argmax(true >= 60.0))
    assert fy["load"] == pytest.approx(
        np.interp(60.0, true[k - 1 : k + 1], lp.load[k - 1 : k + 1]), rel=1e-12
    )
    concentration = true / np.asarray(lp.peak_stress["hinge"])
    assert concentration[k - 1] <= moment_y / fy["load"] <= concentration[k]
    assert concentration[k] > 1.01  # the notch's own concentration, not round-off
    assert fy["at"] == pytest.approx(0.5 * flexure.shape.length, rel=1e-9)  # at the root
    # the calibration's K (continuum:2) against this coarse mesh's own: within 1 %
    assert calibrated_yield == pytest.approx(fy["load"], rel=1e-2)


def test_sweep_rows_carry_first_yield(tmp_path):

    from flexval.validation.sweep import load_sweep, run_sweep, sweep_rows

    base = _scene_file(tmp_path, yield_strength=5.0)
    sweep_file = tmp_path / "sw.toml"
    sweep_file.write_text(
        f'name = "strong"\nbase = "{base}"\nmodels = ["ee", "dcmm:1"]\nreference = "prbm"\n'
        'load_cases = ["f+", "m+"]\noutputs = ["first_yield"]\n'
        '[[axes]]\npath = "material.yield_strength"\nvalues = [4.0, 6.0]\n'
    )
    sweep = load_sweep(sweep_file)
    with in_process_client() as client:
        run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    rows = sweep_rows(sweep, tmp_path / "o")
    assert len(rows) == 2 * 3 * 2
    for r in rows:
        scene = sweep.points[r["point"]].scene
        assert scene.mechanism.material.yield_strength == r["param:material.yield_strength"]
        want = scene_yield(
            scene, run_model(scene, parse_model(r["model"]), scene.load_case(r["load_case"]))
        )
        fy = want["first_yield"] or {}
        # the sweep traces its points as batches: each path its solo run's to 1e-12
        if fy:
            assert r["first_yield_load"] == pytest.approx(fy["load"], rel=1e-12)
            assert r["first_yield_fraction"] == pytest.approx(fy["fraction"], rel=1e-12)
        else:
            assert r["first_yield_load"] is None and r["first_yield_fraction"] is None
        assert r["first_yield_flexure"] == fy.get("flexure")
        assert r["safety_factor"] == pytest.approx(want["safety_factor"]["yield"], rel=1e-12)
        assert r["fatigue_safety_factor"] is None  # no fatigue strength
        assert (r["first_yield_load"] is None) == (r["load_case"] == "m+")  # 3 MPa < 4
