"""Mass data in scenes (flexval.geometry.inertia) and gravity as dead loads
(flexval.reducedmodels.core.inertia)."""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest

from flexval.geometry import Arc, MassData, RigidMass, SceneError, Segment
from flexval.geometry.inertia import polygon_properties
from flexval.geometry.scene import parse_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.inertia import MassModel, Weighted, chain_mass_points
from flexval.reducedmodels.models import build_system, run_reduced
from tests.builders import cantilever, fd_check, tip_moment

SCENE = """
name = "mass"
[material]
youngs_modulus = 2100.0
poisson_ratio = 0.35
density = 1.24e-9
[section]
depth = 1.0
thickness = 0.1
[gravity]
acceleration = [0.0, -9810.0]
[ground]
name = "1"
points = [[0.0, 0.0]]
[target]
body = "2"
point = [10.0, 0.0]
[[flexures]]
name = "s"
bodies = ["1", "2"]
shape = "segment"
start = [0.0, 0.0]
end = [10.0, 0.0]
[[bodies]]
name = "2"
outline = [[10.0, -0.5], [12.0, -0.5], [12.0, 0.5], [10.0, 0.5]]
depth = 2.0
[[load_cases]]
name = "m"
kind = "moment"
value = 1.0e-4
"""


def scene_with(edit=None):
    data = tomllib.loads(SCENE)
    if edit is not None:
        edit(data)
    return parse_scene(data, "<test>")


def test_rectangle_outline_gives_mass_centre_and_inertia():
    """A 2 x 1 mm rectangle, 2 mm deep: m = rho b A, centre at its middle,
    J = m (w^2 + h^2) / 12 about it; either orientation."""
    mass = scene_with().mechanism.inertia.bodies["2"]
    m = 1.24e-9 * 2.0 * 2.0
    assert mass.mass == pytest.approx(m, rel=1e-14)
    np.testing.assert_allclose(mass.center_of_mass, [11.0, 0.0], atol=1e-14)
    assert mass.inertia == pytest.approx(m * (4.0 + 1.0) / 12.0, rel=1e-13)
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    for outline in (square, square[::-1]):
        area, centre, polar = polygon_properties(outline)
        assert (area, polar) == pytest.approx((1.0, 1.0 / 6.0), rel=1e-14)
        np.testing.assert_allclose(centre, [0.5, 0.5])


@pytest.mark.parametrize(
    "edit, field",
    [
        (lambda d: d["material"].update(density=1240.0), "material.density"),
        (lambda d: d["material"].pop("density"), "bodies.2.outline"),
        (lambda d: d["bodies"][0].update(mass=1e-6), "bodies.2.mass"),
        (
            lambda d: d["bodies"].__setitem__(0, {"name": "2", "mass": 1e-6, "inertia": 1e-6}),
            "bodies.2.center_of_mass",
        ),
        (
            lambda d: d["bodies"].__setitem__(
                0, {"name": "2", "mass": -1.0, "inertia": 1e-6, "center_of_mass": [0.0, 0.0]}
            ),
            "bodies.2.mass",
        ),
        (
            lambda d: d["bodies"].__setitem__(
                0, {"name": "1", "mass": 1.0, "inertia": 1e-6, "center_of_mass": [0.0, 0.0]}
            ),
            "bodies.1.mass",
        ),
        (
            lambda d: d["bodies"][0].update(outline=[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
            "bodies.2.outline",
        ),
        (lambda d: d["gravity"].update(acceleration=[0.0]), "gravity.acceleration"),
        (lambda d: d["gravity"].update(g=1.0), "gravity.g"),
    ],
)
def test_bad_mass_data_names_the_field(edit, field):
    with pytest.raises(SceneError) as info:
        scene_with(edit)
    assert info.value.field == field


def test_weighted_connector_derivatives():
    """Energy, gradient and Hessian of a beam with its own and a body's weight agree
    (central differences; the rotated offsets make the theta terms nonlinear)."""
    mech = scene_with().mechanism
    system = build_system(mech, parse_model("beam:3"))
    connector = system.connectors[0]
    assert isinstance(connector, Weighted)
    pose_b = np.array([10.2, -0.3, 0.4])
    internal = system.initial_state()[3:] + 0.05
    eg, eh, sym = fd_check(connector, np.zeros(3), pose_b, internal)
    assert eg < 1e-7 and eh < 1e-6 and sym < 1e-12


@pytest.mark.parametrize("model, rtol", [("beam:40", 2e-3), ("continuum:0", 2e-3)])
def test_self_weight_sag_of_a_cantilever(model, rtol):
    """Tip deflection under the beam's own weight q = rho A g: q L^4 / (8 EI) (small:
    deflection/L ~ 1e-3, so the nonlinear correction is ~1e-6). The lumped nodal
    weights converge at O(1/N^2) (measured 0.07 % at N = 40); the continuum adds its
    shear deflection (h/L)^2 terms (measured 0.05 %); bound 0.2 %."""
    L, b, h, E, rho, g = 10.0, 1.0, 0.1, 2100.0, 1.24e-9, 9810.0
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), E=E, b=b, h=h, nu=0.3)
    mech = dataclasses.replace(mech, inertia=MassData(density=rho, gravity=np.array([0.0, -g])))
    from flexval.geometry import Scene
    from flexval.validation.run import run_model

    scene = Scene("sag", "", mech, (tip_moment(0.0, levels=2),), (), frozenset(), "<sag>")
    lp = run_model(scene, parse_model(model), scene.load_cases[0])
    expected = -rho * b * h * g * L**4 / (8.0 * E * b * h**3 / 12.0)
    assert lp.dy[0] == pytest.approx(expected, rel=rtol)


