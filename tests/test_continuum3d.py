"""The 3D continuum (``continuum:LEVEL[3d]``): extruded mesh, 27-node kernel, connector, catalogue.

References: finite differences of the energy and forces, scikit-fem's own
linear-elastic assembly of the same hexahedra, the rigid motions, the mesh of
the full depth (no symmetry), the 2D plane-stress continuum on the same
in-plane mesh (narrow strips) and the plane-strain one (wide strips), and the
exact count of unknowns. Slow studies (mesh convergence, the open chain's
load cases at levels 0 and 1): ``benchmarks/bench_continuum3d.py``.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from test_continuum import E_MOD, NU, cantilever, rest_poses

import flexval.validation  # noqa: F401  (registers the continuum)
from flexval.geometry import BUILTIN_SCENES, Arc, LoadCase, Moment, SceneError, Segment, load_scene
from flexval.geometry.extrude import (
    boundary_layer,
    extrude,
    extruded_mesh,
    layer_bounds,
    layers,
    mean_radius,
)
from flexval.geometry.outline import flexure_mesh
from flexval.reducedmodels import SolverSettings, System, parse_model, solve_path
from flexval.reducedmodels.core.system import local_hessian
from flexval.validation.continuum import ContinuumConnector
from flexval.validation.continuum.connector3d import Continuum3DConnector
from flexval.validation.continuum.cost import size_3d
from flexval.validation.continuum.run import build_system
from flexval.validation.continuum.solid3d import QUAD9_REFERENCE, Law3D, Solid3D

pytestmark = pytest.mark.usefixtures("private_mesh_cache")  # meshes go to a temporary cache

H = 0.1  # in-plane thickness of the strips, mm


def compliance(connector, mech) -> np.ndarray:
    """Linear 3x3 compliance of body 2 (dx, dy, theta per Fx, Fy, M) from the tangent at rest
    (the ground, body 1, holds the flexure's start)."""
    _, _, hess = connector.evaluate(*rest_poses(mech), connector.initial_internal())
    K = local_hessian(connector, hess)[3:, 3:].tocsc()
    rhs = np.zeros((K.shape[0], 3))
    rhs[:3] = np.eye(3)
    return spla.spsolve(K, rhs)[:3]


# --- mesh ----------------------------------------------------------------------------------
def test_the_layers_are_graded_so_the_outer_half_lies_in_the_boundary_layer():
    half, delta = 2.0, 0.3
    for count in (2, 4, 8):
        z = layer_bounds(half, delta, count)
        t = np.diff(z)
        assert z[0] == 0.0 and z[-1] == pytest.approx(half, rel=1e-15)
        assert z[-1] - z[count // 2] == pytest.approx(delta, rel=1e-12)
        assert np.allclose(t[1:] / t[:-1], t[1] / t[0], rtol=1e-12)  # geometric
        assert t[-1] < t[0]  # finer towards the free face
    assert np.allclose(np.diff(layer_bounds(0.5, 0.55, 4)), 0.125)  # wide layer: uniform
    assert [layers(level) for level in range(3)] == [2, 4, 8]
    arc = Arc((0.0, 0.0), 3.0, 0.0, 1.0)
    assert mean_radius(flexure_mesh(arc, cantilever(arc, H).flexures[0].section, 0)) == (
        pytest.approx(3.0, rel=1e-4)
    )
    assert boundary_layer(math.inf, H, 1.0) == 1.0
    assert boundary_layer(3.0, H, 1.0) == pytest.approx(math.sqrt(0.3))


def test_the_hexahedra_extrude_the_plane_mesh():
    """Every node layer repeats the quad9 mesh; the elements' volume is the strip's (half)."""
    mech = cantilever(Arc((0.0, 0.0), 3.0, 0.0, 1.0), H, b=1.0)
    flexure = mech.flexures[0]
    mesh = extruded_mesh(flexure.shape, flexure.section, 1)
    plane = mesh.plane
    assert mesh.z.size == 2 * layers(1) + 1 and mesh.z[0] == 0.0 and mesh.z[-1] == 0.5
    assert mesh.nodes.shape[0] == plane.nodes.shape[0] * mesh.z.size
    assert mesh.elements.shape[0] == plane.elements.shape[0] * layers(1)
    assert np.array_equal(
        mesh.nodes[mesh.layer_nodes(plane.centre_line, [3])[0], :2], plane.nodes[plane.centre_line]
    )
    solid = Solid3D(mesh.nodes, mesh.elements, Law3D("svk", E_MOD, NU))
    area = ContinuumConnector(flexure, mech, 1).solid.weight.sum()  # times b = 1 mm
    assert solid.volume == pytest.approx(area * 0.5, rel=1e-13)
    full = extrude(plane, layer_bounds(0.5, 0.5, 2), half=False)
    assert full.z[0] == -0.5 and full.z[-1] == 0.5 and full.mid_layer == 4


# --- kernel --------------------------------------------------------------------------------
def box(n=(2, 1, 2), size=(1.0, 0.5, 0.3)):
    """A box of 27-node elements in this module's local order, built from scikit-fem's MeshHex
    and the ElementHex2 basis on it (their degrees of freedom are the nodes)."""
    from skfem import Basis, ElementHex2, MeshHex

    axes = [np.linspace(0.0, s, k + 1) ** 1.3 * s**-0.3 for s, k in zip(size, n)]  # unequal
    mesh = MeshHex.init_tensor(*axes)
    basis = Basis(mesh, ElementHex2())
    nodes = basis.doflocs.T
    key = {tuple(np.round(p, 12)): i for i, p in enumerate(nodes)}
    ref = np.column_stack([np.tile(QUAD9_REFERENCE, (3, 1)), np.repeat([-1.0, 0.0, 1.0], 9)])
    lo, hi = mesh.p[:, mesh.t].min(axis=1).T, mesh.p[:, mesh.t].max(axis=1).T  # (n_el, 3)
    points = lo[:, None] + 0.5 * (ref[None] + 1.0) * (hi - lo)[:, None]
    elements = np.array([[key[tuple(np.round(p, 12))] for p in el] for el in points])
    return mesh, nodes, elements


def test_the_linear_tangent_is_scikit_fem_linear_elasticity():
    """At the reference state the tangent is the linear-elastic stiffness: scikit-fem's
    ``linear_elasticity`` form on ElementVector(ElementHex2()) gives the same matrix."""
    from skfem import Basis, BilinearForm, ElementHex2, ElementVector, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh, nodes, elements = box()
    vector = Basis(mesh, ElementVector(ElementHex2()), intorder=5)
    reference = asm(BilinearForm(linear_elasticity(*lame_parameters(E_MOD, NU))), vector)
    for name in ("svk", "neo-hookean"):
        solid = Solid3D(nodes, elements, Law3D(name, E_MOD, NU))
        _, forces, Ke = solid.evaluate(nodes)
        assert np.abs(forces).max() < 1e-9
        rows = np.repeat(solid.element_dofs, 81, axis=1).ravel()
        cols = np.tile(solid.element_dofs, (1, 81)).ravel()
        K = sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(solid.n_dofs,) * 2).toarray()
        # this module's dof 3 n + i is scikit-fem's dof of component i at node n's place
        at = {tuple(np.round(p, 12)): i for i, p in enumerate(nodes)}
        perm = np.empty(solid.n_dofs, np.int64)
        for i, dofs in enumerate(vector.split_indices()):
            for dof, p in zip(dofs, vector.doflocs[:, dofs].T):
                perm[3 * at[tuple(np.round(p, 12))] + i] = dof
        ref = reference.toarray()[np.ix_(perm, perm)]
        assert np.abs(K - ref).max() < 1e-10 * np.abs(ref).max()


@pytest.mark.parametrize("law", ["svk", "neo-hookean"])
def test_forces_and_tangent_match_finite_differences(law):
    _, nodes, elements = box((1, 1, 1))
    solid = Solid3D(nodes, elements, Law3D(law, E_MOD, NU), factor=2.0)
    rng = np.random.default_rng(3)
    x = nodes @ np.array([[1.02, 0.1, 0.0], [-0.05, 0.97, 0.02], [0.01, 0.0, 1.01]])
    x += 0.01 * rng.standard_normal(x.shape)
    energy, forces, Ke = solid.evaluate(x)
    assert energy == pytest.approx(solid.energy(x), rel=1e-14)
    assert np.allclose(forces, solid.forces(x), rtol=0, atol=1e-12 * np.abs(forces).max())
    d = rng.standard_normal(x.shape)
    eps = 1e-6  # central differences: error ~ eps^2 |third derivative|, round-off ~ 1e-16/eps
    slope = (solid.energy(x + eps * d) - solid.energy(x - eps * d)) / (2 * eps)
    assert slope == pytest.approx(forces @ d.ravel(), rel=1e-8)
    rows = np.repeat(solid.element_dofs, 81, axis=1).ravel()
    cols = np.tile(solid.element_dofs, (1, 81)).ravel()
    K = sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(solid.n_dofs,) * 2).tocsr()
    fd = (solid.forces(x + eps * d) - solid.forces(x - eps * d)) / (2 * eps)
    assert np.abs(fd - K @ d.ravel()).max() < 1e-7 * np.abs(fd).max()
    assert abs(K - K.T).max() < 1e-12 * abs(K).max()


