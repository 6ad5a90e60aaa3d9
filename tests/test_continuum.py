"""The continuum reference (quad9 plane-stress hyperelastic solids as connectors).

Checks, each with its tolerance justified next to it: the Gmsh meshes, the
plane-stress law in a strip, objectivity, the patch test, quadratic Newton
convergence, a large-rotation cantilever against the elastica circle, the
small-load compliance of an arc against Castigliano, the mesh convergence
rate against the theory (including the clamped-corner singularity), and the
consistency of the tangent by finite differences.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.optimize import brentq

from flexval.geometry import Arc, Force, LoadCase, Material, Moment, Section, Segment
from flexval.geometry.files import cache_dir
from flexval.geometry.mechanism import FlexureSpec, assemble
from flexval.geometry.mesh import mesh_flexure
from flexval.reducedmodels import solve_path
from flexval.reducedmodels.core.newton import FixedLoad, solve
from flexval.reducedmodels.core.system import local_hessian
from flexval.validation.continuum import ContinuumConnector
from flexval.validation.continuum.material import make_law
from flexval.validation.continuum.run import build_system
from flexval.validation.continuum.solid import Solid

E_MOD, NU = 2100.0, 0.35


pytestmark = pytest.mark.usefixtures("private_mesh_cache")  # meshes go to a temporary cache


def cantilever(shape, h: float, b: float = 1.0, nu: float = NU, start_on_ground: bool = True):
    """One flexure from the ground (body 1) to body 2, the shape's start on the ground or not."""
    spec = FlexureSpec("e", shape, ("1", "2"), Section(b, h))
    ground, tip = (0, 1) if start_on_ground else (1, 0)
    return assemble(
        [spec],
        "1",
        shape.end_points[ground : ground + 1],
        Material(E_MOD, nu),
        "2",
        shape.end_points[tip],
    )


def rest_poses(mech) -> tuple[np.ndarray, np.ndarray]:
    return (
        np.array([*mech.bodies["1"].reference, 0.0]),
        np.array([*mech.bodies["2"].reference, 0.0]),
    )


def tip_compliance(mech, level: int) -> np.ndarray:
    """Linear 3x3 compliance of body 2 (dx, dy, theta per Fx, Fy, M) from the tangent at rest."""
    c = ContinuumConnector(mech.flexures[0], mech, level)
    _, _, H = c.evaluate(*rest_poses(mech), c.initial_internal())
    K = local_hessian(c, H)[3:, 3:]  # ground pose removed
    rhs = np.zeros((K.shape[0], 3))
    rhs[:3] = np.eye(3)
    return spla.spsolve(K.tocsc(), rhs)[:3]


# --- mesh --------------------------------------------------------------------
def test_arc_mesh_is_the_exact_band_with_tagged_faces(capfd):
    arc = Arc((1.0, -2.0), 3.0, math.radians(150.0), math.radians(240.0))  # wider than pi
    h = 0.3
    m = mesh_flexure(arc, h, 1, use_cache=False)
    assert capfd.readouterr().out == ""  # Gmsh is silent
    assert (m.n_t, m.n_l) == (2, 2 * math.ceil(arc.length / h))
    assert m.nodes.shape[0] == (2 * m.n_t + 1) * (2 * m.n_l + 1)
    rho = np.hypot(*(m.nodes - arc.center).T)
    assert rho.min() == pytest.approx(3.0 - h / 2, abs=1e-12)
    assert rho.max() == pytest.approx(3.0 + h / 2, abs=1e-12)
    # every node on one of the 2 n_t + 1 circles of the structured mesh (snapped)
    rings = 3.0 + h * (np.arange(2 * m.n_t + 1) / (2 * m.n_t) - 0.5)
    assert np.abs(rho[:, None] - rings).min(axis=1).max() < 1e-12
    np.testing.assert_allclose(rho[m.centre_line], 3.0, atol=1e-12)
    for face, angle in ((m.start_face, arc.start_angle), (m.end_face, arc.end_angle)):
        u = np.array([math.cos(angle), math.sin(angle)])
        np.testing.assert_allclose(
            m.nodes[face], np.asarray(arc.center) + rings[:, None] * u, atol=1e-12
        )
    np.testing.assert_allclose(m.nodes[m.centre_line[[0, -1]]], arc.end_points, atol=1e-12)
    # the isoparametric area is the band's: quadratic interpolation of the circles
    # errs by ~dphi^4 / 500 = 1.3e-8 with element angle dphi = h / 2r = 0.05 rad
    sol = Solid(m.nodes, m.elements, make_law("svk", "stress", E_MOD, NU), 1.0)
    assert sol.weight.sum() == pytest.approx(arc.length * h, rel=1e-7)


