"""Displacement control: a body point's prescribed motion, the reaction as the output.

Anchors: the von Mises truss's exact load through its snap-through (a path load control
cannot follow), a parallel leaf guide's 24 EI / L^3 and its parasitic shortening
(3/5) delta^2 / L, a cantilever turned by a pure end moment (uniform curvature, M = EI
theta / L exactly), and load control itself: the force a drive reports, applied as a dead
load, gives back the prescribed motion in every family.
"""

import copy
import math
import tomllib

import numpy as np
import pytest
from builders import fd_check
from test_joints import von_mises_truss

from flexval.geometry import Displacement, Force, LoadCase, Moment, SceneError, load_scene
from flexval.geometry.scene import parse_scene
from flexval.reducedmodels import run_reduced
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.batch import run_batch
from flexval.reducedmodels.core.drives import DriveConnector
from flexval.validation.cli import main
from flexval.validation.run import run_model

GUIDE = """
name = "guide"
[material]
youngs_modulus = 70000.0
poisson_ratio = 0.33
[section]
depth = 10.0
thickness = 0.625
[ground]
name = "g"
points = [[0.0, 0.0], [20.0, 0.0]]
[target]
body = "shuttle"
point = [10.0, 50.0]
[[flexures]]
name = "left"
bodies = ["g", "shuttle"]
shape = "segment"
start = [0.0, 0.0]
end = [0.0, 50.0]
[[flexures]]
name = "right"
bodies = ["g", "shuttle"]
shape = "segment"
start = [20.0, 0.0]
end = [20.0, 50.0]
[[load_cases]]
name = "drive"
kind = "displacement"
dx = 1.0
dy = 0.0
[[load_cases]]
name = "slide"
kind = "displacement"
dx = 1.0
"""
EI = 70000.0 * 10.0 * 0.625**3 / 12.0  # N mm^2
L = 50.0  # mm


def guide(text: str = GUIDE):
    return parse_scene(tomllib.loads(text), "<guide>")


@pytest.mark.parametrize("model", ["beam:1", "beam:4", "dcmm:3"])
def test_von_mises_truss_snaps_through_under_displacement_control(model):
    # pinned bars carry axial force only: beams and DCMM segments are exact trusses, so
    # the drive's force is the closed form P(w) all the way through the snap-through
    # (negative stiffness from w ~ 8.5 mm) to beyond the mirrored position at w = 40 mm
    mech, load = von_mises_truss()
    case = LoadCase("snap", (Displacement("c", mech.target_point, dy=-50.0),), 26)
    lp = run_reduced(mech, parse_model(model), case)
    w = -np.asarray(lp.dy)
    np.testing.assert_allclose(w, np.linspace(0.0, 50.0, 26), atol=1e-9)
    forces = np.asarray(lp.drive_reactions)
    p_max = load(np.linspace(0.0, 40.0, 4001)).max()
    # the drive pushes the apex down: Fy = -P(w); the solver's tolerance is 1e-10 of the scale
    np.testing.assert_allclose(-forces[:, 1], load(w), rtol=0, atol=1e-9 * p_max)
    np.testing.assert_allclose(forces[:, [0, 2]], 0.0, atol=1e-9 * p_max)
    assert (forces[:, 1] > 0).any() and (forces[:, 1] < 0).any()  # it snapped through


def test_continuum_truss_crosses_zero_where_the_truss_does():
    # solid bars of L / h = 5 are no exact truss (their end zones soften them: measured
    # 2.1 % below the closed form at the peak), but symmetry is exact: no force with both
    # bars level (w = h0) and in the mirrored, stress-free state (w = 2 h0), and
    # F(w) = -F(2 h0 - w) between
    mech, load = von_mises_truss()
    case = LoadCase("snap", (Displacement("c", mech.target_point, dy=-40.0),), 9)
    lp = run_model_on(mech, "continuum:0", case)
    forces = np.asarray(lp.drive_reactions)[:, 1]
    p_max = load(np.linspace(0.0, 40.0, 4001)).max()
    assert abs(forces[4]) < 1e-9 * p_max and abs(forces[8]) < 1e-9 * p_max
    np.testing.assert_allclose(forces, -forces[::-1], atol=1e-9 * p_max)
    w = -np.asarray(lp.dy)
    np.testing.assert_allclose(-forces, load(w), atol=0.025 * p_max)


def run_model_on(mech, model, case):
    spec = parse_model(model)
    return spec.model_family.trace(mech, spec, case)