def test_an_inverted_element_is_refused():
    _, nodes, elements = box((1, 1, 1))
    solid = Solid3D(nodes, elements, Law3D("svk", E_MOD, NU))
    x = nodes.copy()
    x[:, 2] *= -1.0  # mirrored: det F = -1
    with pytest.raises(ValueError, match="inverted"):
        solid.evaluate(x)
    assert solid.min_det(x).max() == pytest.approx(-1.0)


# --- connector -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def small():
    mech = cantilever(Arc((0.0, 0.0), 1.0, 0.3, 0.6), H, b=0.3, start_on_ground=False)
    return mech, Continuum3DConnector(mech.flexures[0], mech, 0)


@pytest.mark.parametrize("law", ["svk", "neo-hookean"])
def test_connector_gradient_and_hessian_match_finite_differences(law, small):
    mech, _ = small
    c = Continuum3DConnector(mech.flexures[0], mech, 0, law=law)
    rng = np.random.default_rng(5)
    pa, pb = rest_poses(mech)
    q = np.concatenate(
        [
            pa + [1e-3, 2e-3, 0.02],
            pb + [3e-3, -2e-3, 0.05],
            1e-3 * rng.standard_normal(c.n_internal),
        ]
    )

    def ev(v):
        return c.evaluate(v[:3], v[3:6], v[6:])

    _, g, h = ev(q)
    K = local_hessian(c, h)
    d = rng.standard_normal(q.size)
    eps = 1e-7
    assert (ev(q + eps * d)[0] - ev(q - eps * d)[0]) / (2 * eps) == pytest.approx(g @ d, rel=1e-7)
    fd = (ev(q + eps * d)[1] - ev(q - eps * d)[1]) / (2 * eps)
    assert np.abs(fd - K @ d).max() < 1e-7 * np.abs(fd).max()
    assert abs(K - K.T).max() < 1e-12 * abs(K).max()


