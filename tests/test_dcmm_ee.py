"""DCMM_n and EE against independent references: finite-difference tangents,
Castigliano compliance of an arc, the exact pure-moment rotation, the
small-load limit, invariance, closed-chain equilibrium, path independence."""

import math

import numpy as np
import pytest
from builders import cantilever, fd_check, tip_force, tip_moment
from scipy.integrate import quad

from flexval.geometry import Arc, Segment, load_scene
from flexval.reducedmodels import run_reduced
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.dcmm.connector import DcmmConnector, dcmm_kernels
from flexval.reducedmodels.models import build_system


@pytest.mark.parametrize("n", [1, 3])
def test_dcmm_tangent_matches_finite_differences(n):
    mech = cantilever(Arc((0.0, 0.0), 3.0, 0.4, math.radians(240)))
    conn = DcmmConnector(mech.flexures[0], mech, n)
    rng = np.random.default_rng(1)
    ref_a, ref_b = mech.bodies["g"].reference, mech.bodies["t"].reference
    pose_a = np.array([*ref_a + rng.normal(0, 0.3, 2), 0.7])
    pose_b = np.array([*ref_b + rng.normal(0, 0.5, 2), -1.9])
    internal = conn.initial_internal() + rng.normal(0, 0.3, conn.n_internal)
    eg, eh, asym = fd_check(conn, pose_a, pose_b, internal)
    # central differences with h = 1e-6: truncation ~ h^2 * q''' and round-off ~ eps/h
    assert eg < 1e-7 and eh < 1e-6 and asym < 1e-12


@pytest.mark.parametrize("n", [1, 3])
def test_bending_kinematics_tangent_matches_finite_differences(n):
    """A calibrated notch hinge's sub-arcs take their bending kinematics (the centre
    separation g(phi) in the element's displacement): the same exact gradient and Hessian."""
    import dataclasses

    from test_varying_linear import MATERIAL, NOTCHES, clamped

    from flexval.geometry import Section

    profile = NOTCHES["corner-filleted"]
    mech = clamped(
        Segment((0.3, -0.2), (0.3 + profile.length, -0.2)), Section(5.0, profile.t, profile)
    )
    mech = dataclasses.replace(mech, material=dataclasses.replace(MATERIAL, shear_flexible=True))
    conn = DcmmConnector(mech.flexures[0], mech, n)
    assert np.any(conn.parameters[:, 11:13] != 0.0)
    rng = np.random.default_rng(2)
    ref_a, ref_b = mech.bodies["g"].reference, mech.bodies["t"].reference
    pose_a = np.array([*ref_a + rng.normal(0, 0.01, 2), 0.3])
    pose_b = np.array([*ref_b + rng.normal(0, 0.01, 2), 0.9])
    internal = conn.initial_internal() + rng.normal(0, 0.01, conn.n_internal)
    eg, eh, asym = fd_check(conn, pose_a, pose_b, internal)
    assert eg < 1e-7 and eh < 1e-6 and asym < 1e-12


@pytest.mark.parametrize("n", [1, 3])
def test_compiled_energy_is_the_displaced_compliance_quadratic_form(n):
    """The kernel's energy is 1/2 u^T C^-1 u with u from the paper's matrix form (Eqs. 9-14).

    u = [Q^T R(theta_L)^T (p_F(C) - p_L(C)), theta_F - theta_L], each
    sub-arc's centre of elasticity carried by its two bodies, written with
    rotation matrices and the shape's ellipse, independently of the
    kernel's scalar expansion; random chain poses (0.3 mm, 0.7 rad).
    Round-off only (1e-12 relative).
    """
    mech = cantilever(Arc((0.0, 0.0), 3.0, 0.4, math.radians(240)))
    flexure = mech.flexures[0]
    conn = DcmmConnector(flexure, mech, n)
    rng = np.random.default_rng(5)
    chain = np.vstack(
        [
            [*mech.bodies["g"].reference, 0.0],
            conn.initial_internal().reshape(-1, 3),
            [*mech.bodies["t"].reference, 0.0],
        ]
    )
    refs = chain[:, :2].copy()
    chain += rng.normal(0.0, [0.3, 0.3, 0.7], chain.shape)
    EI = flexure.bending_stiffness(mech.material)

    def rot(t):
        return np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])

    expected = 0.0
    for (lead, follow), (ref_l, ref_f), part in zip(
        zip(chain, chain[1:]), zip(refs, refs[1:]), flexure.shape.split(n)
    ):
        ell = part.ellipse(EI)
        p_l = lead[:2] + rot(lead[2]) @ (ell.center - ref_l)
        p_f = follow[:2] + rot(follow[2]) @ (ell.center - ref_f)
        u = np.append(ell.axes.T @ rot(lead[2]).T @ (p_f - p_l), follow[2] - lead[2])
        expected += 0.5 * u @ np.linalg.solve(ell.compliance(), u)
    energy, _, _ = conn.evaluate(chain[0], chain[-1], chain[1:-1].ravel())
    assert energy == pytest.approx(expected, rel=1e-12)


