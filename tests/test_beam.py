"""The corotational beam connector (``beam:N``) against exact tangents, closed-form
elastica, the exact circle under an end moment, Castigliano's linear compliance
and rigid-motion invariance.

Every reference is independent of the code under test: the elliptic-integral
elastica and the Castigliano quadrature live in ``tests/elastica.py``.
Units: mm, N, MPa, N mm, rad.
"""

import numpy as np
import pytest
from elastica import (
    arc_tip_compliance,
    cantilever_tip_force,
    circle_under_end_moment,
    corotational_chain_under_end_moment,
)
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from flexval.geometry import Arc, Force, LoadCase, Material, Moment, Section, Segment, load_scene
from flexval.geometry.mechanism import FlexureSpec, assemble
from flexval.reducedmodels import LoadControl, build_system, run_reduced, trace
from flexval.reducedmodels.beam.elements import BeamConnector, evenly_spaced
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.chains import chain_kernels
from flexval.reducedmodels.core.extrapolation import hermite_weights, lagrange_weights
from flexval.reducedmodels.core.system import local_hessian
from flexval.reducedmodels.core.tracer import PREDICTOR_STATES

MATERIAL = Material(2000.0, 0.3)
ARC = Arc((5.0, 2.0), 10.0, 0.3, np.radians(240.0))  # r = 10 mm, L = 41.9 mm
SEGMENT = Segment((1.0, 2.0), (30.0, 10.0))  # L = 30.1 mm, inclined


def cantilever(shape, section: Section):
    """A flexure clamped to the ground "g" at its start, carrying body "t" at its end."""
    start, end = shape.end_points
    spec = FlexureSpec("f", shape, ("g", "t"), section)
    return assemble([spec], "g", start[None], MATERIAL, "t", end)


def bending_stiffness(section: Section) -> float:
    """EI of a section in MATERIAL, N mm^2."""
    return MATERIAL.youngs_modulus * section.inertia


def solve(mech, case: LoadCase, n_elements: int, **options):
    """Full load path of ``case`` with beam:N."""
    return run_reduced(mech, parse_model(f"beam:{n_elements}"), case, **options)


# --- 1. consistent tangent and objectivity ---------------------------------------------------


