"""Pins (revolute joints as Lagrange-multiplier constraints): exact tangent,
exact truss answers, closed chains whose reactions balance, the [[pins]]
scene table and its validation."""

import copy
import math
import tomllib

import numpy as np
import pytest
from builders import fd_check

from flexval.geometry import Force, LoadCase, Material, SceneError, Section, Segment, load_scene
from flexval.geometry.mechanism import FlexureSpec, PinSpec, assemble
from flexval.geometry.scene import parse_scene
from flexval.reducedmodels import build_system, run_reduced, solve_path
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.joints import PinConnector
from flexval.validation.cli import main

FOURBAR = """
# A compliant four-bar: two rigid cranks pinned to the ground, joined by an arc.
name = "pinned_fourbar"
[material]
youngs_modulus = 2200.0
poisson_ratio = 0.35
[section]
depth = 5.0
thickness = 1.2
[ground]
name = "g"
points = [[0.0, 0.0], [100.0, 0.0]]
[target]
body = "a"
point = [10.0, 60.0]
[[flexures]]
name = "coupler"
bodies = ["a", "b"]
center = [50.0, 40.0]
radius = 44.721359549995796       # through (10, 60) and (90, 60)
axis_deg = 90.0
width_deg = 126.86989764584402
[[pins]]
name = "pa"
bodies = ["g", "a"]
point = [0.0, 0.0]
[[pins]]
name = "pb"
bodies = ["b", "g"]
point = [100.0, 0.0]
[[load_cases]]
name = "fx"
kind = "force"
point = [10.0, 60.0]
angle_deg = 0.0
value = 1.0
[[load_cases]]
name = "mb"
kind = "moment"
body = "b"
value = 100.0
"""


def fourbar_scene():
    return parse_scene(tomllib.loads(FOURBAR), "<fourbar>")


def von_mises_truss(a: float = 100.0, h0: float = 20.0, E: float = 1000.0, t: float = 20.0):
    """Two straight bars pinned to the ground at (-a, 0), (a, 0) and to each other at (0, h0).

    Each bar is a flexure between two bodies that are held only by pins, so
    its end moments vanish and it carries pure axial force: an exact truss.
    With t = 20 mm the bars' Euler load pi^2 EI / L^2 (~630 N) stays well above
    their axial force below the snap (~190 N): the symmetric truss branch is
    stable, as the core's stability check requires.
    Returns the mechanism and the exact load P(w) (N, downward) at apex
    deflection w (mm): P = 2 EA h (1/L - 1/L0), h = h0 - w, L = sqrt(a^2 + h^2).
    """
    specs = [
        FlexureSpec("b1", Segment((-a, 0.0), (0.0, h0)), ("l", "c"), Section(1.0, t)),
        FlexureSpec("b2", Segment((0.0, h0), (a, 0.0)), ("d", "r"), Section(1.0, t)),
    ]
    pins = [
        PinSpec("pl", ("g", "l"), (-a, 0.0)),
        PinSpec("apex", ("c", "d"), (0.0, h0)),
        PinSpec("pr", ("r", "g"), (a, 0.0)),
    ]
    mech = assemble(
        specs,
        "g",
        np.array([[-a, 0.0], [a, 0.0]]),
        Material(E, 0.3),
        "c",
        np.array([0.0, h0]),
        pin_specs=pins,
    )
    EA, L0 = E * t, math.hypot(a, h0)

    def load(w):
        h = h0 - np.asarray(w, float)
        return 2.0 * EA * h * (1.0 / np.hypot(a, h) - 1.0 / L0)

    return mech, load