@pytest.mark.parametrize(
    "model, rtol",
    # beam:100 and the continuum: measured 0.07 % and 0.01 % off (the shuttle's tilt from
    # the leaves' axial compliance softens the guide by 1e-4); the one-element models
    # carry their own discretisation (dcmm:1 and ee 0.1 %, prbm 0.05 %)
    [("beam:100", 1e-3), ("continuum:1", 1e-3), ("dcmm:1", 2e-3), ("ee", 2e-3), ("prbm", 2e-3)],
)
def test_leaf_guide_stiffness_is_24_EI_over_L_cubed(model, rtol):
    lp = run_model(guide(), model, "slide", levels=3)
    forces = np.asarray(lp.drive_reactions)
    assert forces[1, 0] / lp.dx[1] == pytest.approx(24.0 * EI / L**3, rel=rtol)
    np.testing.assert_allclose(forces[:, 1:], 0.0, atol=1e-9)  # free: no force along y


@pytest.mark.parametrize("model", ["beam:100", "continuum:1"])
def test_leaf_guide_parasitic_shortening(model):
    # Awtar's beam constraint model: the shuttle drops (3/5) delta^2 / L for a stroke delta
    lp = run_model(guide(), model, "slide", levels=3)
    assert lp.dy[-1] == pytest.approx(-0.6 / L, rel=5e-3)


@pytest.mark.parametrize("model", ["beam:20", "dcmm:2", "prbm", "ee", "continuum:0"])
def test_the_drives_force_as_a_dead_load_gives_the_motion_back(model):
    # two formulations of one equilibrium: a prescribed dx (dy held) and its reaction
    # applied as dead loads (force and moment); the solver tolerances are 1e-10
    scene = guide()
    # prbm's straight leaves are inextensible links: it cannot be held along dy as well
    driven = run_model(scene, model, "slide" if model == "prbm" else "drive", levels=3)
    fx, fy, moment = driven.drive_reactions[-1]
    point = scene.mechanism.target_point
    case = LoadCase(
        "back",
        (
            Force("shuttle", point, math.atan2(fy, fx), math.hypot(fx, fy)),
            Moment("shuttle", moment),
        ),
        3,
    )
    loaded = run_model(scene, model, case)
    assert loaded.dx[-1] == pytest.approx(1.0, rel=1e-7)
    assert loaded.dy[-1] == pytest.approx(driven.dy[-1], abs=1e-7)
    assert loaded.rotation[-1] == pytest.approx(driven.rotation[-1], abs=1e-9)


@pytest.mark.parametrize("model", ["beam:40", "continuum:0"])
def test_a_prescribed_rotation_is_held_by_a_pure_moment(model):
    # a cantilever whose tip is turned 1 rad with its position free: the drive applies a
    # pure end moment, which bends the flexure to a circle, M = EI theta / L (elastica)
    text = """
name = "cantilever"
[material]
youngs_modulus = 200000.0
poisson_ratio = 0.3
[section]
depth = 5.0
thickness = 0.5
[ground]
name = "g"
points = [[0.0, 0.0]]
[target]
body = "tip"
point = [40.0, 0.0]
[[flexures]]
name = "leaf"
bodies = ["g", "tip"]
shape = "segment"
start = [0.0, 0.0]
end = [40.0, 0.0]
[[load_cases]]
name = "turn"
kind = "displacement"
rotation_deg = 57.29577951308232
"""
    scene = parse_scene(tomllib.loads(text), "<cantilever>")
    lp = run_model(scene, model, "turn", levels=5)
    ei = 200000.0 * 5.0 * 0.5**3 / 12.0
    fx, fy, moment = lp.drive_reactions[-1]
    assert lp.rotation[-1] == pytest.approx(1.0, rel=1e-9)
    assert lp.load_unit == "rad" and lp.load[-1] == pytest.approx(1.0)
    # the continuum's bending stiffness is plane stress's to its mesh (measured 0.05 %)
    assert moment == pytest.approx(ei / 40.0, rel=1e-6 if model.startswith("beam") else 2e-3)
    assert math.hypot(fx, fy) < 1e-8 * ei / 40.0**2
    # the circle: tip at (L sin 1, L (1 - cos 1)) for an inextensible leaf
    assert lp.dx[-1] == pytest.approx(40.0 * math.sin(1.0) - 40.0, abs=2e-3)
    assert lp.dy[-1] == pytest.approx(40.0 * (1.0 - math.cos(1.0)), abs=2e-3)