def test_mesh_cache_returns_the_same_mesh():
    seg = Segment((0.0, 0.0), (3.0, 4.0))
    first = mesh_flexure(seg, 0.5, 0)
    assert any((cache_dir() / "meshes").glob("*.npz"))
    again = mesh_flexure(seg, 0.5, 0)
    np.testing.assert_array_equal(first.nodes, again.nodes)
    np.testing.assert_array_equal(first.elements, again.elements)
    np.testing.assert_array_equal(first.end_face, again.end_face)


# --- 1. plane-stress law --------------------------------------------------------
@pytest.mark.parametrize("law", ["svk", "neo-hookean"])
@pytest.mark.parametrize("b_over_h", [0.1, 1.0, 10.0])
@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_strip_in_tension_has_the_plane_law(law, b_over_h, plane):
    h, length, eps = 1.0, 20.0, 1e-6
    mech = cantilever(Segment((0.0, 0.0), (length, 0.0)), h, b=b_over_h * h)
    system = build_system(mech, 1, law=law, plane=plane)
    force = eps * E_MOD * b_over_h * h * h  # plane-stress axial strain eps
    case = LoadCase("pull", (Force("2", np.array([length, 0.0]), 0.0, force),))
    q, _, _, why, *_ = solve(
        FixedLoad(system, system.loads(case), 1.0), system.initial_state(), system.settings
    )
    assert q is not None, why
    conn = system.connectors[0]
    x = conn.positions(*system.local_states(q)[0])
    X = conn.mesh.nodes

    def section(at):  # nodes of the cross-section at x = at, bottom to top
        idx = np.flatnonzero(np.abs(X[:, 0] - at) < 1e-9)
        return idx[np.argsort(X[idx, 1])]

    mid = section(length / 2)
    gauge = x[section(length / 2 + 2 * h), 0] - x[section(length / 2 - 2 * h), 0]
    axial = gauge.mean() / (4 * h) - 1
    lateral = (x[mid[-1], 1] - x[mid[0], 1]) / h - 1
    # plane stress: eps_xx = sigma/E, eps_yy = -nu eps_xx; plane strain: eps_zz = 0
    axial_ref = eps if plane == "stress" else eps * (1 - NU**2)
    ratio_ref = NU if plane == "stress" else NU / (1 - NU)
    # tolerance 1e-4: the clamps' disturbance decays like exp(-pi x / h) (e^-31 at the
    # gauge) and the uniform state is in the quad9 space, so what is left is the laws'
    # nonlinearity, O(eps) = 1e-6 (measured 0.5-1.5e-6), whatever b/h
    assert axial == pytest.approx(axial_ref, rel=1e-4)
    assert -lateral / axial == pytest.approx(ratio_ref, rel=1e-4)
    # the second Piola-Kirchhoff stress in the middle is uniaxial: S_xx = F / (b h)
    st = conn.solid.state(x)
    centre = np.abs(conn.solid.basis.global_coordinates()[0] - length / 2) < 2 * h
    S = st.S[centre]
    sigma = force / (b_over_h * h * h)
    np.testing.assert_allclose(S[:, 0, 0], sigma, rtol=1e-4)
    assert np.abs(S[:, 1, 1]).max() < 1e-4 * sigma


# --- 2. objectivity ------------------------------------------------------------
def test_rigid_rotation_by_90_degrees_costs_nothing():
    arc = Arc((0.0, 0.0), 3.0, math.radians(60.0), math.radians(200.0))
    mech = cantilever(arc, 0.3)
    conn = ContinuumConnector(mech.flexures[0], mech, 1)
    centre, rot = np.array([1.0, 2.0]), np.array([[0.0, -1.0], [1.0, 0.0]])

    def moved(p):
        return centre + (p - centre) @ rot.T

    poses = [np.array([*moved(mech.bodies[b].reference), math.pi / 2]) for b in ("1", "2")]
    X = conn.mesh.nodes[conn.free_nodes]
    internal = (moved(X) - X).ravel()
    energy, grad, _ = conn.evaluate(*poses, internal)
    # round-off of positions ~1e-15 mm over elements ~0.1 mm: strains ~1e-14, so the
    # energy is ~E V 1e-28 and the forces ~E b h 1e-14 (moments ~ that times the size)
    volume = arc.length * 0.3 * 1.0
    assert energy <= 1e-24 * E_MOD * volume
    assert np.abs(grad).max() <= 1e-11 * E_MOD * 0.3 * 1.0 * 10.0