def test_section_forces_come_from_the_end_face_alone(small):
    """The end wrench from the end face's elements equals the gradient on the end body's pose;
    the resultants carried from it by statics: the end moment at the end."""
    mech, c = small
    rng = np.random.default_rng(7)
    pa, pb = rest_poses(mech)
    state = (
        pa + [1e-3, 2e-3, 0.02],
        pb + [3e-3, -2e-3, 0.05],
        1e-3 * rng.standard_normal(c.n_internal),
    )
    _, grad, _ = c.evaluate(*state)
    alone, given = c.section_forces(*state), c.section_forces(*state, gradient=grad)
    scale = np.abs(given.moment).max()
    assert np.allclose(alone.moment, given.moment, rtol=0, atol=1e-10 * scale)
    assert np.allclose(alone.axial, given.axial, rtol=0, atol=1e-10 * np.abs(given.axial).max())


def test_rigid_in_plane_motion_costs_nothing(small):
    mech, c = small
    th, t = 1.2, np.array([0.3, -0.2])
    R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    pa, pb = rest_poses(mech)

    def moved(p):
        return np.array([*(R @ p[:2] + t), p[2] + th])

    xy = c.mesh.nodes[c._free, :2]
    internal = np.concatenate([(xy @ R.T + t - xy).ravel(), np.zeros(c._free_z.size)])
    energy, grad, _ = c.evaluate(moved(pa), moved(pb), internal)
    _, stiff, _ = c.evaluate(pa + [0, 0, 1e-3], pb, c.initial_internal())
    assert abs(energy) < 1e-20
    assert np.abs(grad).max() < 1e-10 * np.abs(stiff).max()


