"""The validity monitor: where each model stops meaning anything
(flexval.reducedmodels.core.validity).

* limits against closed forms: a straight cantilever under an end moment
  bends into a circle, so a beam element's ends turn by kappa l0 / 2 from
  its chord and DCMM_1's relative rotation is M L / EI exactly; the
  monitor must switch on the limit (tested at 0.9 and 1.1 of it);
* a continuum strip pulled to 1 % and 3 % axial strain against the 2 %
  fibre-stretch limit;
* DCMM_1 at 100x and 1000x the paper's loads on the
  open chain reports levels outside its range (a flexure whose ends are
  hundreds of mm apart), while every model at the paper's loads stays inside;
* the verdict round-trips through JSON.
"""

import dataclasses
import math

import pytest
from builders import cantilever, tip_force, tip_moment

from flexval.geometry import Segment, load_scene
from flexval.reducedmodels import LoadPath, run_reduced
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.validity import MAX_CHORD_TURN, MAX_RELATIVE_ROTATION, MAX_STRAIN
from flexval.validation.continuum import run_continuum
from flexval.validation.run import run_model

LENGTH, E, H = 10.0, 2100.0, 0.1  # mm, MPa, mm (b = 1 mm)
EI = E * H**3 / 12.0  # N mm^2


def straight():
    return cantilever(Segment((0.0, 0.0), (LENGTH, 0.0)), E=E, h=H)


@pytest.mark.parametrize("share", [0.9, 1.1])
def test_beam_element_turn_switches_at_its_limit(share):
    n = 4
    # pure moment: curvature M / EI, element ends turn by kappa (L / n) / 2 from the chord
    moment = share * MAX_CHORD_TURN * 2.0 * EI * n / LENGTH
    lp = run_reduced(straight(), parse_model(f"beam:{n}"), tip_moment(moment, levels=3))
    assert lp.valid[-1] is (share < 1.0)
    if share > 1.0:
        assert "turned" in lp.validity[-1] and lp.valid[:2] == [True, True]


@pytest.mark.parametrize("share", [0.9, 1.1])
def test_dcmm_relative_rotation_switches_at_its_limit(share):
    moment = share * MAX_RELATIVE_ROTATION * EI / LENGTH  # rotation M L / EI
    lp = run_reduced(straight(), parse_model("dcmm:1"), tip_moment(moment, levels=3))
    assert lp.rotation[-1] == pytest.approx(share * MAX_RELATIVE_ROTATION, rel=1e-9)
    assert lp.valid[-1] is (share < 1.0)


@pytest.mark.parametrize("strain", [0.5 * MAX_STRAIN, 1.5 * MAX_STRAIN])
def test_continuum_fibre_stretch_switches_at_the_strain_limit(strain):
    mech = cantilever(Segment((0.0, 0.0), (LENGTH, 0.0)), E=E, h=1.0)
    # SVK in plane stress: nominal stress E (lambda^3 - lambda) / 2 at stretch lambda = 1 + strain
    stretch = 1.0 + strain
    force = E * (stretch**3 - stretch) / 2.0 * 1.0 * 1.0
    lp = run_continuum(mech, tip_force(mech, force, 0.0, levels=3), level=0)
    assert lp.valid[-1] is (strain < MAX_STRAIN)
    if strain > MAX_STRAIN:
        assert "centre-line segment" in lp.validity[-1]


def scaled(case, factor):
    comps = tuple(dataclasses.replace(c, value=c.value * factor) for c in case.components)
    return dataclasses.replace(case, components=comps)


@pytest.mark.parametrize("factor", [100.0, 1000.0])
@pytest.mark.parametrize("case_name", ["f+", "f-"])
def test_dcmm1_far_beyond_the_paper_loads_is_reported_invalid(factor, case_name):
    scene = load_scene("open_chain")
    case = scaled(scene.load_case(case_name), factor)
    lp = run_reduced(scene.mechanism, parse_model("dcmm:1"), case)
    assert lp.converged and lp.valid[0] and not lp.valid[-1]
    assert "sub-arc chord stretched" in lp.validity[-1]
    # the monitor's reason is the flexure geometry, not the solver: ends farther apart
    # than the flexure is long
    lengths = {f.name: f.shape.length for f in scene.mechanism.flexures}
    flexure = lp.validity[-1].split(":")[0]
    assert flexure in lengths


