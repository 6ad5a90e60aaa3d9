"""The stress suite: unit rescaling, load amplification with failure
classification, step-count and invariance studies, and the report files."""

import dataclasses
import json
import math

import numpy as np
import pytest
from builders import cantilever, tip_force, tip_moment
from test_compare_scale import _arch
from test_joints import fourbar_scene

from flexval.geometry import Arc, Scene, load_scene
from flexval.reducedmodels import run_reduced
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.run import run_model
from flexval.validation.studies.compare import errors, scale_of
from flexval.validation.studies.stress import (
    rescale_lengths,
    scale_case,
    stress_report,
    write_stress,
)


@pytest.mark.parametrize(
    "scene_fn,case_name",
    [(fourbar_scene, "fx"), (fourbar_scene, "mb"), (lambda: load_scene("closed_chain"), "f-")],
)
@pytest.mark.parametrize("model", ["dcmm:2", "beam:8", "ee"])
def test_metres_give_the_same_answer(scene_fn, case_name, model):
    scene = scene_fn()
    case = scene.load_case(case_name)
    base = run_reduced(scene.mechanism, parse_model(model), case)
    mech_m, case_m = rescale_lengths(scene.mechanism, case, 1e-3)
    assert mech_m.material.youngs_modulus == pytest.approx(
        1e6 * scene.mechanism.material.youngs_modulus, rel=1e-15
    )
    metres = run_reduced(mech_m, parse_model(model), case_m)
    # the solver's tests are dimensionless (size, load scale): the same iterations up to
    # round-off; 1e-9 leaves room for the force tolerance (1e-10) on a soft path
    d = np.array([base.dx, base.dy])
    np.testing.assert_allclose(
        np.array([metres.dx, metres.dy]) / 1e-3, d, atol=1e-9 * np.abs(d).max()
    )
    np.testing.assert_allclose(
        metres.rotation, base.rotation, atol=1e-9 * np.abs(base.rotation).max()
    )


def test_scale_case_scales_every_component():
    case = load_scene("open_chain").load_case("f+")
    big = scale_case(case, 20.0)
    assert big.name == case.name and big.levels == case.levels
    assert big.magnitude == 20.0 * case.magnitude


def _tiny_scene() -> Scene:
    """One 240 deg arc clamped to the ground; a moment and a force on its tip."""
    mech = cantilever(Arc((0.0, 0.0), 3.0, 0.4, math.radians(240)))
    EI = mech.flexures[0].bending_stiffness(mech.material)
    length = mech.flexures[0].shape.length
    cases = (tip_moment(0.05 * EI / length, name="M"), tip_force(mech, 0.0, 2e-4, name="F"))
    return Scene("tiny", "", mech, cases, (), frozenset(), "<tiny>")


@pytest.fixture(scope="module")
def tiny_report():
    return stress_report(_tiny_scene(), ["dcmm:1", "ee"], quick=True)


def test_stress_report_on_a_tiny_scene(tiny_report):
    r = tiny_report
    assert r["reference"] == "beam:40" and r["amplifications"] == [1, 2, 5, 10, 20, 50, 100]
    assert r["step_counts"] == [2, 11, 101]
    for model in ("dcmm:1", "ee"):
        for case in ("M", "F"):
            res = r["models"][model][case]
            amp = res["amplification"]
            # a failure must be a SolverError, never a crash or non-finite output
            assert amp["failure"] is None or amp["failure"]["kind"] == "solver"
            assert [row["factor"] for row in amp["rows"]] == r["amplifications"][: len(amp["rows"])]
            # path independence and invariance: round-off and the 1e-10 force tolerance
            assert res["step_count"]["disp_rel"] < 1e-9 and res["step_count"]["rot_rel"] < 1e-9
            for kind in ("rigid_motion", "metres"):
                assert res["invariance"][kind]["disp_rel"] < 1e-9
                assert res["invariance"][kind]["rot_rel"] < 1e-9
    # the linear model never fails, and its error grows with the load
    ee = r["models"]["ee"]["F"]["amplification"]
    assert ee["largest_factor"] == 100 and ee["failure"] is None
    errs = [row["errors"]["path_disp"] for row in ee["rows"] if row["errors"]]
    assert len(errs) >= 3 and errs[-1] > 10 * errs[0]
    # a pure moment bends an arc into a circle: DCMM_1's rotation is exact at any load,
    # so only the reference's discretisation (beam:40) separates them
    for row in r["models"]["dcmm:1"]["M"]["amplification"]["rows"]:
        if row["errors"]:
            assert row["errors"]["end_rot"] < 0.1