def deformed_state(conn: BeamConnector, mech, turn: float, rng: np.random.Generator):
    """Coordinates after a rigid turn by ``turn`` (rad) plus a random bending state.

    Nodes move by ~5 % of an element length and turn by ~0.3 rad on top of
    the rigid turn, so the local rotations stay far from the +-pi branch cut
    while chords and nodes turn by several radians.
    """
    R = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    shift = np.array([3.0, -7.0])
    length = next(f.shape.length for f in mech.flexures if f.name == conn.name)
    jiggle = 0.05 * length / (conn.n_internal // 3 + 1)
    poses = [
        np.array(
            [
                *(R @ mech.bodies[b].reference + shift + jiggle * rng.normal(size=2)),
                turn + 0.3 * rng.normal(),
            ]
        )
        for b in conn.bodies
    ]
    inner = conn.initial_internal().reshape(-1, 3)
    inner[:, :2] = inner[:, :2] @ R.T + shift + jiggle * rng.normal(size=(len(inner), 2))
    inner[:, 2] = turn + 0.3 * rng.normal(size=len(inner))
    return np.concatenate([*poses, inner.ravel()])


def evaluate(conn: BeamConnector, q: np.ndarray):
    """Energy, gradient and dense Hessian at connector coordinates q."""
    e, g, h = conn.evaluate(q[:3], q[3:6], q[6:])
    return e, g, local_hessian(conn, h).toarray()


def parallel_pair(shape, bodies: tuple[str, str]):
    """``shape`` as a flexure "f" beside a straight one "s", both from the ground "g" to "t".

    The bodies' reference points are the ends of "s", so both ends of "f" sit
    at an offset from them: the rigid end attachments (with their d^2x/dtheta^2
    terms) are exercised. ``bodies`` sets the order in which "f" names them.
    """
    start, end = shape.end_points
    side = Segment(tuple(start + [-6.0, -4.0]), tuple(end + [5.0, -3.0]))  # not crossing "f"
    specs = [
        FlexureSpec("s", side, ("g", "t"), Section(1.0, 0.5)),
        FlexureSpec("f", shape, tuple(bodies), Section(1.0, 0.5)),
    ]
    mech = assemble(specs, "g", np.array([side.start, start]), MATERIAL, "t", end)
    return mech, mech.flexures[1]


@pytest.mark.parametrize("shape", [ARC, SEGMENT], ids=["arc", "segment"])
@pytest.mark.parametrize("shear", [False, True], ids=["euler-bernoulli", "timoshenko"])
@pytest.mark.parametrize("bodies, turn", [(("g", "t"), 2.5), (("t", "g"), -7.0)])
@pytest.mark.parametrize("n_elements", [1, 6])
def test_gradient_and_hessian_match_central_differences(shape, shear, bodies, turn, n_elements):
    # h = 1e-5 (mm and rad): the observed relative errors are ~5e-11 (truncation
    # ~h^2 |f'''| grows to 1e-9 at h = 1e-4, rounding ~eps |f| / h to 5e-10 at
    # 1e-6), so the 1e-6 gate has a wide margin while a missing term fails.
    mech, flexure = parallel_pair(shape, bodies)
    conn = BeamConnector(flexure, mech, n_elements, shear=shear)
    assert conn.bodies == bodies and flexure.start_body == "g"
    q = deformed_state(conn, mech, turn, np.random.default_rng(7))
    _, g, H = evaluate(conn, q)
    h = 1e-5
    plus = [evaluate(conn, q + d) for d in h * np.eye(q.size)]
    minus = [evaluate(conn, q - d) for d in h * np.eye(q.size)]
    g_fd = np.array([(p[0] - m[0]) / (2 * h) for p, m in zip(plus, minus)])
    H_fd = np.array([(p[1] - m[1]) / (2 * h) for p, m in zip(plus, minus)])
    assert np.linalg.norm(g_fd - g) / np.linalg.norm(g) < 1e-6
    assert np.linalg.norm(H_fd - H) / np.linalg.norm(H) < 1e-6
    np.testing.assert_array_equal(H, H.T)


def test_group_evaluates_every_connector_as_alone():
    # the core evaluates all beams of a mechanism in one vectorised call
    # (BeamGroup); element offsets, end attachments and gradient scatter must
    # give each flexure exactly (bit for bit: same operations) its own result,
    # for one element (both end nodes on one element) and many, either body order
    rng = np.random.default_rng(11)
    conns, states = [], []
    for shape, bodies, n_elements in [
        (ARC, ("g", "t"), 6),
        (SEGMENT, ("t", "g"), 1),
        (ARC, ("t", "g"), 3),
    ]:
        mech, flexure = parallel_pair(shape, bodies)
        conns.append(BeamConnector(flexure, mech, n_elements))
        q = deformed_state(conns[-1], mech, 2.0, rng)
        states.append((q[:3], q[3:6], q[6:]))
    energy, gradient, hessian = BeamConnector.group(conns).evaluate(states)
    alone = [c.evaluate(*s) for c, s in zip(conns, states)]
    assert energy == pytest.approx(sum(e for e, _, _ in alone), rel=1e-14)
    np.testing.assert_array_equal(gradient, np.concatenate([g for _, g, _ in alone]))
    np.testing.assert_array_equal(hessian, np.concatenate([h for _, _, h in alone]))


@pytest.mark.parametrize("turn", [1.0, 4.0, -7.0, 20.0])
def test_rigid_motion_is_strain_free(turn):
    # turns beyond pi put the chord rotation on another branch than the nodal
    # rotations; the wrapped local rotations must still vanish. Rounding leaves
    # forces ~ EA * eps * |x| / l0 ~ 1e-14 EA; a branch error gives ~ EI / l0 * 2 pi.
    mech = cantilever(ARC, Section(1.0, 0.5))
    conn = BeamConnector(mech.flexures[0], mech, 9)
    R = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    shift = np.array([-4.0, 11.0])
    poses = [np.array([*(R @ mech.bodies[b].reference + shift), turn]) for b in conn.bodies]
    inner = conn.initial_internal().reshape(-1, 3)
    inner[:, :2] = inner[:, :2] @ R.T + shift
    inner[:, 2] = turn
    e, g, _ = conn.evaluate(*poses, inner.ravel())
    EA = mech.flexures[0].axial_stiffness(MATERIAL)
    assert abs(e) < 1e-12 * EA * ARC.length
    assert np.abs(g[0::3]).max() < 1e-10 * EA and np.abs(g[1::3]).max() < 1e-10 * EA
    assert np.abs(g[2::3]).max() < 1e-10 * EA * ARC.length


def test_connector_layout_follows_the_protocol():
    mech = cantilever(ARC, Section(1.0, 0.5))
    flex = mech.flexures[0]
    conn = BeamConnector(flex, mech, 5)
    assert conn.name == "f" and conn.bodies == ("g", "t") and conn.n_internal == 12
    np.testing.assert_array_equal(conn.internal_is_rotation(), [False, False, True] * 4)
    nodes = conn.initial_internal().reshape(-1, 3)
    np.testing.assert_allclose(
        nodes[:, :2], ARC.point(np.arange(1, 5) * ARC.length / 5), atol=1e-13
    )
    rest = [np.array([*mech.bodies[b].reference, 0.0]) for b in conn.bodies]
    e, g, H = conn.evaluate(*rest, conn.initial_internal())
    assert e == 0.0 and not np.any(g) and local_hessian(conn, H).shape == (18, 18)
    np.testing.assert_allclose(
        conn.shape(*rest, conn.initial_internal()),
        ARC.point(np.linspace(0.0, ARC.length, 6)),
        atol=1e-13,
    )
    with pytest.raises(ValueError, match="elements"):
        BeamConnector(flex, mech, 0)


def _chord_strain(conn: BeamConnector, state) -> np.ndarray:
    """Relative chord stretch (l - l0) / l0 of every element in a connector state."""
    d = np.diff(conn.shape(*state), axis=0)
    return np.hypot(d[:, 0], d[:, 1]) / conn._l0 - 1.0


def test_newton_update_equals_the_linear_update_to_first_order():
    # a retraction: |update(q, eps du) - (q + eps du)| = O(eps^2), so Newton stays
    # quadratic; halving eps must quarter the difference (measured ratio 0.25)
    rng = np.random.default_rng(3)
    mech = cantilever(ARC, Section(1.0, 0.5))
    conn = BeamConnector(mech.flexures[0], mech, 12)
    q = deformed_state(conn, mech, 0.4, rng)
    direction = rng.normal(size=q.size)
    gaps = []
    for eps in (1e-3, 5e-4):
        new = q + eps * direction
        updated = conn.update_internal((q[:3], q[3:6], q[6:]), (new[:3], new[3:6], new[6:]))
        gaps.append(np.abs(updated - new[6:]).max())
    assert gaps[1] / gaps[0] == pytest.approx(0.25, abs=0.02)


def test_newton_update_turns_chords_instead_of_stretching_them():
    # the whole flexure turns by 0.05 rad about the clamp, linearised: q + du puts every
    # node on the tangent of its circle, stretching every chord by turn^2 / 2. The update
    # turns the chords rigidly; what is left is the end body's own linearisation error m
    # (its node too is off its circle), which the closure takes up by bending: the chords
    # keep their lengths but for the closure's axial share, below 1e-2 |m| / L (measured
    # 9.3e-4 |m| / L; spread as a uniform stretch it was |m| / L), and the axial energy
    # drops by more than 1e6 (measured: ratio 6.0e-8; 0.068 with the stretch)
    mech = cantilever(ARC, Section(1.0, 0.5))
    conn = BeamConnector(mech.flexures[0], mech, 20)
    rest = [np.array([*mech.bodies[b].reference, 0.0]) for b in conn.bodies]
    pivot, turn = mech.bodies["g"].reference, 0.05
    inner = conn.initial_internal().reshape(-1, 3)
    tip = rest[1].copy()
    tip[:2] += turn * np.array([-(tip[1] - pivot[1]), tip[0] - pivot[0]])
    tip[2] += turn
    linear = inner.copy()
    linear[:, 0] -= turn * (inner[:, 1] - pivot[1])
    linear[:, 1] += turn * (inner[:, 0] - pivot[0])
    linear[:, 2] += turn
    old, new = (rest[0], rest[1], inner.ravel()), (rest[0], tip, linear.ravel())
    updated = (rest[0], tip, conn.update_internal(old, new))
    stretched, remaining = _chord_strain(conn, new), _chord_strain(conn, updated)
    np.testing.assert_allclose(stretched, turn**2 / 2, rtol=0.01)
    nodes = conn.shape(*old)
    R = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    mismatch = conn.shape(*new)[-1] - (nodes[0] + R @ (nodes[-1] - nodes[0]))
    assert np.abs(remaining).max() <= 1e-2 * np.linalg.norm(mismatch) / conn._l0.sum()
    assert np.sum(remaining**2) < 1e-6 * np.sum(stretched**2)


def castigliano_closure(
    shape, EI: float, EA: float, gap: np.ndarray, s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Displacements (k, 2) and rotations (k,) at arc lengths s of a flexure clamped at both
    ends whose end point is moved by ``gap`` (mm), its end rotation held: linear elasticity.

    The end wrench (F, M0) that does it solves C (F, M0) = (gap, 0) with the
    cantilever's tip compliance C (Castigliano, :func:`elastica.arc_tip_compliance`);
    a point P(s) then moves by int_0^s [M/EI J (P(s) - P) + N/EA t] ds' and turns
    by int_0^s M/EI ds', M = M0 + (P_L - P) x F, N = F . t (Gauss-Legendre).
    """
    wrench = np.linalg.solve(arc_tip_compliance(shape, EI, EA), [*gap, 0.0])
    force, moment = wrench[:2], wrench[2]
    end = shape.point(shape.length)
    xg, wg = np.polynomial.legendre.leggauss(64)
    moved, turned = [], []
    for station in s:
        at, w = 0.5 * station * (xg + 1.0), 0.5 * station * wg
        points = shape.point(at)
        lever = end - points
        M = moment + lever[:, 0] * force[1] - lever[:, 1] * force[0]
        angle = shape.tangent_angle(at)
        t = np.column_stack([np.cos(angle), np.sin(angle)])
        arm = shape.point(station) - points
        bend = (M / EI)[:, None] * np.column_stack([-arm[:, 1], arm[:, 0]])
        moved.append(w @ (bend + ((t @ force) / EA)[:, None] * t))
        turned.append(w @ (M / EI))
    return np.array(moved), np.array(turned)


def test_chain_closure_is_the_clamped_flexures_linear_response_at_second_order():
    # A chain of chords that misses its end node by a small gap is closed the way the
    # flexure itself takes up an end displacement with both ends clamped. Against
    # Castigliano's linear response of the continuous arc, the interior nodes' moves and
    # turns converge at second order in 1/N (measured errors, relative to the largest:
    # moves 1.0e-2, 2.6e-3, 6.3e-4 and turns 4.1e-2, 1.0e-2, 2.5e-3 at N = 10, 20, 40)
    section = Section(1.0, 0.5)
    EI, EA = bending_stiffness(section), MATERIAL.youngs_modulus * section.area
    gap = np.array([0.3, -0.2]) * 1e-6 * ARC.length
    errors = []
    for n in (10, 20, 40):
        s = np.linspace(0.0, ARC.length, n + 1)
        nodes = ARC.point(s)
        chord = np.diff(nodes, axis=0)
        length = np.hypot(chord[:, 0], chord[:, 1])
        ends = nodes.copy()
        ends[-1] += gap
        closed = (
            chain_kernels()
            .close_chains(
                chord, ends, np.zeros(n + 1), np.array([0, n + 1]), length / EI, length / EA
            )
            .reshape(-1, 3)
        )
        moved, turned = castigliano_closure(ARC, EI, EA, gap, s[1:-1])
        errors.append(
            (
                np.abs(closed[:, :2] - nodes[1:-1] - moved).max() / np.abs(moved).max(),
                np.abs(closed[:, 2] - turned).max() / np.abs(turned).max(),
            )
        )
    errors = np.array(errors)
    assert np.all(errors[-1] < [1e-3, 4e-3])
    np.testing.assert_allclose(errors[:-1] / errors[1:], 4.0, rtol=0.05)


@pytest.mark.parametrize("scene_name", ["open_chain", "closed_chain"])
def test_newton_converges_quadratically_along_the_paper_paths(scene_name):
    # beam:100 on the f+ path: from each converged level, the linearised step to the next
    # (the tangent's slope through the connectors' update, as the first sub-step starts),
    # then plain Newton with the connectors' update. Every correction above 1e-9 is at
    # most 20 |previous|^2 (scaled coordinates; measured at most 6.4 on the open chain,
    # 3.8 on the closed one, over 12 and 20 corrections). With the chains closed by a
    # uniform stretch and the end elements stretched by the arc their bodies' nodes run
    # on, the open chain's step to 0.5 took 9.2e-4, 3.0e-3, 1.6e-3, 1.0e-4, 1.2e-4 (ratios
    # up to 4.9e5 along the path; the closed chain's wandered off, up to 8.4e4): the
    # stretch's axial force exceeded the flexures' buckling load and spoiled the
    # tangent's bending directions.
    scene = load_scene(scene_name)
    case = scene.load_case("f+")
    system = build_system(scene.mechanism, parse_model("beam:100"))
    loads = system.loads(case)
    points = list(trace(system, loads, LoadControl(case.factors())))
    ratios = []
    for start, end in zip(points, points[1:]):
        slope = start.tangent.solve(loads.vector(start.state))
        q = system.update(start.state, slope * (end.factor - start.factor))
        steps = []
        for _ in range(5):
            _, g, K = system.assemble(q, loads, end.factor)
            du = K.solve(-g)
            steps.append(np.abs(system.scaled(du)).max())
            q = system.update(q, du)
        ratios += [b / a**2 for a, b in zip(steps, steps[1:]) if b > 1e-9]
    assert len(ratios) >= 12 and max(ratios) < 20.0


def test_predictor_reproduces_a_converged_state_and_a_rigid_motion():
    rng = np.random.default_rng(5)
    mech = cantilever(ARC, Section(1.0, 0.5))
    conn = BeamConnector(mech.flexures[0], mech, 10)
    q = deformed_state(conn, mech, 0.3, rng)
    state = (q[:3], q[3:6], q[6:])
    np.testing.assert_allclose(
        conn.predict_internal([state], [1.0], q[:3], q[3:6]), q[6:], atol=1e-12
    )

    # two states differing by a rigid turn about the origin, extrapolated one step further:
    # the chords keep their lengths, so the prediction is the next rigid turn exactly
    def turned(angle):
        R = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        out = q.copy().reshape(-1, 3)
        out[:, :2] = out[:, :2] @ R.T
        out[:, 2] += angle
        return out.ravel()

    states = [(v[:3], v[3:6], v[6:]) for v in (turned(0.0), turned(0.2))]
    target = turned(0.4)
    predicted = conn.predict_internal(states, [-1.0, 2.0], target[:3], target[3:6])
    np.testing.assert_allclose(predicted, target[6:], atol=1e-12)


def test_chord_predictor_with_the_slope_is_exact_one_degree_higher():
    # The flexure and its end body turn about the clamp by a(f), a quintic in the load factor f:
    # chord lengths stay, chord angles and rotations are a(f) plus constants, so from
    # PREDICTOR_STATES (5) unevenly spaced states and the slope dq/df at the last, the
    # Hermite extrapolation of chords and rotations is exact (the end body's pose given
    # exactly): agreement to round-off, 1e-12 mm and rad. The states alone (a quartic)
    # miss it by more than 1e-6 (measured 9.9e-6; with the slope 1.3e-13).
    mech = cantilever(ARC, Section(1.0, 0.5))
    system = build_system(mech, parse_model("beam:12"))
    _, _, internal, (remember, predict) = system._predictors[0]
    pivot = mech.bodies["g"].reference
    rest = system.initial_state()
    rng = np.random.default_rng(13)
    coefficients = 0.3 * rng.standard_normal(PREDICTOR_STATES + 1)

    def turn(f):
        return sum(c * f**k for k, c in enumerate(coefficients))

    def state(f):
        a = turn(f)
        R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        q = rest.reshape(-1, 3).copy()
        q[:, :2] = (q[:, :2] - pivot) @ R.T + pivot
        q[:, 2] += a
        return q.ravel()

    def slope(f):
        rate = sum(k * c * f ** (k - 1) for k, c in enumerate(coefficients) if k)
        q = state(f).reshape(-1, 3)
        return (
            rate * np.column_stack([-(q[:, 1] - pivot[1]), q[:, 0] - pivot[0], np.ones(len(q))])
        ).ravel()

    factors = [0.1, 0.2, 0.25, 0.275, 0.3][-PREDICTOR_STATES:]
    past = np.array([remember(system.extended(state(f))) for f in factors])
    exact = state(0.35)
    weights, slope_weight = hermite_weights(factors, 0.35)
    with_slope = predict(
        past,
        np.array(weights),
        system.extended(exact),
        np.append(slope(factors[-1]), np.zeros(3)),
        slope_weight,
    )
    assert np.max(np.abs(with_slope - exact[internal])) <= 1e-12
    without = predict(past, np.array(lagrange_weights(factors, 0.35)), system.extended(exact))
    assert np.max(np.abs(without - exact[internal])) > 1e-6


# --- 2. straight cantilever under a dead tip force: the elastica ------------------------------


def test_cantilever_tip_force_matches_elliptic_elastica_at_second_order():
    # L/h = 1000: the stretch the inextensible reference ignores is of relative
    # order (P L^2/EI) h^2 / (12 L^2) <= 1e-6, 20x below the N = 80 error, so it
    # neither spoils the 1e-3 gate nor shifts the observed order by more than 0.05.
    L, section = 100.0, Section(1.0, 0.1)
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), section)
    EI = bending_stiffness(section)
    # 11 levels of 0 .. 10 EI / L^2: the levels 1, 2, 5, 10 are P L^2 / EI = 1, 2, 5, 10
    case = LoadCase(
        "tip", (Force("t", np.array([L, 0.0]), 0.5 * np.pi, 10.0 * EI / L**2),), levels=11
    )
    params = [1, 2, 5, 10]
    exact = np.array([cantilever_tip_force(p) for p in params])  # x/L, y/L, phi0
    errors = {}
    for n in (20, 40, 80):
        lp = solve(mech, case, n)
        x_tip = (L + np.array(lp.dx)[params]) / L
        y_tip = np.array(lp.dy)[params] / L
        rot = np.array(lp.rotation)[params]
        errors[n] = np.abs(y_tip / exact[:, 1] - 1.0)
        if n == 40:
            assert errors[n].max() < 1e-3
            np.testing.assert_allclose(x_tip, exact[:, 0], rtol=1e-3)
            np.testing.assert_allclose(rot, exact[:, 2], rtol=1e-3)
    for coarse, fine in ((20, 40), (40, 80)):
        order = np.log2(errors[coarse] / errors[fine])
        assert np.all((order > 1.7) & (order < 2.3)), order


def test_elliptic_elastica_reference_agrees_with_shooting():
    # independent check of the reference: integrate phi'' = -(P L^2/EI) cos phi on
    # s in [0, 1] from the clamp and shoot on phi'(0) until phi'(1) = 0
    for p in (1, 2, 5, 10):

        def rhs(s, z, p=p):
            return [z[1], -p * np.cos(z[0]), np.cos(z[0]), np.sin(z[0])]

        def ivp(k0):
            return solve_ivp(rhs, (0.0, 1.0), [0.0, k0, 0.0, 0.0], rtol=1e-12, atol=1e-13).y[:, -1]

        phi0, _, x, y = ivp(brentq(lambda k0: ivp(k0)[1], 0.0, p, xtol=1e-14))
        np.testing.assert_allclose(cantilever_tip_force(p), [x, y, phi0], rtol=1e-9)


# --- 3. pure end moment: the exact circle ----------------------------------------------------


@pytest.mark.parametrize("shape", [ARC, SEGMENT], ids=["arc", "segment"])
def test_end_moment_gives_the_discrete_circle_exactly(shape):
    # No force anywhere, so every chord keeps l0 and carries end moments (-M, M):
    # the N-element solution is known in closed form. Newton converges
    # quadratically, so what its last correction leaves is at rounding level
    # (observed <= 1e-12); 1e-9 leaves margin. The end turns by 4 rad (> pi).
    section = Section(1.0, 0.2)
    EI = bending_stiffness(section)
    mech = cantilever(shape, section)
    M = 4.0 * EI / shape.length
    lp = solve(mech, LoadCase("m", (Moment("t", M),), levels=3), 7)
    end = shape.end_points[1] + [lp.dx[-1], lp.dy[-1]]
    x_ref, rot_ref = corotational_chain_under_end_moment(shape, EI, M, 7)
    assert np.hypot(*(end - x_ref)) < 1e-9 * shape.length
    assert lp.rotation[-1] == pytest.approx(rot_ref, rel=1e-9)
    if shape.curvature == 0.0:
        # straight: the chords add up to L, so the end rotation M L / EI is exact
        assert lp.rotation[-1] == pytest.approx(M * shape.length / EI, rel=1e-9)


def test_end_moment_on_arc_converges_to_the_exact_circle_at_second_order():
    # For an arc the discrete end rotation is M sum(l0) / EI, and the chords
    # are shorter than the arc by the factor sin(d/2) / (d/2), d = width / N,
    # i.e. by ~d^2 / 24: neither the rotation nor the position is exact, both
    # converge at O(1/N^2) (observed orders 2.000..2.001).
    section = Section(1.0, 0.2)
    EI = bending_stiffness(section)
    mech = cantilever(ARC, section)
    M = EI * ARC.curvature  # doubles the curvature: end turns by 4.19 rad
    case = LoadCase("m", (Moment("t", M),), levels=3)
    x_exact, rot_exact = circle_under_end_moment(ARC, EI, M)
    pos_err, rot_err = [], []
    for n in (10, 20, 40):
        lp = solve(mech, case, n)
        end = ARC.end_points[1] + [lp.dx[-1], lp.dy[-1]]
        pos_err.append(np.hypot(*(end - x_exact)) / ARC.length)
        rot_err.append(abs(lp.rotation[-1] / rot_exact - 1.0))
        dtheta = ARC.width / n
        assert rot_err[-1] == pytest.approx(1.0 - np.sin(dtheta / 2) / (dtheta / 2), rel=1e-6)
    assert pos_err[-1] < 5e-4
    for err in (pos_err, rot_err):
        order = np.log2(np.array(err[:-1]) / np.array(err[1:]))
        assert np.all((order > 1.9) & (order < 2.1)), order


# --- 4. small-load limit: Castigliano's compliance of the arc -------------------------------


@pytest.mark.parametrize(
    "thickness, shear", [(0.2, False), (2.0, True)], ids=["euler-bernoulli", "timoshenko"]
)
def test_small_load_matches_castigliano_compliance(thickness, shear):
    # At 1e-6 of a load that turns the tip by ~1 rad the response is linear to
    # ~1e-6; the chord discretisation errs by ~(width/N)^2/24 = 2e-5 at N = 200,
    # hence the 1e-4 gate. In the thick (h/L = 0.05) Timoshenko case shear adds
    # ~0.4 % to the compliance, > 20x that gate, so dropping it would fail.
    section = Section(1.0, thickness)
    EI, EA = bending_stiffness(section), MATERIAL.youngs_modulus * section.area
    kGA = 5.0 / 6.0 * MATERIAL.shear_modulus * section.area
    mech = cantilever(ARC, section)
    L = ARC.length
    C = arc_tip_compliance(ARC, EI, EA, kGA if shear else None)
    if shear:
        assert np.abs(C - arc_tip_compliance(ARC, EI, EA)).max() > 2e-3 * np.abs(C).max()
    tip = ARC.end_points[1]
    loads = [
        Force("t", tip, 0.0, 1e-6 * EI / L**2),
        Force("t", tip, 0.5 * np.pi, 1e-6 * EI / L**2),
        Moment("t", 1e-6 * EI / L),
    ]
    weights = np.array([1.0, 1.0, L])  # rotation counted as the tip motion it causes
    for j, load in enumerate(loads):
        lp = solve(mech, LoadCase("small", (load,), levels=2), 200, shear=shear)
        response = np.array([lp.dx[-1], lp.dy[-1], lp.rotation[-1]]) / load.value
        ref = C[:, j]
        assert np.linalg.norm((response - ref) * weights) < 1e-4 * np.linalg.norm(ref * weights)


# --- 5. invariance under a rigid placement of the whole mechanism ---------------------------


@pytest.mark.parametrize("case_name", ["f+", "m+"])
def test_rigidly_moved_mechanism_gives_the_same_response(case_name):
    # Equilibria are frame independent; the converged states differ only by
    # rounding and by what Newton's last (quadratically small) correction
    # leaves along a different step history: observed <= 6e-14 relative.
    scene = load_scene("open_chain")
    case = scene.load_case(case_name)
    angle, shift = 2.0, np.array([37.0, -12.0])
    a = solve(scene.mechanism, case, 30)
    b = solve(scene.mechanism.transformed(angle, shift), case.transformed(angle, shift), 30)
    np.testing.assert_allclose(np.hypot(b.dx, b.dy), np.hypot(a.dx, a.dy), rtol=1e-8, atol=0)
    np.testing.assert_allclose(b.rotation, a.rotation, rtol=1e-8, atol=1e-14)


def test_run_reduced_records_shapes_attached_to_the_bodies():
    scene = load_scene("open_chain")
    lp = run_reduced(
        scene.mechanism,
        parse_model("beam:12"),
        scene.load_case("m+"),
        record_poses=True,
        record_shapes=True,
    )
    mech = scene.mechanism
    for flex in mech.flexures:
        shape = np.array(lp.shapes[flex.name][-1])
        assert shape.shape == (13, 2)
        for body, node in ((flex.start_body, shape[0]), (flex.end_body, shape[-1])):
            x, y, th = lp.poses[body][-1]
            rel = flex.end_point_of(body) - mech.bodies[body].reference
            R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
            np.testing.assert_allclose(node, [x, y] + R @ rel, atol=1e-12)


def test_path_hooks_judge_every_state_as_alone():
    # the recorder asks for a path's section forces and validity in one call
    # (one compiled pass over the states); each state's row must be exactly
    # what the state alone gives, including states outside the valid range
    rng = np.random.default_rng(5)
    mech, flexure = parallel_pair(ARC, ("g", "t"))
    conn = BeamConnector(flexure, mech, 7)
    rest = [np.array([*mech.bodies[b].reference, 0.0]) for b in conn.bodies]
    states = [(*rest, conn.initial_internal())]
    for turn in (0.0, 2.5, -6.0):
        q = deformed_state(conn, mech, turn, rng)
        states.append((q[:3], q[3:6], q[6:]))
    path = conn.path_section_forces(states)
    assert path.axial.shape == path.moment.shape == (len(states), path.at.size)
    for k, state in enumerate(states):
        alone = conn.section_forces(*state)
        np.testing.assert_array_equal(path.at, alone.at)
        np.testing.assert_array_equal(path.axial[k], alone.axial)
        np.testing.assert_array_equal(path.moment[k], alone.moment)
    verdicts = conn.path_validity(states)
    assert verdicts == [conn.validity(*state) for state in states]
    assert any(verdicts) and not all(verdicts)


@pytest.mark.parametrize("n", [1, 2, 3, 7, 10, 100, 999, 2000])
@pytest.mark.parametrize("stop", [1.0, 12.345, np.pi, 40.0 / 3.0])
def test_evenly_spaced_is_linspace_bit_for_bit(n, stop):
    """The nodes' arc lengths and fractions are numpy.linspace's numbers exactly (node positions,
    chords and every result built on them unchanged)."""
    expected = np.linspace(0.0, stop, n + 1)
    got = evenly_spaced(stop, n)
    assert got.dtype == expected.dtype and np.array_equal(got, expected)