def test_an_inverted_element_is_refused():
    mech = cantilever(Segment((0.0, 0.0), (2.0, 0.0)), 0.5)
    conn = ContinuumConnector(mech.flexures[0], mech, 0)
    internal = conn.initial_internal()
    internal[1::2] = -2.0 * conn.mesh.nodes[conn.free_nodes, 1]  # mirror the free nodes in y
    with pytest.raises(ValueError, match="inverted"):
        conn.evaluate(*rest_poses(mech), internal)


# --- 3. patch test -------------------------------------------------------------------
def test_linear_patch_test_on_a_distorted_mesh():
    rng = np.random.default_rng(7)
    n = 5  # 2 x 2 quad9 elements: 5 x 5 nodes
    g = np.linspace(0.0, 2.0, n)
    X = np.array([[x, y] for y in g for x in g])
    node = np.arange(n * n).reshape(n, n)  # node[row (y), col (x)]
    boundary = np.zeros(n * n, bool)
    boundary[node[[0, -1], :]] = boundary[node[:, [0, -1]]] = True
    X[~boundary] += rng.uniform(-0.12, 0.12, ((~boundary).sum(), 2))
    elements = np.array(
        [
            [
                node[j, i],
                node[j, i + 2],
                node[j + 2, i + 2],
                node[j + 2, i],
                node[j, i + 1],
                node[j + 1, i + 2],
                node[j + 2, i + 1],
                node[j + 1, i],
                node[j + 1, i + 1],
            ]
            for j in (0, 2)
            for i in (0, 2)
        ]
    )
    solid = Solid(X, elements, make_law("svk", "stress", E_MOD, NU), 2.0)
    _, _, Ke = solid.evaluate(X)  # tangent at rest: the linear stiffness
    K = sp.coo_matrix((Ke.ravel(), (solid.rows, solid.cols))).tocsr()
    grad_u, shift = np.array([[2e-3, -1e-3], [4e-3, 1e-3]]), np.array([0.3, -0.2])
    u_exact = (X @ grad_u.T + shift).ravel()
    fixed = np.flatnonzero(np.repeat(boundary, 2))
    free = np.flatnonzero(~np.repeat(boundary, 2))
    u = u_exact.copy()
    u[free] = spla.spsolve(K[free][:, free].tocsc(), -K[free][:, fixed] @ u_exact[fixed])
    # an isoparametric element reproduces linear fields exactly: only round-off remains
    np.testing.assert_allclose(u, u_exact, rtol=0, atol=1e-13)
    F = solid.state(X + u.reshape(-1, 2)).F
    np.testing.assert_allclose(F - np.eye(2), np.broadcast_to(grad_u, F.shape), atol=1e-13)


# --- 4. Newton -------------------------------------------------------------------------
def test_newton_converges_quadratically():
    arc = Arc((0.0, 0.0), 5.0, math.radians(90.0), math.radians(120.0))
    h = 0.5
    mech = cantilever(arc, h)
    EI = E_MOD * h**3 / 12
    system = build_system(mech, 0)
    loads = system.loads(LoadCase("m", (Moment("2", 0.1 * EI / arc.length),)))  # 0.1 rad
    q = system.initial_state()
    iterates = [q]
    for _ in range(8):  # one Newton solve from rest, full load
        _, g, K = system.assemble(q, loads, 1.0)
        q = q + K.solve(-g)
        iterates.append(q)
    err = np.array([np.abs(system.scaled(x - q)).max() for x in iterates])
    # once in the terminal phase (error < 1e-4 of the size) the error squares:
    # e_k+1 <= C e_k^2 with C ~ 4 measured (10 allowed), then hits round-off (~1e-15)
    # in the next step, where a linearly converging method at rate 0.1 would need 9
    k = int(np.argmax(err < 1e-4))
    assert err[k + 1] <= 10.0 * err[k] ** 2, err
    assert err[k + 2] < 1e-13, err