@pytest.mark.parametrize(
    "model", ["dcmm:1", "dcmm:2", "prbm", "beam:20", "beam:100", "continuum:0"]
)
@pytest.mark.parametrize("scene_name", ["open_chain", "closed_chain"])
def test_every_model_is_valid_at_the_paper_loads(scene_name, model):
    scene = load_scene(scene_name)
    for case in scene.load_cases:
        lp = run_model(scene, parse_model(model), case)
        assert all(lp.valid), (case.name, lp.validity)


def test_ee_is_judged_by_its_linearised_rotations():
    """The linear response is valid while every body turns less than sqrt(2 MAX_STRAIN)
    (0.2 rad): the open chain's f- turns the target by 0.054 rad (valid at every
    level), m+ by 0.957 rad (invalid from the level where the rotation, linear in the
    load, passes 0.2 rad), and 1000 times f+ is invalid from its first loaded level."""
    from flexval.reducedmodels.core.validity import MAX_LINEAR_ROTATION

    scene = load_scene("open_chain")
    ee = parse_model("ee")
    small = run_reduced(scene.mechanism, ee, scene.load_case("f-"))
    assert all(small.valid) and not any(small.validity)
    turned = run_reduced(scene.mechanism, ee, scene.load_case("m+"))
    expected = [abs(r) <= MAX_LINEAR_ROTATION for r in turned.rotation]
    assert turned.valid == expected and expected[1] and not expected[-1]
    assert "body '4' turned" in turned.validity[-1]
    far = run_reduced(scene.mechanism, ee, scaled(scene.load_case("f+"), 1000))
    assert far.valid[0] and not any(far.valid[1:])


def test_the_verdict_round_trips_through_json():
    scene = load_scene("open_chain")
    lp = run_reduced(scene.mechanism, parse_model("dcmm:1"), scaled(scene.load_case("f+"), 100))
    back = LoadPath.from_json(lp.to_json())
    assert back.valid == lp.valid and back.validity == lp.validity
    assert back.validity[0] is None and isinstance(back.validity[-1], str)
    assert math.isfinite(back.dx[-1])


def test_a_notch_bent_beyond_the_strain_limit_is_invalid_in_the_continuum_as_in_the_beam(
    tmp_path,
):
    """A circular notch hinge (t = 0.1 mm, b = 5 mm, aluminium) under a moment whose throat
    stress by the beam formula, 6 M / (b t^2), reaches 2.5 % of E at full load: the levels
    whose throat strain is past 2.05 % are invalid in continuum:0 (its surface fibre stress,
    the stress concentration on top) and in beam:100; those below 1.9 % are valid in both
    (a concentration under 5 % cannot lift them over the limit). The centre line hardly
    stretches: the continuum judged it alone and called every level valid."""
    from pathlib import Path

    import numpy as np

    b, t, E = 5.0, 0.1, 70000.0  # mm, mm, MPa (tests/scenes/notch_hinge.toml)
    moment = 0.025 * E * b * t**2 / 6.0  # N mm
    text = (Path(__file__).parent / "scenes" / "notch_hinge.toml").read_text()
    scene_file = tmp_path / "bent.toml"
    scene_file.write_text(text.replace("value = 1.0\n", f"value = {moment!r}\n"))
    scene = load_scene(str(scene_file))
    case = scene.load_case("moment")
    for model in ("continuum:0", "beam:100"):
        lp = run_model(scene, parse_model(model), case)
        throat = 6.0 * np.abs(lp.load) / (b * t**2 * E)
        for strain, ok, why in zip(throat, lp.valid, lp.validity):
            if strain < 0.019:
                assert ok, (model, strain, why)
            elif strain > 0.0205:
                assert not ok, (model, strain)
                assert "strain" in why