def test_the_half_depth_with_symmetry_is_the_full_depth():
    """The full-depth mesh (its mirror image added, no mid-plane constraint, no factor 2) has
    the same linear compliance and the same large-rotation path."""
    mech = cantilever(Arc((0.0, 0.0), 1.0, 0.3, 0.6), H, b=0.4)
    flexure = mech.flexures[0]
    half = Continuum3DConnector(flexure, mech, 0)
    full = Continuum3DConnector(
        flexure, mech, 0, mesh=extrude(half.mesh.plane, half.mesh.z[::2], half=False)
    )
    a, b = compliance(half, mech), compliance(full, mech)
    assert np.abs(a - b).max() < 1e-9 * np.abs(a).max()
    EI = E_MOD * 0.4 * H**3 / 12
    case = LoadCase("m", (Moment("2", EI * 1.0 / 0.6),), levels=2)  # turns the tip by ~1 rad
    paths = []
    for conn in (half, full):
        system = System(mech, [conn], SolverSettings())
        paths.append(solve_path(system, case))
    assert paths[0].rotation[-1] > 0.9
    assert paths[0].rotation[-1] == pytest.approx(paths[1].rotation[-1], rel=1e-9)
    assert paths[0].dx[-1] == pytest.approx(paths[1].dx[-1], rel=1e-9)


# --- against the 2D continuum ----------------------------------------------------------------
def test_a_narrow_strip_is_the_plane_stress_continuum():
    """b = h: the 3D end rotation under an end moment is the 2D plane-stress one within 0.5 %,
    linear and at a large rotation. Measured (L/h = 50, level 0): 3D stiffer by 0.19 %
    linear, the clamps holding each end face's z (the 2D clamp frees it)."""
    L = 5.0
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), H, b=H)
    flexure = mech.flexures[0]
    c2 = compliance(ContinuumConnector(flexure, mech, 0), mech)
    c3 = compliance(Continuum3DConnector(flexure, mech, 0), mech)
    assert c3[2, 2] == pytest.approx(c2[2, 2], rel=5e-3)
    EI = E_MOD * H**4 / 12
    theta = math.pi / 3
    case = LoadCase("m", (Moment("2", EI * theta / L),), levels=3)
    plane = solve_path(build_system(mech, 0), case)
    solid = solve_path(build_system(mech, 0, three_d=True), case)
    assert solid.rotation[-1] == pytest.approx(plane.rotation[-1], rel=5e-3)
    assert solid.rotation[-1] == pytest.approx(theta, rel=1e-2)


def test_the_bending_stiffness_of_a_curved_strip_grows_to_plane_strain():
    """An arc (R = 30 h) under an end moment: the 3D rotational stiffness over the plane-stress
    one grows with b^2 / (R h) towards the plane-strain ratio 1 / (1 - nu^2) (the anticlastic
    curvature held back across the depth, all but a boundary layer sqrt(R h) wide at the free
    faces). Measured at level 0 with the layers given: 1.002, 1.034, 1.106, 1.130 at
    b^2/(R h) = 0.033, 3.3, 30, 333 (plane strain: 1.141)."""
    arc = Arc((0.0, 0.0), 3.0, math.radians(90.0), math.radians(90.0))
    ratios = []
    for b, count in ((0.1, 2), (1.0, 2), (3.0, 4), (10.0, 8)):
        mech = cantilever(arc, H, b)
        flexure = mech.flexures[0]
        stress = ContinuumConnector(flexure, mech, 0)
        delta = boundary_layer(3.0, H, b)
        mesh = extrude(stress.mesh, layer_bounds(b / 2, delta, count))
        solid = Continuum3DConnector(flexure, mech, 0, mesh=mesh)
        ratios.append(compliance(stress, mech)[2, 2] / compliance(solid, mech)[2, 2])
    strain = ContinuumConnector(flexure, mech, 0, plane="strain")
    limit = compliance(stress, mech)[2, 2] / compliance(strain, mech)[2, 2]
    assert limit == pytest.approx(1.0 / (1.0 - NU**2), rel=2e-3)  # the clamps' share
    assert ratios[0] == pytest.approx(1.0, abs=5e-3)
    assert np.all(np.diff(ratios) > 0.0)
    assert 1.02 < ratios[1] < 1.05  # the open chain's strips (CalculiX: about 3 %)
    # the boundary layer's share of the depth, ~ sqrt(R h) / b = 0.055 at b = 10 mm, is
    # what is left to plane strain: measured 0.011 of 0.141
    assert limit - 0.02 < ratios[-1] < limit