def test_path_wrenches_are_the_assembled_gradient_on_the_follower():
    """The path pass's sub-arc wrenches are the assembled gradient entries of body b (dcmm:1).

    Two entry points of the compiled kernel, at random poses of the closed
    chain's four flexures: equal to the last bit.
    """
    system = build_system(load_scene("closed_chain").mechanism, parse_model("dcmm:1"))
    group = system.groups[0][0]
    rng = np.random.default_rng(3)
    states = [
        (a + rng.normal(0.0, 0.3, 3), b + rng.normal(0.0, 0.3, 3), i)
        for a, b, i in system.local_states(system.initial_state())
    ]
    stack = group.stack()
    wrenches = dcmm_kernels().sub_arc_wrenches(
        stack.poses([states]), stack.tables.sub_arc_body, stack.parameters
    )[0]
    for c, state, wrench in zip(group.connectors, states, wrenches):
        assert np.array_equal(wrench, c.evaluate(*state)[1][3:6])


def test_end_pass_measures_and_statics_against_direct_numpy_forms():
    """The compiled end pass's chord strains, turns and section forces, from their definitions.

    Closed chain, dcmm:3, random states: each sub-arc's chord (flexure ends
    on the end bodies, cut points between) against its arc length, each
    relative rotation, and a sample's moment -(M + r x F) and normal force
    t . F for its sub-arc's wrench, written with numpy per connector. To
    round-off (1e-12 relative).
    """
    mech = load_scene("closed_chain").mechanism
    system = build_system(mech, parse_model("dcmm:3"))
    group = system.groups[0][0]
    rng = np.random.default_rng(7)
    q0 = system.initial_state()
    levels = [system.local_states(q0 + rng.normal(0.0, 0.05, q0.size)) for _ in range(3)]
    stack = group.stack()
    kernels = dcmm_kernels()
    poses = stack.poses(levels)
    tables = stack.tables
    strain, turn = kernels.chain_measures(
        poses, tables.first, stack.end_rel, tables.sub_arc_body, stack.lengths, tables.sub_arc_start
    )
    forces = group.path_section_forces(levels)
    wrenches = kernels.sub_arc_wrenches(poses, tables.sub_arc_body, stack.parameters)

    def place(pose, rel):
        c, s = math.cos(pose[2]), math.sin(pose[2])
        return pose[:2] + np.array([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]])

    for k, states in enumerate(levels):
        for j, (c, (pose_a, pose_b, internal)) in enumerate(zip(group.connectors, states)):
            chain = np.vstack([pose_a, internal.reshape(-1, 3), pose_b])
            points = np.vstack(
                [place(pose_a, c.end_rel[0]), chain[1:-1, :2], place(pose_b, c.end_rel[1])]
            )
            chords = np.hypot(*np.diff(points, axis=0).T)
            assert strain[k, j] == pytest.approx(
                np.max(chords / c.sub_lengths - 1.0), rel=1e-12, abs=1e-15
            )
            assert turn[k, j] == pytest.approx(np.max(np.abs(np.diff(chain[:, 2]))), rel=1e-12)
            start = tables.sample_start[j]
            for i in range(start, tables.sample_start[j + 1]):
                e, w = tables.sub_arc[i], tables.w[i]
                local = e - tables.sub_arc_start[j]
                lead, follow = chain[local], chain[local + 1]
                point = (1.0 - w) * place(lead, c.sample_rel[i - start, :2]) + w * place(
                    follow, c.sample_rel[i - start, 2:]
                )
                axis = c.sample_tangent[i - start] + (1.0 - w) * lead[2] + w * follow[2]
                fx, fy, m = wrenches[k, e]
                r = follow[:2] - point
                station = np.flatnonzero(tables.order == i)[0] - start
                scale = np.abs(forces[j].moment[k]).max()
                assert forces[j].moment[k, station] == pytest.approx(
                    -(m + r[0] * fy - r[1] * fx), abs=1e-12 * scale
                )
                assert forces[j].axial[k, station] == pytest.approx(
                    math.cos(axis) * fx + math.sin(axis) * fy, abs=1e-12 * scale
                )