def test_pin_tangent_matches_finite_differences():
    mech = fourbar_scene().mechanism
    conn = PinConnector("p", "a", "b", np.array([40.0, 30.0]), mech)
    rng = np.random.default_rng(3)
    pose_a = np.array([*mech.bodies["a"].reference + rng.normal(0, 2.0, 2), 0.8])
    pose_b = np.array([*mech.bodies["b"].reference + rng.normal(0, 2.0, 2), -2.3])
    mu = rng.normal(0, 1.0, 2)
    eg, eh, asym = fd_check(conn, pose_a, pose_b, mu)
    # central differences, h = 1e-6 on coordinates of O(100): truncation ~ h^2 |x'''| and
    # round-off ~ eps |E| / h relative to gradients of O(s |mu| 100)
    assert eg < 1e-7 and eh < 1e-7 and asym == 0.0
    # the theta-theta entries are the only second derivatives: present and nonzero
    _, _, H = conn.evaluate(pose_a, pose_b, mu)
    assert H[2, 2] != 0.0 and H[5, 5] != 0.0 and np.all(H[6:, 6:] == 0.0)


def test_pin_constraint_and_forces_are_the_gradient():
    mech = fourbar_scene().mechanism
    conn = PinConnector("p", "g", "a", np.array([0.0, 0.0]), mech, stiffness=7.0)
    pose_g = np.array([0.0, 0.0, 0.0])
    pose_a = np.array([10.5, 60.2, 0.1])  # reference of a is (10, 60)
    mu = np.array([0.3, -0.2])
    _, g, _ = conn.evaluate(pose_g, pose_a, mu)
    xa = pose_a[:2] + np.array(
        [[math.cos(0.1), -math.sin(0.1)], [math.sin(0.1), math.cos(0.1)]]
    ) @ np.array([-10.0, -60.0])
    # gap = difference of O(60 mm) terms: round-off of order 1e-14 * 60 * s
    np.testing.assert_allclose(g[6:], 7.0 * (0.0 - xa), rtol=0, atol=1e-12 * 7.0 * 60.0)
    np.testing.assert_allclose(conn.force_on_b(mu), 7.0 * mu)
    assert list(conn.internal_is_rotation()) == [False, False]


@pytest.mark.parametrize("model", ["beam:1", "beam:4", "dcmm:1"])
def test_pinned_truss_is_exact_below_the_limit_load(model):
    mech, load = von_mises_truss()
    w = np.linspace(0.0, 40.0, 40001)
    p_max = load(w).max()
    case = LoadCase("P", (Force("c", mech.target_point, -math.pi / 2, 0.9 * p_max),), 6)
    lp = run_reduced(mech, parse_model(model), case)
    # pinned bars carry axial force only: the beam and the DCMM segment (axial
    # compliance L/EA) are exact; the residual is the solver tolerance (1e-10 of the load)
    np.testing.assert_allclose(load(-np.array(lp.dy)), lp.load, rtol=0, atol=1e-8 * p_max)
    np.testing.assert_allclose(lp.dx, 0.0, atol=1e-9)


@pytest.mark.parametrize("model", ["dcmm:2", "beam:10", "beam:40", "ee"])  # beam:40: sparse
def test_pinned_four_bar_solves_and_reactions_balance(model):
    scene = fourbar_scene()
    for case in scene.load_cases:
        lp = run_reduced(scene.mechanism, parse_model(model), case, record_reactions=model != "ee")
        assert lp.converged and np.all(np.isfinite(lp.dx + lp.dy + lp.rotation))
        if model == "ee":
            continue
        comp = case.components[0]
        for k, lam in enumerate(case.factors()):
            R = np.array(lp.reactions[k])
            if isinstance(comp, Force):
                F = lam * comp.vector
                p = scene.mechanism.target_point + [lp.dx[k], lp.dy[k]]  # ground ref is (0, 0)
                moment = p[0] * F[1] - p[1] * F[0]
            else:
                F, moment = np.zeros(2), lam * comp.value
            # equilibrium of the whole mechanism; 1e-8 of the load covers the solver's tolerance
            np.testing.assert_allclose(R[:2] + F, 0.0, atol=1e-8)
            assert R[2] + moment == pytest.approx(0.0, abs=1e-8 * 100)