def test_body_weight_at_an_offset_centre():
    """A massless beam carrying a body whose centre of mass is d beyond the tip: the tip
    sees P = m g and M = m g d; deflection P L^3/3EI + M L^2/2EI. A 1 g body: deflection
    2.4e-3 L, so the geometric nonlinearity is of order 1e-5 and the beam elements are
    exact for end loads; bound 1e-4."""
    L, E, m, g, d = 10.0, 2100.0, 1e-9, 9810.0, 2.0
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), E=E)
    mech = dataclasses.replace(
        mech,
        inertia=MassData(
            gravity=np.array([0.0, -g]), bodies={"t": RigidMass(m, 1e-6, np.array([L + d, 0.0]))}
        ),
    )
    EI = E * 1.0 * 0.1**3 / 12.0
    lp = run_reduced(mech, parse_model("beam:40"), tip_moment(0.0, levels=2))
    P = m * g
    expected = -(P * L**3 / (3 * EI) + P * d * L**2 / (2 * EI))
    assert abs(expected) / L < 3e-3
    assert lp.dy[0] == pytest.approx(expected, rel=1e-4)


def test_lumped_masses_add_up_to_the_flexure():
    """HRZ lumping: total mass rho A L and the first moment of a uniform chain."""
    pts = chain_mass_points(
        [[0, 1, 2], [6, 7, 8], [9, 10, 11], [3, 4, 5]], np.zeros((4, 2)), np.full(3, 2.0), 0.5
    )
    assert pts.mass.sum() == pytest.approx(3.0)
    np.testing.assert_allclose(pts.mass, [0.5, 1.0, 1.0, 0.5])
    np.testing.assert_allclose(pts.rotary, np.array([1, 2, 2, 1]) * 1.0 * 4.0 / 78.0)


def test_mass_matrix_is_the_rigid_body_kinetic_energy():
    """For a body's pose velocity v, 1/2 v^T M v equals 1/2 m |v_G|^2 + 1/2 J_G omega^2
    with v_G the velocity of the centre of mass, at a turned pose."""
    mech = scene_with().mechanism
    mech = dataclasses.replace(mech, inertia=dataclasses.replace(mech.inertia, density=None))
    system = build_system(mech, parse_model("dcmm:1"))
    body = mech.inertia.bodies["2"]
    q = np.array([10.1, 0.2, 0.7])
    v = np.array([3.0, -1.0, 5.0])
    M = MassModel(system).matrix(q).toarray()
    rel = body.center_of_mass - mech.bodies["2"].reference
    c, s = math.cos(q[2]), math.sin(q[2])
    r = np.array([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]])
    v_g = v[:2] + v[2] * np.array([-r[1], r[0]])
    assert 0.5 * v @ M @ v == pytest.approx(
        0.5 * body.mass * v_g @ v_g + 0.5 * body.inertia * v[2] ** 2, rel=1e-13
    )