# --- 5. large rotation of a straight cantilever --------------------------------------------
def test_pure_moment_bends_a_slender_strip_into_the_circle():
    L, h, b = 50.0, 1.0, 1.0  # L/h = 50
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), h, b)
    EI = E_MOD * b * h**3 / 12  # plane stress: E, not E/(1 - nu^2)
    theta = math.pi / 3
    case = LoadCase("m", (Moment("2", EI * theta / L),), levels=2)
    lp = solve_path(build_system(mech, 1), case)
    tip = np.array([L + lp.dx[-1], lp.dy[-1]])
    circle = L / theta * np.array([math.sin(theta), 1 - math.cos(theta)])
    # beam theory is exact for the curvature M/EI; the continuum differs by the
    # rigid clamps holding back the Poisson contraction (~nu^2 h/L, local) and by
    # the Saint Venant-Kirchhoff law at the bending strain theta h / 2L ~ 1 %
    # (measured at level 1: tip 0.014 % of L off the circle, rotation -0.025 %)
    assert np.hypot(*(tip - circle)) / L < 5e-3
    assert lp.rotation[-1] == pytest.approx(theta, rel=5e-3)


# --- 6. small loads: Castigliano --------------------------------------------------------
def castigliano(arc: Arc, h: float, b: float, nu: float = NU) -> np.ndarray:
    """Tip compliance of an arc cantilever: bending + axial + shear (kappa = 5/6), thin beam."""
    EI, EA = E_MOD * b * h**3 / 12, E_MOD * b * h
    kGA = 5.0 / 6.0 * E_MOD / (2 * (1 + nu)) * b * h
    xg, wg = np.polynomial.legendre.leggauss(400)
    phi = arc.start_angle + 0.5 * (xg + 1) * arc.width
    ds = 0.5 * arc.width * wg * arc.radius
    q = np.asarray(arc.center) + arc.radius * np.column_stack([np.cos(phi), np.sin(phi)])
    tip = arc.end_points[1]
    t = np.column_stack([-np.sin(phi), np.cos(phi)])
    n = np.column_stack([np.cos(phi), np.sin(phi)])
    m = np.column_stack([-(tip[1] - q[:, 1]), tip[0] - q[:, 0], np.ones_like(phi)])  # per Fx, Fy, M
    ax = np.column_stack([t, np.zeros_like(phi)])
    sh = np.column_stack([n, np.zeros_like(phi)])
    return (m.T * ds / EI) @ m + (ax.T * ds / EA) @ ax + (sh.T * ds / kGA) @ sh


@pytest.mark.parametrize("r_over_h", [10.0, 20.0])
def test_small_loads_give_the_thin_curved_beam_compliance(r_over_h):
    arc = Arc((0.0, 0.0), 10.0, math.radians(90.0), math.radians(120.0))
    h, b = arc.radius / r_over_h, 1.0
    mech = cantilever(arc, h, b)
    system = build_system(mech, 2)
    ref = castigliano(arc, h, b)
    tip = arc.end_points[1]
    unit_loads = [
        lambda v: Force("2", tip, 0.0, v),
        lambda v: Force("2", tip, math.pi / 2, v),
        lambda v: Moment("2", v),
    ]
    measured = np.zeros((3, 3))
    for k, load in enumerate(unit_loads):
        scale = 1e-7 / ref[k, k]  # displacement ~1e-7 of the size: linear
        loads = system.loads(LoadCase("u", (load(scale),)))
        q, _, _, why, *_ = solve(
            FixedLoad(system, loads, 1.0), system.initial_state(), system.settings
        )
        assert q is not None, why
        dx, dy, rot = system.target(q)
        measured[:, k] = np.array([dx, dy, rot]) / scale
    # thin-beam theory omits the O((h/r)^2) curved-beam terms (Winkler's bending
    # stiffness and the bending-axial coupling); the clamps' local Poisson constraint
    # and the level-2 mesh error (~3e-4) are smaller. Measured: 0.50 (h/r)^2 at
    # r/h = 10, 20 and 40, relative to the diagonal of the compliance.
    scale = np.sqrt(np.outer(np.diag(ref), np.diag(ref)))
    err = (np.abs(measured - ref) / scale).max()
    assert 0.25 * (h / arc.radius) ** 2 < err < (h / arc.radius) ** 2


# --- 7. mesh convergence rate ------------------------------------------------------------
def williams_clamped_free(nu: float) -> float:
    """Smallest exponent lambda (stress ~ r^(lambda - 1)) at a right-angle clamped-free corner.

    Williams (1952): 1 + kappa^2 + 2 kappa cos(2 lambda alpha) = 4 lambda^2 sin^2(alpha),
    alpha = pi/2, plane stress kappa = (3 - nu) / (1 + nu).
    """
    kappa = (3 - nu) / (1 + nu)
    return brentq(
        lambda lam: 1 + kappa**2 + 2 * kappa * math.cos(math.pi * lam) - 4 * lam**2, 0.5, 0.999
    )