def test_pins_stay_closed_along_the_path():
    scene = fourbar_scene()
    system = build_system(scene.mechanism, parse_model("beam:10"))
    lp = solve_path(system, scene.load_case("fx"), record_poses=True)
    for pin in scene.mechanism.pins:
        pts = []
        for b in pin.bodies:
            ref = scene.mechanism.bodies[b].reference
            for x, y, th in lp.poses[b]:
                c, s = math.cos(th), math.sin(th)
                d = pin.point - ref
                pts.append([x + c * d[0] - s * d[1], y + s * d[0] + c * d[1]])
        pts = np.array(pts).reshape(2, -1, 2)
        # the gap is a residual: 1e-10 of the load over the multiplier scale EI/L^3
        assert np.abs(pts[0] - pts[1]).max() < 1e-9 * scene.mechanism.size()


def test_ee_with_pins_is_the_small_load_limit():
    scene = fourbar_scene()
    case = scene.load_case("fx")
    ee = run_reduced(scene.mechanism, parse_model("ee"), case)
    small = LoadCase("fx", (Force("a", case.components[0].point, 0.0, 1e-4),), 3)
    lp = run_reduced(scene.mechanism, parse_model("dcmm:1"), small)
    # geometric nonlinearity is first order in the load: 1e-4 of a load that turns the
    # crank by 0.2 rad leaves a relative difference of order 1e-4
    assert lp.dx[-1] / 1e-4 == pytest.approx(ee.dx[-1], rel=1e-3)


def test_rigid_motion_moves_the_pins():
    scene = fourbar_scene()
    case = scene.load_case("fx")
    angle, shift = -0.7, np.array([12.0, -30.0])
    base = run_reduced(scene.mechanism, parse_model("dcmm:2"), case)
    moved_mech = scene.mechanism.transformed(angle, shift)
    R = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    np.testing.assert_allclose(moved_mech.pins[0].point, R @ [0.0, 0.0] + shift)
    np.testing.assert_allclose(moved_mech.pins[1].point, R @ [100.0, 0.0] + shift)
    moved = run_reduced(moved_mech, parse_model("dcmm:2"), case.transformed(angle, shift))
    np.testing.assert_allclose(
        np.array([moved.dx, moved.dy]), R @ np.array([base.dx, base.dy]), atol=1e-9 * 15
    )
    np.testing.assert_allclose(moved.rotation, base.rotation, atol=1e-10)


def test_scene_pins_make_bodies_and_points():
    mech = fourbar_scene().mechanism
    assert [p.name for p in mech.pins] == ["pa", "pb"]
    # flexure ends first (the body frame's origin), then pin points
    np.testing.assert_allclose(mech.bodies["a"].points, [[10.0, 60.0], [0.0, 0.0]])
    np.testing.assert_allclose(mech.bodies["b"].points, [[90.0, 60.0], [100.0, 0.0]])
    assert mech.flexures[0].start_body == "b"
    # no pins: nothing changes for existing scenes
    assert load_scene("open_chain").mechanism.pins == ()


def test_cli_runs_a_pinned_scene(tmp_path, capsys):
    path = tmp_path / "fourbar.toml"
    path.write_text(FOURBAR)
    out = tmp_path / "out.json"
    assert main(["run", str(path), "--model", "dcmm:2", "--json", str(out)]) == 0
    assert out.exists() and "dcmm:2" in capsys.readouterr().out


def _bad(mutate) -> SceneError:
    data = tomllib.loads(FOURBAR)
    mutate(data)
    with pytest.raises(SceneError) as info:
        parse_scene(copy.deepcopy(data), "bad.toml")
    return info.value


def _set(path, value):
    def mutate(d):
        x = d
        for k in path[:-1]:
            x = x[k]
        if value is _DELETE:
            del x[path[-1]]
        else:
            x[path[-1]] = value

    return mutate


_DELETE = object()