def test_a_drive_in_a_turned_frame_is_the_rotated_problem():
    # the guide and its drive rotated together by 30 degrees: the same reaction, rotated
    scene = guide()
    angle, shift = math.radians(30.0), np.array([5.0, -2.0])
    turned = scene.mechanism.transformed(angle, shift)
    case = scene.load_case("drive")
    moved = case.transformed(angle, shift)
    spec = parse_model("beam:20")
    here = spec.model_family.trace(scene.mechanism, spec, case, levels=3)
    there = spec.model_family.trace(turned, spec, moved, levels=3)
    c, s = math.cos(angle), math.sin(angle)
    fx, fy, m = here.drive_reactions[-1]
    np.testing.assert_allclose(
        there.drive_reactions[-1], [c * fx - s * fy, s * fx + c * fy, m], atol=1e-9
    )


def test_drive_tangent_matches_finite_differences():
    scene = guide()
    drive = Displacement("shuttle", np.array([10.0, 50.0]), 1.0, None, 0.3, 0.4)
    conn = DriveConnector(drive, scene.mechanism)
    rng = np.random.default_rng(5)
    pose_g = np.zeros(3)
    pose_b = np.array([*(scene.mechanism.bodies["shuttle"].reference + rng.normal(0, 1, 2)), 0.7])
    mu = rng.normal(0, 1.0, 2)
    eg, eh, asym = fd_check(conn, pose_g, pose_b, mu)
    assert eg < 1e-7 and eh < 1e-7 and asym == 0.0


def test_batch_of_driven_copies_equals_their_solo_runs():
    scene = guide()
    case = scene.load_case("slide")
    spec = parse_model("dcmm:2")
    paths = run_batch([scene.mechanism] * 3, spec, [case] * 3)
    solo = spec.model_family.trace(scene.mechanism, spec, case)
    for path in paths:
        assert path.drive_reactions == solo.drive_reactions and path.dx == solo.dx


def test_the_linear_response_reaction_is_linear():
    lp = run_model(guide(), "ee", "slide", levels=5)
    forces = np.asarray(lp.drive_reactions)[:, 0]
    np.testing.assert_allclose(forces, forces[-1] * np.linspace(0, 1, 5), rtol=1e-12)


@pytest.mark.parametrize(
    "change, field",
    [
        ({"value": 1.0}, "load_cases.slide.value"),
        ({"dx": None}, "load_cases.slide.dx"),
        ({"dx": 2e6}, "load_cases.slide.dx"),
        ({"rotation_deg": 1e5}, "load_cases.slide.rotation_deg"),
        ({"body": "g", "point": [0.0, 0.0]}, "load_cases.slide.body"),
        ({"body": "nowhere", "point": [0.0, 0.0]}, "load_cases.slide.body"),
        ({"body": "g"}, "load_cases.slide.point"),
    ],
)
def test_bad_displacements_name_the_field(change, field):
    data = tomllib.loads(GUIDE)
    entry = data["load_cases"][1]
    for key, value in change.items():
        if value is None:
            entry.pop(key)
        else:
            entry[key] = value
    with pytest.raises(SceneError) as info:
        parse_scene(data, "<guide>")
    assert info.value.field == field


def test_drive_fields_on_a_force_and_two_drives_are_refused():
    data = tomllib.loads(GUIDE)
    force = {"name": "f", "kind": "force", "value": 1.0, "angle_deg": 0.0, "dx": 1.0}
    data["load_cases"].append(force)
    with pytest.raises(SceneError, match="belongs to kind = 'displacement'") as info:
        parse_scene(data, "<guide>")
    assert info.value.field == "load_cases.f.dx"
    data = tomllib.loads(GUIDE)
    two = {"kind": "displacement", "dx": 1.0}
    data["load_cases"].append({"name": "two", "loads": [two, copy.deepcopy(two)]})
    with pytest.raises(SceneError, match="one point at most") as info:
        parse_scene(data, "<guide>")
    assert info.value.field == "load_cases.two.loads"


def test_a_family_without_the_capability_is_refused_by_name():
    import dataclasses

    spec = parse_model("beam:4")
    family = dataclasses.replace(spec.model_family, capabilities=frozenset())
    case = guide().load_case("slide")
    with pytest.raises(SceneError, match="does not trace a prescribed motion"):
        family.trace(guide().mechanism, spec, case)


def test_a_system_without_its_drive_refuses_the_case():
    from flexval.reducedmodels import build_system

    system = build_system(guide().mechanism, parse_model("beam:4"))
    with pytest.raises(ValueError, match="built without its drive"):
        system.loads(guide().load_case("slide"))


def test_cli_prints_the_drive_reaction_and_refuses_buckle(tmp_path, capsys):
    path = tmp_path / "guide.toml"
    path.write_text(GUIDE)
    assert main(["run", str(path), "--model", "beam:20", "--load-case", "slide"]) == 0
    out = capsys.readouterr().out
    assert "drive reaction: Fx 2.73" in out and " mm " in out
    code = main(["buckle", str(path), "--model", "beam:20", "--load-case", "slide"])
    assert code == 2
    assert "prescribes a motion" in capsys.readouterr().err
    assert (
        main(["run", str(path), "--model", "beam:20", "--load-case", "slide", "--arclength"]) == 0
    )
    assert "drive reaction" in capsys.readouterr().out