def _castigliano_tip_compliance(shape, EI, point):
    """3x3 compliance at ``point`` (rigidly attached to the free end) of a clamped
    flexure, bending only: C_ij = int m_i m_j / EI ds, m = moment of unit loads."""

    def m(s):
        # moment at the section s of unit (Fx, Fy, M) at the load point P:
        # M(s) = (P - p) x F  ->  (p - P)_y, -(p - P)_x, 1
        d = shape.point(s) - point
        return np.array([d[1], -d[0], 1.0])

    C = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            C[i, j] = (
                quad(lambda s, i=i, j=j: m(s)[i] * m(s)[j], 0.0, shape.length, limit=200)[0] / EI
            )
    return C


@pytest.mark.parametrize("width_deg", [60.0, 180.0, 270.0])
def test_ee_equals_castigliano_compliance_of_an_arc(width_deg):
    arc = Arc((1.0, 2.0), 3.0, math.radians(35.0), math.radians(width_deg))
    mech = cantilever(arc, target_offset=(1.5, -0.7))
    EI = mech.flexures[0].bending_stiffness(mech.material)
    C = _castigliano_tip_compliance(arc, EI, mech.target_point)
    spec = parse_model("ee")
    got = []
    for case in [tip_force(mech, 1e-3, 0.0), tip_force(mech, 0.0, 1e-3), tip_moment(1e-3)]:
        lp = run_reduced(mech, spec, case)
        got.append([lp.dx[-1], lp.dy[-1], lp.rotation[-1]])
    # exact up to round-off: both are the same linear bending compliance
    np.testing.assert_allclose(np.array(got).T / 1e-3, C, rtol=1e-7, atol=1e-9 * np.abs(C).max())


def test_dcmm1_pure_moment_rotation_is_exact_at_large_rotation():
    # a pure moment bends an arc into another circle: end rotation M L / EI exactly
    arc = Arc((0.0, 0.0), 2.5, 1.0, math.radians(270))
    mech = cantilever(arc)
    EI = mech.flexures[0].bending_stiffness(mech.material)
    M = 1.2 * EI / arc.length  # 1.2 rad of end rotation
    for n in (1, 2):
        lp = run_reduced(mech, parse_model(f"dcmm:{n}"), tip_moment(M))
        assert lp.rotation[-1] == pytest.approx(M * arc.length / EI, rel=1e-10)


def test_small_load_limit_dcmm_tends_to_ee():
    mech = load_scene("open_chain").mechanism
    case = load_scene("open_chain").load_case("f+")
    ee = run_reduced(mech, parse_model("ee"), case)
    errs = []
    for scale in (1e-2, 1e-3):
        small = case.__class__(
            case.name,
            tuple(c.__class__(**{**c.__dict__, "value": c.value * scale}) for c in case.components),
            3,
        )
        lp = run_reduced(mech, parse_model("dcmm:1"), small)
        errs.append(abs(lp.displacement[-1] / scale - ee.displacement[-1]) / ee.displacement[-1])
    # geometric nonlinearity enters at first order in the load: error ~ load
    assert errs[1] < 0.02 * 0.1 + 1e-9 and errs[1] < 0.2 * errs[0]


@pytest.mark.parametrize("model", ["dcmm:2", "ee"])
def test_rigid_motion_of_the_scene_changes_nothing_but_the_frame(model):
    scene = load_scene("closed_chain")
    case = scene.load_case("f+")
    base = run_reduced(scene.mechanism, parse_model(model), case)
    angle, shift = 2.1, np.array([-40.0, 17.0])
    moved = run_reduced(
        scene.mechanism.transformed(angle, shift),
        parse_model(model),
        case.transformed(angle, shift),
    )
    R = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    d0 = R @ np.array([base.dx, base.dy])
    np.testing.assert_allclose(np.array([moved.dx, moved.dy]), d0, atol=1e-8 * 50)
    np.testing.assert_allclose(moved.rotation, base.rotation, atol=1e-10)