def test_the_mid_strip_stiffness_is_the_anticlastic_theory():
    """A half-circle arc (R = 30 h) under an end moment, its curvature change measured on the
    middle third (away from the clamps, which hold the section flat): M / (E I kappa) is the
    linear theory of the curved strip (Searle, Ashwell; :mod:`flexval.geometry.anticlastic`).
    Measured at level 0, the layers given: within 0.06 % at b^2/(R h) = 0.3 ... 333 (0.014,
    0.009, 0.06, 0.008 %); the 2D plane-stress continuum gives 1.0001 (the in-plane mesh)."""
    from flexval.geometry.anticlastic import stiffness_ratio

    R = 3.0
    arc = Arc((0.0, 0.0), R, 0.0, math.pi)
    for b, count in ((0.3, 2), (1.0, 2), (3.0, 4), (10.0, 8)):
        mech = cantilever(arc, H, b)
        flexure = mech.flexures[0]
        plane = flexure_mesh(arc, flexure.section, 0)
        mesh = extrude(plane, layer_bounds(b / 2, boundary_layer(R, H, b), count))
        c = Continuum3DConnector(flexure, mech, 0, mesh=mesh)
        rest = rest_poses(mech)
        _, _, hess = c.evaluate(*rest, c.initial_internal())
        unit_moment = np.zeros(3 + c.n_internal)
        unit_moment[2] = 1.0
        u = spla.spsolve(local_hessian(c, hess)[3:, 3:].tocsc(), unit_moment)
        eps = 1e-6  # a linear change: the centre line's angles move by eps u
        moved = c.shape(rest[0], rest[1] + eps * u[:3], eps * u[3:])
        still = c.shape(*rest, c.initial_internal())
        turn, s = [], None
        for line in (moved, still):
            d = np.diff(line, axis=0)
            turn.append(np.unwrap(np.arctan2(d[:, 1], d[:, 0])))
            s = np.cumsum(np.hypot(d[:, 0], d[:, 1]))
        middle = slice(s.size // 3, 2 * s.size // 3)
        kappa = np.polyfit(s[middle], (turn[0] - turn[1])[middle], 1)[0] / eps
        EI = E_MOD * b * H**3 / 12
        theory = float(stiffness_ratio(b * b / (R * H), NU))
        assert 1.0 / (EI * kappa) == pytest.approx(theory, rel=2e-3), b


def test_a_wide_straight_strip_stiffens_as_it_bends():
    """A straight strip (b = 10 h) under a growing end moment: M over E I times the curvature
    measured in its middle (away from the clamps' boundary layers) is 1 at small curvature
    and grows with b^2 / (R h) (Searle's anticlastic parameter, 4 at full load). Measured
    (level 0): 1.0044, 1.0134, 1.0250, 1.0369 at b^2/(R h) = 1.0, 2.0, 2.9, 3.9 (a secant
    stiffness of a strip bent from straight, above the pre-curved strip's tangent one)."""
    L, b = 5.0, 1.0
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), H, b)
    system = build_system(mech, 0, three_d=True)
    EI = E_MOD * b * H**3 / 12
    kappa_end = 4.0 * H / b**2  # b^2 kappa / h = 4
    case = LoadCase("m", (Moment("2", EI * kappa_end),), levels=5)
    lp = solve_path(system, case, record_shapes=True)
    ratios = []
    for factor, line in zip(lp.load, lp.shapes["e"]):
        line = np.asarray(line)
        middle = slice(line.shape[0] // 3, 2 * line.shape[0] // 3)
        d = np.diff(line[middle], axis=0)
        phi = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
        s = np.cumsum(np.hypot(d[:, 0], d[:, 1]))
        kappa = np.polyfit(s, phi, 1)[0]
        if factor > 0:
            ratios.append(factor / (EI * kappa))
    assert 1.0 < ratios[0] < 1.01
    assert np.all(np.diff(ratios) > 0.0)
    assert 1.02 < ratios[-1] < 1.0 / (1.0 - NU**2)


# --- catalogue and cost --------------------------------------------------------------------
def test_the_option_parses_and_refuses_a_plane():
    assert parse_model("continuum:0[3d]").id == "continuum:0[3d]"
    assert parse_model("continuum:0[3d]").kwargs == {"three_d": True}
    for text in ("continuum:0[3d,plane=strain]", "continuum:0[plane=stress,3d]"):
        with pytest.raises(SceneError, match="'plane' of 'continuum' means nothing with '3d'"):
            parse_model(text)


@pytest.mark.parametrize("scene", BUILTIN_SCENES)
def test_the_3d_unknowns_are_counted_exactly_without_meshing(scene):
    mechanism = load_scene(scene).mechanism
    assert size_3d(mechanism, 0)[0] == build_system(mechanism, 0, three_d=True).n_dofs


def test_a_3d_level_beyond_the_memory_budget_is_refused_before_work():
    """$FLEXVAL_MEMORY = 2G: open_chain's continuum:1[3d] (6.8 GB estimated, 6.1-7.7 GB
    measured) exits 2 at once, naming the finest level that fits, continuum:0[3d]."""
    code = (
        "import sys\n"
        "from flexval.validation.cli import main\n"
        "sys.exit(main(['run', 'open_chain', '--model', 'continuum:1[3d]', "
        "'--load-case', 'm+']))\n"
    )
    env = dict(os.environ, FLEXVAL_MEMORY="2G")
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=60
    )
    assert done.returncode == 2, done.stderr
    assert "continuum:1[3d]" in done.stderr and "(3D)" in done.stderr, done.stderr
    assert "continuum:0[3d] needs about" in done.stderr, done.stderr