def test_the_builtin_scenes_still_parse_without_drives():
    for name in ("open_chain", "closed_chain", "notch_fourbar"):
        scene = load_scene(name)
        assert all(case.drive is None for case in scene.load_cases)
        assert scene.mechanism.driven_by(scene.load_cases[0]) is scene.mechanism


def test_a_motion_the_model_holds_rigid_is_refused_before_tracing():
    # prbm's straight leaves are inextensible: holding dy as well as driving dx
    # over-constrains the shuttle (its tangent at rest has a zero eigenvalue: one negative
    # pivot short of its multipliers), and the pinned truss cannot move at all
    from flexval.reducedmodels import SolverError

    with pytest.raises(SolverError, match="prbm on load case 'drive': the prescribed") as info:
        run_model(guide(), "prbm", "drive")
    assert info.value.load_factor == 0.0 and "holds rigid" in str(info.value)
    with pytest.raises(SolverError, match="holds rigid"):
        run_model(load_scene("bistable_truss"), "prbm", "snap")
    # the same drive without dy is well posed in the PRBM
    assert run_model(guide(), "prbm", "slide", levels=2).converged


def test_a_drives_free_components_are_its_parasitic_motion():
    from flexval.validation.studies.parasitic import parasitic_components

    scene = guide()
    target = (scene.mechanism.target_body, scene.mechanism.target_point)
    slide, held = scene.load_case("slide"), scene.load_case("drive")
    assert [n for n, _ in parasitic_components(slide, target)] == ["dy", "rotation"]
    assert [n for n, _ in parasitic_components(held, target)] == ["rotation"]
    elsewhere = (scene.mechanism.target_body, np.array([0.0, 50.0]))
    assert parasitic_components(slide, elsewhere) == []  # another point: not the target's


def test_reaction_errors_and_zero_crossings():
    from flexval.validation.report.drivereaction import reaction_errors, zero_crossings

    mech, load = von_mises_truss()
    drive = Displacement("c", mech.target_point, dy=-50.0)
    case = LoadCase("snap", (drive,), 26)
    ref = run_reduced(mech, parse_model("beam:4"), case)
    (same,) = reaction_errors(ref, ref, drive)
    assert same["component"] == "Fv" and same["end"] == 0.0 and same["path"] == 0.0
    scaled = copy.deepcopy(ref)
    scaled.drive_reactions = [[1.1 * x for x in row] for row in ref.drive_reactions]
    (off,) = reaction_errors(scaled, ref, drive)
    assert off["end"] == pytest.approx(10.0) and off["path"] == pytest.approx(10.0)
    # the truss's force vanishes with both bars level (20 mm) and mirrored (40 mm), levels
    # of this path: exact crossings there
    fv = np.asarray(ref.drive_reactions)[:, 1]
    np.testing.assert_allclose(zero_crossings(ref, fv), [-20.0, -40.0], atol=1e-9)


def test_a_driven_system_holds_its_point_under_a_case_without_motion():
    # the drive's multipliers carry load only for a case that prescribes the motion: a
    # force case traced on the same System finds the driven point held at rest
    from flexval.reducedmodels import build_system, solve_path

    scene = guide()
    driven = scene.mechanism.driven_by(scene.load_case("slide"))
    system = build_system(driven, parse_model("beam:10"))
    push = LoadCase("push", (Force("shuttle", scene.mechanism.target_point, 0.0, 5.0),), 3)
    lp = solve_path(system, push)
    assert abs(lp.dx[-1]) < 1e-9 and lp.drive_reactions is None


def test_the_load_axis_of_a_drive_is_its_first_moving_component():
    # a component held at 0 moves nothing: the load factor's axis (tables, plots, the
    # zero crossings) is the first component that moves, whatever the fields' order
    point = np.zeros(2)
    held_then_moved = Displacement("b", point, dx=0.0, dy=-2.0, rotation=0.0)
    assert held_then_moved.axis == (1, -2.0)
    case = LoadCase("c", (held_then_moved,))
    assert (case.magnitude, case.unit) == (-2.0, "mm")
    turned = Displacement("b", point, dx=0.0, rotation=0.5)
    assert (turned.value, turned.unit) == (0.5, "rad")
    held = Displacement("b", point, dx=0.0, dy=0.0)
    assert held.axis == (0, 0.0)