def test_closed_chain_reactions_balance_the_load():
    scene = load_scene("closed_chain")
    for name in ("f+", "f-"):
        case = scene.load_case(name)
        lp = run_reduced(scene.mechanism, parse_model("dcmm:3"), case, record_reactions=True)
        F = case.components[0].vector
        for k, lam in enumerate(np.linspace(0, 1, len(lp.load))):
            R = np.array(lp.reactions[k])
            # moment of the load about the ground reference, at the displaced point
            ref = scene.mechanism.bodies["1"].reference
            p = scene.mechanism.target_point + [lp.dx[k], lp.dy[k]] - ref
            moment = p[0] * lam * F[1] - p[1] * lam * F[0]
            np.testing.assert_allclose(R[:2] + lam * F, 0.0, atol=1e-8 * abs(F).max())
            assert R[2] + moment == pytest.approx(0.0, abs=1e-8 * abs(F).max() * 100)


def test_path_independence_of_the_end_state():
    scene = load_scene("open_chain")
    case = scene.load_case("f+")
    ends = [
        run_reduced(scene.mechanism, parse_model("dcmm:2"), case, levels=n) for n in (2, 11, 41)
    ]
    for lp in ends[1:]:
        assert lp.dx[-1] == pytest.approx(ends[0].dx[-1], rel=1e-8)
        assert lp.rotation[-1] == pytest.approx(ends[0].rotation[-1], rel=1e-8)


def test_straight_segment_dcmm_uses_axial_compliance():
    seg = Segment((0.0, 0.0), (10.0, 0.0))
    mech = cantilever(seg, h=0.5)
    EA = mech.flexures[0].axial_stiffness(mech.material)
    lp = run_reduced(mech, parse_model("dcmm:1"), tip_force(mech, 1e-2, 0.0))
    assert lp.dx[-1] == pytest.approx(1e-2 * 10.0 / EA, rel=1e-9)


def test_measuring_frame_matters_less_as_n_grows():
    """Leader and follower frames are two DCMM variants; both converge to the same
    curve as the sub-arcs' relative rotations shrink (difference ~ 1/n^2)."""
    scene = load_scene("closed_chain")
    case = scene.load_case("f-")
    diffs = []
    for n in (1, 2, 4, 8):
        a = run_reduced(scene.mechanism, parse_model(f"dcmm:{n}"), case)
        b = run_reduced(scene.mechanism, parse_model(f"dcmm:{n}"), case, frame="follower")
        diffs.append(abs(a.displacement[-1] - b.displacement[-1]) / a.displacement[-1])
    assert diffs[0] > 0.05  # DCMM_1: the choice matters (paper discrepancy)
    assert diffs[-1] < 0.01 and diffs[3] < diffs[2] < diffs[1]


def test_one_big_step_does_not_land_on_an_unstable_branch():
    """Open chain f-: a single load step from rest can converge to an unstable
    equilibrium (103 % off); the stability check cuts it and the end state is the
    one the 11-level path reaches."""
    scene = load_scene("open_chain")
    case = scene.load_case("f-")
    one = run_reduced(scene.mechanism, parse_model("dcmm:1"), case, levels=2)
    ref = run_reduced(scene.mechanism, parse_model("dcmm:1"), case)
    assert one.dx[-1] == pytest.approx(ref.dx[-1], rel=1e-8)
    assert one.rotation[-1] == pytest.approx(ref.rotation[-1], rel=1e-8)


def test_every_tangent_storage_counts_the_inertia():
    import scipy.sparse as sp

    from flexval.reducedmodels.core.tangent import BandedTangent, DenseTangent, SparseTangent

    rng = np.random.default_rng(0)
    Q, _ = np.linalg.qr(rng.normal(size=(120, 120)))
    ev = np.concatenate([-np.logspace(-3, 2, 3), np.logspace(-2, 3, 117)])
    A = (Q * ev) @ Q.T
    A = 0.5 * (A + A.T)
    upper = np.zeros((119 + 1, 120), order="F")  # LAPACK upper band form, identity permutation
    for k in range(120):  # k = j - i
        j = np.arange(k, 120)
        upper[119 - k, j] = A[j - k, j]
    assert DenseTangent(A).negative_eigenvalues() == 3
    assert BandedTangent(upper, np.arange(120), 119).negative_eigenvalues() == 3
    assert SparseTangent(sp.csc_matrix(A), 0).negative_eigenvalues() == 3
    assert DenseTangent(np.diag(ev[3:])).negative_eigenvalues() == 0


