"""Mass data in scenes (geometry.inertia) and gravity as dead loads (reducedmodels.inertia)."""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest

from geometry import Arc, MassData, RigidMass, SceneError, Segment
from reducedmodels.catalogue import parse_model
from geometry.inertia import polygon_properties
from geometry.scene import parse_scene
from reducedmodels.inertia import MassModel, Weighted, chain_mass_points
from reducedmodels.models import build_system, run_reduced
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


@pytest.mark.parametrize("edit, field", [
    (lambda d: d["material"].update(density=1240.0), "material.density"),
    (lambda d: d["material"].pop("density"), "bodies.2.outline"),
    (lambda d: d["bodies"][0].update(mass=1e-6), "bodies.2.mass"),
    (lambda d: d["bodies"].__setitem__(0, {"name": "2", "mass": 1e-6, "inertia": 1e-6}),
     "bodies.2.center_of_mass"),
    (lambda d: d["bodies"].__setitem__(0, {"name": "2", "mass": -1.0, "inertia": 1e-6,
                                           "center_of_mass": [0.0, 0.0]}), "bodies.2.mass"),
    (lambda d: d["bodies"].__setitem__(0, {"name": "1", "mass": 1.0, "inertia": 1e-6,
                                           "center_of_mass": [0.0, 0.0]}), "bodies.1.mass"),
    (lambda d: d["bodies"][0].update(outline=[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
     "bodies.2.outline"),
    (lambda d: d["gravity"].update(acceleration=[0.0]), "gravity.acceleration"),
    (lambda d: d["gravity"].update(g=1.0), "gravity.g"),
])
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
    from validation.run import run_model
    from geometry import Scene

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
    mech = dataclasses.replace(mech, inertia=MassData(
        gravity=np.array([0.0, -g]), bodies={"t": RigidMass(m, 1e-6, np.array([L + d, 0.0]))}))
    EI = E * 1.0 * 0.1**3 / 12.0
    lp = run_reduced(mech, parse_model("beam:40"), tip_moment(0.0, levels=2))
    P = m * g
    expected = -(P * L**3 / (3 * EI) + P * d * L**2 / (2 * EI))
    assert abs(expected) / L < 3e-3
    assert lp.dy[0] == pytest.approx(expected, rel=1e-4)


def test_lumped_masses_add_up_to_the_flexure():
    """HRZ lumping: total mass rho A L and the first moment of a uniform chain."""
    pts = chain_mass_points([[0, 1, 2], [6, 7, 8], [9, 10, 11], [3, 4, 5]], np.zeros((4, 2)),
                            np.full(3, 2.0), 0.5)
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
    assert 0.5 * v @ M @ v == pytest.approx(0.5 * body.mass * v_g @ v_g
                                            + 0.5 * body.inertia * v[2] ** 2, rel=1e-13)


def test_cli_modes_json_and_refusal(tmp_path):
    from validation.cli import main

    scene = tmp_path / "mass.toml"
    scene.write_text(SCENE, encoding="utf-8")
    out = tmp_path / "modes.json"
    assert main(["modes", str(scene), "--model", "beam:10", "--count", "2",
                 "--json", str(out)]) == 0
    record = json.loads(out.read_text())
    assert len(record["frequencies_hz"]) == 2 and record["frequencies_hz"][0] > 0.0
    assert main(["modes", "open_chain", "--model", "prbm"]) == 2
    assert main(["modes", str(scene), "--model", "beam:10", "--at", "2"]) == 2
    assert main(["modes", "open_chain", "--model", "dcmm:2", "--density", "1.24e-9"]) == 0
    assert main(["modes", "open_chain", "--model", "dcmm:2", "--density", "1240"]) == 2


def test_ee_carries_the_weights_like_its_nonlinear_parent():
    """ee is dcmm:1 linearised at rest, weights included (they act before the load case
    in every static run). On a PLA cantilever arc (size 3 mm) sagging by 7e-4 mm under
    its own weight, plus a small tip moment, the two differ only by the geometric
    nonlinearity, measured 2e-4 relative; ee without the weights misses the whole
    sag at the first level (a relative difference of 1)."""
    from geometry import Scene
    from validation.run import run_model

    mech = cantilever(Arc((0.0, 0.0), 3.0, 0.4, 2.0), E=2100.0, b=1.0, h=0.1)
    mech = dataclasses.replace(mech, inertia=MassData(density=1.24e-9,
                                                      gravity=np.array([0.0, -9810.0])))
    scene = Scene("sag", "", mech, (tip_moment(1e-5, levels=3),), (), frozenset(), "<sag>")
    linear, nonlinear = (run_model(scene, parse_model(m), scene.load_cases[0])
                         for m in ("ee", "dcmm:1"))
    for k in range(3):
        d_lin = np.array([linear.dx[k], linear.dy[k]])
        d_non = np.array([nonlinear.dx[k], nonlinear.dy[k]])
        assert np.linalg.norm(d_non) > 5e-4
        assert np.linalg.norm(d_lin - d_non) < 1e-3 * np.linalg.norm(d_non)
        assert linear.peak_stress and all(v[k] > 0 for v in linear.peak_stress.values())