@pytest.mark.parametrize("nu", [0.0, NU])
def test_mesh_convergence_rate_of_a_curved_flexure(nu):
    arc = Arc((0.0, 0.0), 5.0, math.radians(90.0), math.radians(120.0))
    mech = cantilever(arc, 0.5, nu=nu)  # r/h = 10
    rot = np.array([tip_compliance(mech, level)[2, 2] for level in range(5)])
    d = np.abs(np.diff(rot))
    order = np.log2(d[:-1] / d[1:])
    assert np.all(np.diff(rot) > 0)  # displacement FE: stiff, converging upwards
    if nu == 0.0:
        # kappa = 3 gives lambda = 1: no corner singularity, the smooth rate of a
        # compliance (energy) with quad9 is h^(2 p) = h^4
        assert order.min() > 3.4 and order.max() < 4.3, order
    else:
        # the clamped corner's singularity takes over: rate -> 2 lambda (= 1.48 for nu = 0.35)
        rate = 2 * williams_clamped_free(nu)
        assert order[-1] == pytest.approx(rate, abs=0.2), (order, rate)
        assert np.all(order > rate - 0.2)


# --- 8. tangent consistency ---------------------------------------------------------------
@pytest.mark.parametrize(
    "law,plane",
    [("svk", "stress"), ("neo-hookean", "stress"), ("svk", "strain"), ("neo-hookean", "strain")],
)
@pytest.mark.parametrize("start_on_ground", [True, False])
def test_gradient_and_hessian_match_finite_differences(law, plane, start_on_ground):
    arc = Arc((2.0, 1.0), 4.0, math.radians(-30.0), math.radians(150.0))
    mech = cantilever(arc, 0.4, start_on_ground=start_on_ground)
    assert (mech.flexures[0].start_body == "1") == start_on_ground
    conn = ContinuumConnector(mech.flexures[0], mech, 0, law=law, plane=plane)
    rng = np.random.default_rng(3)
    # a state far from rest: everything turned by 0.7 rad and shifted, then body b
    # moved a little more and the free nodes perturbed (elements stay valid)
    rot, shift = (
        np.array([[math.cos(0.7), -math.sin(0.7)], [math.sin(0.7), math.cos(0.7)]]),
        np.array([0.2, -0.1]),
    )
    pa, pb = (np.array([*(rot @ p[:2] + shift), 0.7]) for p in rest_poses(mech))
    free = conn.mesh.nodes[conn.free_nodes]
    internal = (free @ rot.T + shift - free).ravel()
    z = np.concatenate(
        [pa, pb + [0.05, -0.03, 0.05], internal + 0.005 * rng.standard_normal(conn.n_internal)]
    )

    def ev(v):
        return conn.evaluate(v[:3], v[3:6], v[6:])

    _, g, H = ev(z)
    H = local_hessian(conn, H).toarray()
    # central differences: truncation ~ step^2 * third derivative ~ 1e-12 relative,
    # round-off ~ 1e-16 |f| / step ~ 1e-10 relative; 1e-6 leaves a wide margin
    step = 1e-6
    directions = [np.eye(z.size)[k] for k in range(6)] + [rng.standard_normal(z.size)]
    for v in directions:
        ep, gp, _ = ev(z + step * v)
        em, gm, _ = ev(z - step * v)
        assert (ep - em) / (2 * step) == pytest.approx(g @ v, abs=1e-6 * np.abs(g).max())
        np.testing.assert_allclose(
            (gp - gm) / (2 * step), H @ v, rtol=0, atol=1e-6 * np.abs(H @ v).max()
        )
    np.testing.assert_allclose(H, H.T, rtol=0, atol=1e-12 * np.abs(H).max())


@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_svk_tangent_blocks_equal_the_general_contraction(plane):
    # the closed form against Law.tangent_blocks' contraction of the law's own CC over random
    # deformation gradients and weights: the same sums in another order, round-off only
    # (1e-16 of the largest block entry; 1e-13 allowed)
    from flexval.validation.continuum.material import Law

    law = make_law("svk", plane, E_MOD, NU)
    rng = np.random.default_rng(11)
    F = np.eye(2) + 0.3 * rng.standard_normal((5, 9, 2, 2))
    weight = rng.uniform(0.1, 2.0, (5, 9))
    _, _, CC = law(np.einsum("...mi,...mj->...ij", F, F))
    closed, general = law.tangent_blocks(F, CC, weight), Law.tangent_blocks(law, F, CC, weight)
    np.testing.assert_allclose(closed, general, rtol=0, atol=1e-13 * np.abs(general).max())