@pytest.mark.parametrize("seed", range(6))
def test_dense_ldl_gives_the_inertia_and_the_solution_of_saddle_points(seed):
    """The dense LDL^T (dsytrf) of a KKT matrix [[H, B^T], [B, 0]], H indefinite: the count
    of negative eigenvalues is numpy's eigvalsh count (exact here: the spectrum keeps a gap
    of at least 1e-3 from zero) and the solve agrees with numpy's LU to round-off (1e-10
    relative, condition numbers below 1e6 measured)."""
    from flexval.reducedmodels.core.tangent import DenseTangent

    rng = np.random.default_rng(seed)
    n, m = 12, 4
    Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    H = (
        Q * np.concatenate([-rng.uniform(1.0, 5.0, seed % 4), rng.uniform(1.0, 5.0, n - seed % 4)])
    ) @ Q.T
    B = rng.normal(size=(m, n))
    K = np.block([[0.5 * (H + H.T), B.T], [B, np.zeros((m, m))]])
    ev = np.linalg.eigvalsh(K)
    assert np.abs(ev).min() > 1e-3
    rhs = rng.normal(size=n + m)
    for indefinite in (True, False):
        tangent = DenseTangent(K, indefinite)
        assert tangent.negative_eigenvalues() == np.sum(ev < 0)
        assert np.allclose(tangent.solve(rhs), np.linalg.solve(K, rhs), rtol=1e-10, atol=0)


def test_dense_ldl_reads_two_by_two_pivots():
    """A zero diagonal forces a 2 x 2 pivot: [[0, 1], [1, 0]] (eigenvalues -1, 1), beside
    3 and the block [[0, 2], [2, -3]] (eigenvalues 1 and -4): two negative eigenvalues."""
    from flexval.reducedmodels.core.tangent import DenseTangent

    K = np.zeros((5, 5))
    K[0, 1] = K[1, 0] = 1.0
    K[2, 2] = 3.0
    K[3, 4] = K[4, 3] = 2.0
    K[4, 4] = -3.0
    tangent = DenseTangent(K, indefinite=True)
    assert tangent.negative_eigenvalues() == 2
    assert (tangent._ldl[1] < 0).any()  # a 2 x 2 block was read
    rhs = np.arange(1.0, 6.0)
    assert np.allclose(tangent.solve(rhs), np.linalg.solve(K, rhs), rtol=1e-14, atol=0)