def test_cli_modes_json_and_refusal(tmp_path):
    from flexval.validation.cli import main

    scene = tmp_path / "mass.toml"
    scene.write_text(SCENE, encoding="utf-8")
    out = tmp_path / "modes.json"
    assert (
        main(["modes", str(scene), "--model", "beam:10", "--count", "2", "--json", str(out)]) == 0
    )
    record = json.loads(out.read_text())
    assert len(record["frequencies_hz"]) == 2 and record["frequencies_hz"][0] > 0.0
    assert main(["modes", "open_chain", "--model", "prbm"]) == 2
    assert main(["modes", str(scene), "--model", "beam:10", "--at", "2"]) == 2
    assert main(["modes", "open_chain", "--model", "dcmm:2", "--density", "1.24e-9"]) == 0
    assert main(["modes", "open_chain", "--model", "dcmm:2", "--density", "1240"]) == 2


def test_ee_carries_the_weights_like_its_nonlinear_parent():
    """ee is dcmm:1 linearised at rest, weights included (they act before the load case
    in every static run). On a PLA cantilever arc (size 3 mm) sagging by 3e-4 mm under
    its own weight (the half of the flexure next to the tip, rigid on it), plus a small
    tip moment, the two differ only by the geometric
    nonlinearity, measured 2e-4 relative; ee without the weights misses the whole
    sag at the first level (a relative difference of 1)."""
    from flexval.geometry import Scene
    from flexval.validation.run import run_model

    mech = cantilever(Arc((0.0, 0.0), 3.0, 0.4, 2.0), E=2100.0, b=1.0, h=0.1)
    mech = dataclasses.replace(
        mech, inertia=MassData(density=1.24e-9, gravity=np.array([0.0, -9810.0]))
    )
    scene = Scene("sag", "", mech, (tip_moment(1e-5, levels=3),), (), frozenset(), "<sag>")
    linear, nonlinear = (
        run_model(scene, parse_model(m), scene.load_cases[0]) for m in ("ee", "dcmm:1")
    )
    for k in range(3):
        d_lin = np.array([linear.dx[k], linear.dy[k]])
        d_non = np.array([nonlinear.dx[k], nonlinear.dy[k]])
        assert np.linalg.norm(d_non) > 2e-4
        assert np.linalg.norm(d_lin - d_non) < 1e-3 * np.linalg.norm(d_non)
        assert linear.peak_stress and all(v[k] > 0 for v in linear.peak_stress.values())


ARC = Arc((0.0, 3.0), 3.0, math.radians(150.0), math.radians(240.0))
RHO = 1.24e-9


def arc_cantilever(**inertia):
    """A PLA cantilever arc of 240 deg (length 4 pi mm); ``inertia``: MassData fields."""
    return dataclasses.replace(cantilever(ARC, E=2100.0, b=1.0, h=0.1), inertia=MassData(**inertia))


def swept_inertia(u0: float, about: np.ndarray) -> float:
    """int rho A |x - about|^2 ds over the arc beyond arc length u0 (t mm^2), by a fine
    midpoint rule (4000 points: relative error ~1e-8), independent of the quadrature
    under test."""
    u = np.linspace(u0, ARC.length, 4001)
    mid = 0.5 * (u[1:] + u[:-1])
    return float(RHO * 0.1 * np.sum(np.diff(u) * ((ARC.point(mid) - about) ** 2).sum(axis=1)))