def _table(text: str, title: str) -> list[list[str]]:
    """The cells of the Markdown table under the heading ``title``."""
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("## ") and title in line)
    start = next(i for i in range(k, len(lines)) if lines[i].startswith("|"))
    rows = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def test_stress_files_are_strict_json_and_markdown(tiny_report, tmp_path):
    md, js = write_stress(tiny_report, tmp_path / "out")
    data = json.loads(js.read_text(), parse_constant=lambda c: pytest.fail(f"non-JSON {c}"))
    # the JSON is the report, nothing lost (every value here is finite)
    assert data == json.loads(json.dumps(tiny_report))
    text = md.read_text()
    # every table cell, found by row and column, states the report's value
    amplification = _table(text, "(a) Load amplification")
    steps = _table(text, "(b) Step count")
    invariance = _table(text, "(c) Invariance")
    pairs = [(m, c) for m in ("dcmm:1", "ee") for c in ("M", "F")]
    for table in (amplification, steps, invariance):
        assert [tuple(row[:2]) for row in table] == pairs
    for (model, case), a, b, c in zip(pairs, amplification, steps, invariance):
        res = tiny_report["models"][model][case]
        amp = res["amplification"]
        assert float(a[2]) == amp["largest_factor"]
        assert float(a[3].split()[0]) == pytest.approx(amp["largest_load"], rel=5e-4)
        last = [row for row in amp["rows"] if row["errors"]][-1]
        assert float(a[4].split()[0]) == pytest.approx(last["errors"]["path_disp"], rel=5e-3)
        assert float(a[5]) == pytest.approx(last["errors"]["path_rot"], rel=5e-3, abs=1e-12)
        assert (a[6] == "none up to the cap") == (amp["failure"] is None)
        for cell, value in (
            (b[2], res["step_count"]["disp_rel"]),
            (b[3], res["step_count"]["rot_rel"]),
            (c[2], res["invariance"]["rigid_motion"]["disp_rel"]),
            (c[5], res["invariance"]["metres"]["rot_rel"]),
        ):
            assert float(cell) == pytest.approx(value, rel=5e-3, abs=1e-300)


def test_closed_chain_failure_is_a_limit_point():
    scene = load_scene("closed_chain")
    scene = dataclasses.replace(scene, load_cases=(scene.load_case("f+"),))
    amp = stress_report(scene, ["dcmm:1"], quick=True)["models"]["dcmm:1"]["f+"]["amplification"]
    fail = amp["failure"]
    # DCMM_1 holds 4.9 N but not 9.8 N: its equilibrium path turns back at ~8.71 N
    assert amp["largest_factor"] == 1 and fail["factor"] == 2 and fail["kind"] == "solver"
    assert "step cutting failed" in fail["message"]
    reached = fail["load_factor"] * 2 * 4.90
    # load control stops just below the limit; the arc-length peak agrees to ~1e-5
    assert fail["limit_load"] == pytest.approx(reached, rel=1e-3)
    assert fail["limit_load"] >= reached * (1 - 1e-5)


def test_a_rotation_that_vanishes_by_symmetry_is_measured_against_its_scale(tmp_path):
    """The shallow arch pressed on its axis turns its crown by round-off in every model: the
    amplification errors, the step-count spread and the invariance differences take that
    rotation against its scale (:func:`flexval.validation.studies.compare.scale_of`), not against
    itself,
    where round-off over round-off read as a 30-500 % failed invariance."""
    scene, case, _ = _arch(tmp_path, -90.0, 0.1)
    L = scene.mechanism.size()
    res = stress_report(scene, ["dcmm:1"], quick=True)["models"]["dcmm:1"]["down"]
    ref = run_model(scene, parse_model("beam:40"), case)
    lp = run_model(scene, parse_model("dcmm:1"), case)
    assert abs(ref.rotation[-1]) < 1e-9 * scale_of(ref, L)["rot"]  # round-off
    assert abs(lp.rotation[-1] - ref.rotation[-1]) > 0.01 * abs(ref.rotation[-1])
    row = res["amplification"]["rows"][0]
    assert row["factor"] == 1
    assert row["errors"] == pytest.approx(errors(lp, ref, L), rel=1e-12, abs=1e-20)
    assert row["errors"]["end_rot"] < 1e-9 and row["errors"]["end_disp"] > 1  # a real error
    # path independence and invariance hold to round-off once measured on the scale
    assert res["step_count"]["rot_rel"] < 1e-9
    for kind in ("rigid_motion", "metres"):
        assert res["invariance"][kind]["disp_rel"] < 1e-9
        assert res["invariance"][kind]["rot_rel"] < 1e-9