@pytest.mark.parametrize("n", [1, 3])
def test_parts_of_a_kept_centre_line_are_those_computed_anew(n):
    """The parts, windows and ellipses kept per centre line (a tolerance study's copies share
    it) are bit for bit each part's own ellipse(EI), for any section; their arrays are
    read-only, so no copy can change another's; two connectors of one flexure, the second
    from the kept geometry, are equal in every array."""
    import dataclasses

    from flexval.reducedmodels.dcmm.subarcs import sub_arcs

    mech = load_scene("open_chain").mechanism
    for flexure in mech.flexures:
        for scale in (1.0, 0.97):
            f = dataclasses.replace(flexure, section=flexure.section.scaled(scale))
            EI = f.bending_stiffness(mech.material)
            length = f.shape.length
            windows = [length * k / n for k in range(n)] + [length]
            parts = f.shape.split(n)
            for sub, part, s0, s1 in zip(
                sub_arcs(f, mech.material, n), parts, windows, windows[1:]
            ):
                fresh = part.ellipse(EI)
                assert sub.shape == part and (sub.start, sub.end) == (s0, s1)
                assert sub.ellipse.weight == fresh.weight
                assert (sub.ellipse.a, sub.ellipse.b) == (fresh.a, fresh.b)
                assert np.array_equal(sub.ellipse.center, fresh.center)
                assert np.array_equal(sub.ellipse.axes, fresh.axes)
                assert not sub.ellipse.center.flags.writeable
                assert not sub.ellipse.axes.flags.writeable
    first, second = (DcmmConnector(mech.flexures[0], mech, n) for _ in range(2))
    for name, value in vars(first).items():
        if isinstance(value, np.ndarray):
            assert np.array_equal(value, getattr(second, name)), name
    with pytest.raises(ValueError):
        second.sample_tangent[0] = 0.0


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("frame", ["leader", "follower"])
def test_a_chains_kept_geometry_is_the_arcs_closed_form(n, frame):
    """The cut bodies and the flexure's ends of a DCMM chain, which copies of a study over
    sections share (read-only), against the arc's own parametrisation: the cuts at k L / n
    from the end the chain starts at, the ends relative to their bodies' reference points."""
    import dataclasses

    mech = load_scene("open_chain").mechanism
    for flexure in mech.flexures:
        arc = flexure.shape
        first = DcmmConnector(flexure, mech, n, frame=frame)
        forward = flexure.start_body == first.bodies[0]
        s = arc.length * np.arange(1, n) / n
        if not forward:
            s = arc.length - s
        phi = arc.start_angle + s / arc.radius
        cuts = np.column_stack([np.cos(phi), np.sin(phi)]) * arc.radius + np.array(arc.center)
        assert np.allclose(first._cuts, cuts.reshape(-1, 2), rtol=0, atol=1e-12)
        ends = [arc.point(0.0), arc.point(arc.length)]
        if not forward:
            ends = ends[::-1]
        for end, body, rel in zip(ends, first.bodies, first.end_rel):
            assert np.allclose(end - mech.bodies[body].reference, rel, rtol=0, atol=1e-12)
        thinner = dataclasses.replace(flexure, section=flexure.section.scaled(0.9))
        second = DcmmConnector(thinner, mech, n, frame=frame)
        for name in ("_cuts", "sample_rel", "sample_tangent", "sub_lengths"):
            assert getattr(second, name) is getattr(first, name), name
            assert not getattr(first, name).flags.writeable, name
        assert not np.array_equal(second.parameters, first.parameters)  # its own compliance


def test_a_long_chain_is_predicted_and_updated_chordwise_to_the_same_equilibria(monkeypatch):
    """From CHAIN_PREDICTION_FROM sub-arcs the cut bodies are predicted and corrected as a chain
    of chords (the beam's way): the update equals the linear one to first order (so Newton
    stays quadratic), and every level is the equilibrium the coordinate-wise predictor finds,
    in fewer iterations."""
    from flexval.reducedmodels.dcmm import connector as dcmm

    n = dcmm.CHAIN_PREDICTION_FROM + 2
    mech = cantilever(Arc((0.0, 0.0), 3.0, 0.4, math.radians(240)))
    chain = dcmm.dcmm_connector(mech.flexures[0], mech, n)
    assert isinstance(chain, dcmm.DcmmChainConnector)
    rng = np.random.default_rng(3)
    pose_a = np.array([*mech.bodies["g"].reference, 0.0])
    pose_b = np.array([*mech.bodies["t"].reference + [0.2, -0.1], 0.4])
    old = (pose_a, pose_b, chain.initial_internal() + rng.normal(0, 1e-3, chain.n_internal))
    direction = rng.normal(0.0, 1.0, 6 + chain.n_internal)
    gaps = []
    for h in (1e-3, 1e-4):
        step = h * direction
        new = (pose_a + step[:3], pose_b + step[3:6], old[2] + step[6:])
        gaps.append(np.abs(chain.update_internal(old, new) - new[2]).max())
    assert gaps[1] < gaps[0] / 50  # second order: a tenth of the step, a hundredth of the gap

    scene = load_scene("open_chain")
    spec = parse_model(f"dcmm:{n}")
    for case in scene.load_cases:
        chordwise = run_reduced(scene.mechanism, spec, case)
        with monkeypatch.context() as m:
            m.setattr(dcmm, "CHAIN_PREDICTION_FROM", 10**9)  # every chain coordinate-wise
            plain = run_reduced(scene.mechanism, spec, case)
        for key in ("dx", "dy", "rotation"):
            np.testing.assert_allclose(getattr(chordwise, key), getattr(plain, key), atol=1e-7)
        assert chordwise.stats["newton_iterations"] <= plain.stats["newton_iterations"]