@pytest.mark.parametrize("model", ["dcmm:1", "dcmm:3", "prbm"])
def test_lumped_pieces_move_like_the_flexure_they_carry(model):
    """The moving bodies (and cut bodies) turning rigidly at omega = 1 rad/s about a point
    O: 1/2 v^T M v = 1/2 int rho A |x - O|^2 ds over the flexure they carry, i.e. beyond
    the ground's piece (dcmm:n: the first half sub-arc). The prbm's link l turns with
    body b about O, and link h (hinged on the ground at R_a) about R_a: its piece adds
    1/2 int rho A |x - R_a|^2 ds. Exact for rigid pieces of exact inertia; bound 1e-7 (the
    reference's midpoint rule). The moving mass is the flexure's beyond the ground's piece."""
    system = build_system(arc_cantilever(density=RHO), parse_model(model))
    connector = system.connectors[0]
    mass = MassModel(system)
    q = system.initial_state()
    about = np.array([1.0, -2.0])
    v = np.zeros(system.n_dofs)
    dofs = system.pose_dofs("t")
    v[dofs] = [-(q[dofs[1]] - about[1]), q[dofs[0]] - about[0], 1.0]
    if model == "prbm":  # both links turn too; the ground's end piece stays
        v[3:5] = 1.0
        start = connector._fractions[1] * ARC.length
        hinge = connector.joints[0]
        # link h turns about its hinge R_a on the ground, not about O: its piece's share
        link_h = swept_inertia(start, hinge) - swept_inertia(
            connector._fractions[2] * ARC.length, hinge
        )
        rest = swept_inertia(connector._fractions[2] * ARC.length, about)
        expected = 0.5 * (link_h + rest)
    else:
        n = int(model.split(":")[1])
        for k in range(n - 1):  # cut bodies turn with the rest
            v[3 + 3 * k : 6 + 3 * k] = [-(q[4 + 3 * k] - about[1]), q[3 + 3 * k] - about[0], 1.0]
        expected = 0.5 * swept_inertia(0.5 * ARC.length / n, about)
    assert mass.kinetic_energy(q, v) == pytest.approx(expected, rel=1e-7)
    assert mass.points.mass.sum() == pytest.approx(
        RHO
        * 0.1
        * ARC.length
        * (
            1.0
            - (0.0 if model == "prbm" else 0.5 / int(model[-1]))
            - (connector._fractions[1] if model == "prbm" else 0.0)
        ),
        rel=1e-12,
    )


def lagrange_convective(
    mass: MassModel, q: np.ndarray, v: np.ndarray, coords, h: float = 1e-6
) -> np.ndarray:
    """M'(q) v - 1/2 d(v^T M v)/dq by central differences of M(q), the gradient taken over
    ``coords`` only (M depends on no other coordinate)."""

    def matrix(x):
        return mass.matrix(x)

    rate = ((matrix(q + h * v) - matrix(q - h * v)) @ v) / (2 * h)
    grad = np.zeros_like(q)
    for k in coords:
        dq = np.zeros_like(q)
        dq[k] = h
        grad[k] = (v @ (matrix(q + dq) @ v) - v @ (matrix(q - dq) @ v)) / (2 * h)
    return rate - 0.5 * grad


@pytest.mark.parametrize("model", ["prbm", "dcmm:2", "continuum:0"])
def test_convective_forces_are_the_lagrange_terms(model):
    """c(q, v) = M'(q) v - 1/2 d(v^T M v)/dq at a turned state with every coordinate
    moving: mass points on links (prbm), on bodies (dcmm), and the continuum's
    consistent mass with its end faces. M depends only on the angles (bodies' and links');
    central differences h = 1e-6: measured agreement 1e-9 relative; bound 1e-6."""
    mech = arc_cantilever(density=RHO, bodies={"t": RigidMass(1e-7, 1e-6, np.array([0.5, 0.5]))})
    if model.startswith("continuum"):
        from flexval.validation.continuum.run import build_system as continuum_system

        system = continuum_system(mech, 0)
    else:
        system = build_system(mech, parse_model(model))
    mass = MassModel(system)
    rng = np.random.default_rng(3)
    q = system.initial_state() + 0.3 * rng.standard_normal(system.n_dofs) * system.is_rotation
    v = rng.standard_normal(system.n_dofs) * 20.0
    angles = np.flatnonzero(system.is_rotation)
    expected = lagrange_convective(mass, q, v, angles)
    assert np.abs(mass.convective(q, v) - expected).max() < 1e-6 * np.abs(expected).max()


def test_weights_on_links_derivatives():
    """The PRBM with its links' weights (pieces on hinged links) and a body's weight:
    energy, gradient and Hessian agree (central differences) at a turned state."""
    mech = arc_cantilever(
        density=RHO,
        gravity=np.array([3000.0, -9810.0]),
        bodies={"t": RigidMass(1e-7, 1e-6, np.array([0.5, 0.5]))},
    )
    connector = build_system(mech, parse_model("prbm")).connectors[0]
    assert isinstance(connector, Weighted)
    pose_b = np.array([0.3, -0.2, 0.4])
    eg, eh, sym = fd_check(
        connector,
        np.zeros(3),
        pose_b + [*ARC.end_points[1], 0.0],
        np.array([0.2, -0.3, 1e-3, -2e-3]),
    )
    assert eg < 1e-7 and eh < 1e-6 and sym < 1e-12