# --- VTU -----------------------------------------------------------------------------------
def test_the_vtu_cells_follow_vtk_triquadratic_hexahedron_order():
    """VTK's hexahedron27: corners, the midpoints of the edges (0,1) (1,2) (2,3) (3,0) (4,5)
    (5,6) (6,7) (7,4) (0,4) (1,5) (2,6) (3,7), the centres of the faces (0,1,5,4) (1,2,6,5)
    (2,3,7,6) (3,0,4,7) (0,1,2,3) (4,5,6,7), the centre (VTK's documentation)."""
    from flexval.validation.continuum.output3d import VTK_ORDER

    corners = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
        float,
    )
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4)]
    edges += [(0, 4), (1, 5), (2, 6), (3, 7)]
    faces = [(0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7), (0, 1, 2, 3), (4, 5, 6, 7)]
    vtk = np.vstack(
        [
            corners,
            [corners[list(e)].mean(axis=0) for e in edges],
            [corners[list(f)].mean(axis=0) for f in faces],
            [corners.mean(axis=0)],
        ]
    )
    ours = np.column_stack([np.tile(QUAD9_REFERENCE, (3, 1)), np.repeat([-1.0, 0.0, 1.0], 9)])
    assert np.array_equal(0.5 * (ours[VTK_ORDER] + 1.0), vtk)


def test_a_3d_run_writes_its_hexahedra_and_refuses_a_picture(tmp_path):
    import meshio

    from flexval.validation.continuum.run import run_continuum

    mech = cantilever(Arc((0.0, 0.0), 1.0, 0.3, 0.6), H, b=0.3)
    case = LoadCase("m", (Moment("2", 1e-3),), levels=2)
    lp = run_continuum(mech, case, level=0, three_d=True, vtu_dir=tmp_path, model="c3")
    (written,) = tmp_path.glob("*.vtu")
    mesh = meshio.read(written)
    conn = Continuum3DConnector(mech.flexures[0], mech, 0)
    assert mesh.cells[0].type == "hexahedron27"
    assert mesh.cells[0].data.shape == conn.mesh.elements.shape
    assert np.allclose(mesh.points, conn.mesh.nodes)
    tip = mesh.point_data["displacement"][conn.end_faces[1], :2]
    assert np.abs(tip).max() > 0.0 and lp.rotation[-1] > 0.0
    with pytest.raises(ValueError, match="PNG"):
        run_continuum(mech, case, level=0, three_d=True, png=tmp_path / "x.png")