@pytest.mark.parametrize(
    "path,value,field",
    [
        (("pins",), {"name": "p"}, "pins"),
        (("pins", 0), "pa", "pins[0]"),
        (("pins", 0, "name"), _DELETE, "pins[0].name"),
        (("pins", 0, "name"), True, "pins[0].name"),
        (("pins", 0, "bodies"), "g", "pins.pa.bodies"),
        (("pins", 0, "bodies"), ["g"], "pins.pa.bodies"),
        (("pins", 0, "bodies"), ["a", "a"], "pins.pa.bodies"),
        (("pins", 0, "bodies"), ["g", 1.5], "pins.pa.bodies.b"),
        (("pins", 0, "point"), _DELETE, "pins.pa.point"),
        (("pins", 0, "point"), [0.0], "pins.pa.point"),
        (("pins", 0, "point"), [0.0, float("nan")], "pins.pa.point[1]"),
        (("pins", 0, "point"), [0.0, 1e300], "pins.pa.point[1]"),
        (("pins", 0, "radius"), 3.0, "pins.pa.radius"),
        (("pins", 1, "name"), "pa", "pins.name"),
        (("pins", 1, "name"), "coupler", "pins.name"),
        # a misspelt body becomes a new body held by this pin only
        (("pins", 1, "bodies"), ["bb", "g"], "pins.pb.bodies"),
    ],
)
def test_bad_pins_name_the_field(path, value, field):
    err = _bad(_set(path, value))
    assert err.field == field, str(err)
    assert "bad.toml" in str(err)


def test_pins_count_as_connections():
    def drop_pb_and_moment(d):
        del d["pins"][1], d["load_cases"][1]

    def drop_pb_its_ground_point_and_moment(d):
        drop_pb_and_moment(d)
        del d["ground"]["points"][1]

    # without pin pb, a and b (welded by the coupler) turn freely about pin pa
    err = _bad(drop_pb_its_ground_point_and_moment)
    assert err.field == "pins" and "['a', 'b'] can move" in str(err)
    # ... and the ground point (100, 0) that held pb now holds nothing
    err = _bad(drop_pb_and_moment)
    assert err.field == "ground.points" and "[100.0, 0.0]" in str(err)
    # without both pins nothing reaches a and b from the ground
    err = _bad(lambda d: d.pop("pins"))
    assert err.field == "ground"


def test_cli_bad_pin_exit_code_2_and_nothing_written(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(FOURBAR.replace('bodies = ["b", "g"]', 'bodies = ["b", "b"]'))
    out = tmp_path / "out.json"
    assert main(["run", str(path), "--model", "dcmm:1", "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert "pins.pb.bodies" in err and "Traceback" not in err
    assert not out.exists()


def test_linear_response_numbers_and_assembles_as_the_system():
    """ee's linear response (flexval.reducedmodels.models.linear_response, built without a System)
    on the pinned four-bar with gravity: multipliers after the poses, weights as dead
    loads. Its levels must be the System's own K0^-1 (w + lambda f) at rest, from
    System.assemble and Loads.vector, carried to the target point (J dq, rotations
    linearised); both are one LU of the same matrix, so round-off only (1e-10)."""
    import dataclasses

    from flexval.geometry.inertia import MassData

    scene = fourbar_scene()
    mech = dataclasses.replace(
        scene.mechanism, inertia=MassData(density=1.2e-9, gravity=np.array([0.0, -9810.0]))
    )
    case = scene.load_case("fx")
    lp = run_reduced(mech, parse_model("ee"), case)
    system = build_system(mech, parse_model("ee"))
    assert system.n_multipliers == 4 and lp.stats["unknowns"] == system.n_dofs
    q0, loads = system.initial_state(), system.loads(case)
    _, g0, K = system.assemble(q0, loads, 0.0)
    unit, dead = K.solve(loads.vector(q0)), K.solve(-g0)
    dofs = system.pose_dofs(mech.target_body)
    rx, ry = mech.target_point - system.reference[mech.target_body]
    for lam, dx, dy, rot in zip(case.factors(), lp.dx, lp.dy, lp.rotation):
        d = (dead + lam * unit)[dofs]
        scale = np.abs(unit[dofs]).max()
        assert abs(dx - (d[0] - ry * d[2])) <= 1e-10 * scale * max(abs(rx), abs(ry))
        assert abs(dy - (d[1] + rx * d[2])) <= 1e-10 * scale * max(abs(rx), abs(ry))
        assert abs(rot - d[2]) <= 1e-10 * scale
    assert abs(lp.dy[0]) > 0.0  # the weights alone move it at zero load
