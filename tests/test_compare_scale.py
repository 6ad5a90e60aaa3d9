"""Relative errors of a quantity whose reference is near zero are taken against its scale.

Closed forms on hand-made paths (the exact percentages follow from the rule in
:mod:`flexval.validation.studies.compare`), then the case that shows it: a shallow arch pressed
on its axis of symmetry turns its crown by round-off in every model, which
relative errors turned into tens or hundreds of percent; against the rotation
scale it is zero.
The same arch pressed 10 deg off its axis keeps its (real) 785 %.
"""

from __future__ import annotations

import math

import pytest
from test_report_failures import ARCH

from flexval.geometry import load_scene
from flexval.reducedmodels import LoadPath, parse_model
from flexval.validation.run import run_model
from flexval.validation.studies.compare import NEAR_ZERO, errors, scale_of


def _path(dx, rotation, dy=None) -> LoadPath:
    n = len(dx)
    return LoadPath(
        "m", "c", [k / (n - 1) for k in range(n)], list(dx), dy or [0.0] * n, list(rotation), 0.0
    )


def test_a_rotation_back_to_zero_is_measured_against_its_scale():
    # the target moves 10 mm, the mechanism is 20 mm: rotation scale 0.5 rad
    ref = _path([0.0, 5.0, 10.0], [0.0, 0.2, 1e-14])
    model = _path([0.0, 5.0, 10.0], [0.0, 0.2, 0.05])
    assert scale_of(ref, 20.0) == {"disp": pytest.approx(0.2 * 20.0), "rot": 0.5}
    e = errors(model, ref, 20.0)
    assert e["end_rot"] == pytest.approx(100 * 0.05 / 0.5)  # 10 % of the scale
    assert e["path_rot"] == pytest.approx(100 * 0.05 / 0.2)  # the path's own maximum


@pytest.mark.parametrize("length", [None, 0.0, -1.0, float("nan"), float("inf"), "20"])
def test_the_mechanism_size_is_required_and_checked(length):
    ref = _path([0.0, 5.0, 10.0], [0.0, 0.2, 1e-14])
    with pytest.raises(ValueError, match="length must be the mechanism's size"):
        errors(ref, ref, length)
    with pytest.raises(TypeError):
        errors(ref, ref)  # no caller can forget it


def test_a_target_on_the_centre_of_rotation_is_measured_against_its_scale():
    # the body turns 0.1 rad about the target point: displacement scale 0.1 * 30 = 3 mm
    ref = _path([0.0, 1e-15, 2e-15], [0.0, 0.05, 0.1])
    model = _path([0.0, 0.03, 0.06], [0.0, 0.05, 0.1])
    e = errors(model, ref, 30.0)
    assert e["end_disp_vec"] == pytest.approx(100 * 0.06 / 3.0)
    assert e["end_disp"] == pytest.approx(100 * 0.06 / 3.0)
    assert e["path_disp"] == pytest.approx(100 * 0.06 / 3.0)
    assert e["end_rot"] == 0.0


def test_values_above_the_threshold_keep_their_own_denominator():
    """Just above NEAR_ZERO of the scale the rule is the plain relative error."""
    rot_end = 1.01 * NEAR_ZERO * 0.5
    ref = _path([0.0, 5.0, 10.0], [0.0, rot_end / 2, rot_end])
    model = _path([0.0, 5.0, 10.0], [0.0, rot_end / 2, 2 * rot_end])
    e = errors(model, ref, 20.0)
    assert e["end_rot"] == pytest.approx(100.0) and e["path_rot"] == pytest.approx(100.0)
    # and just below it, the scale: 2 * 0.99 % of 0.5 rad off is 0.99 % of the scale
    ref = _path([0.0, 5.0, 10.0], [0.0, 0.2, 0.99 * NEAR_ZERO * 0.5])
    model = _path([0.0, 5.0, 10.0], [0.0, 0.2, 2 * 0.99 * NEAR_ZERO * 0.5])
    assert errors(model, ref, 20.0)["end_rot"] == pytest.approx(0.99 * NEAR_ZERO * 100)


def _arch(tmp_path, angle_deg: float, force: float):
    """The report-failure arch (pressed with 0.15 N at -80 deg) pressed with ``force`` (N)
    at ``angle_deg``."""
    text = ARCH.replace("angle_deg = -80.0", f"angle_deg = {angle_deg}")
    (tmp_path / "arch.toml").write_text(text.replace("value = 0.15", f"value = {force}"))
    scene = load_scene(tmp_path / "arch.toml")
    case = scene.load_case("down")
    return scene, case, run_model(scene, parse_model("beam:100"), case)


@pytest.mark.parametrize("model", ["beam:10", "dcmm:1", "prbm"])
def test_the_crown_of_an_arch_pressed_on_its_axis_does_not_turn(tmp_path, model):
    scene, case, ref = _arch(tmp_path, -90.0, 0.1)
    L = scene.mechanism.size()
    assert abs(ref.rotation[-1]) < 1e-9 * scale_of(ref, L)["rot"]  # round-off
    lp = run_model(scene, parse_model(model), case)
    scaled = errors(lp, ref, L)
    plain = abs(lp.rotation[-1] - ref.rotation[-1]) / abs(ref.rotation[-1])
    assert plain > 0.01  # round-off over round-off: percent and more
    assert scaled["end_rot"] < 1e-9 and scaled["path_rot"] < 1e-9
    d, d_ref = lp.displacement, ref.displacement  # not near zero: plain relative error
    assert scaled["end_disp"] == pytest.approx(100 * abs(d[-1] / d_ref[-1] - 1), rel=1e-9)


def test_an_arch_pressed_off_its_axis_keeps_its_relative_rotation_error(tmp_path):
    """10 deg off the axis the crown turns by 0.42 of its scale: a real rotation, and a
    model that turns it 9 times as far is that far off."""
    scene, case, ref = _arch(tmp_path, -80.0, 0.15)
    L = scene.mechanism.size()
    assert abs(ref.rotation[-1]) > 0.4 * scale_of(ref, L)["rot"]
    lp = run_model(scene, parse_model("dcmm:1"), case)
    e = errors(lp, ref, L)
    assert e["end_rot"] == pytest.approx(
        100 * abs(lp.rotation[-1] / ref.rotation[-1] - 1), rel=1e-12
    )
    assert e["end_rot"] > 500 and math.isfinite(e["end_rot"])
