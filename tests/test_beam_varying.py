"""``beam:N`` on flexures whose section varies: linear tapers and notch hinges.

References, each independent of the code under test: Castigliano's tip
compliance and the elements' flexibilities by scipy.integrate.quad, the
exact large rotation of a straight beam under an end moment (every element
carries the same moment), its deflected shape by solve_ivp, observed
orders of convergence, central differences of the energy, and the
uniform flexure for a taper of equal ends. Notch hinges are run as plain
Euler-Bernoulli beams (``[eb]``): these are beam theory's references; the
calibrated default is tested against the continuum (tests/test_notch_correction.py).
Units: mm, N, MPa, N mm, rad.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from flexval.geometry import Arc, Force, LoadCase, Material, Moment, Section, Segment
from flexval.geometry.mechanism import Body, Flexure, Mechanism
from flexval.geometry.profiles import LinearTaper, NotchProfile
from flexval.geometry.shapes import Spline
from flexval.reducedmodels import LoadControl, build_system, run_reduced, trace
from flexval.reducedmodels.beam.elements import SHEAR_CORRECTION, BeamConnector
from flexval.reducedmodels.beam.varying import element_stiffness, graded_stations, station_density
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.system import local_hessian
from flexval.reducedmodels.core.validity import MAX_STRAIN

MATERIAL = Material(2000.0, 0.3)
NOTCH_LENGTH, WAIST, DEPTH = 10.0, 0.5, 4.0
NOTCHES = {
    "circular": NotchProfile("circular", WAIST, 5.0, NOTCH_LENGTH),
    "elliptical": NotchProfile("elliptical", WAIST, 5.0, NOTCH_LENGTH),
    "corner-filleted": NotchProfile("corner-filleted", WAIST, 4.5, NOTCH_LENGTH, fillet_radius=2.0),
    "power": NotchProfile("power", WAIST, 5.0, NOTCH_LENGTH, exponent=3.0),
}
STRAIGHT = Segment((0.0, 0.0), (20.0, 0.0))
STRAIGHT_TAPER = Section(DEPTH, 0.4, LinearTaper(0.8, 0.4, STRAIGHT.length))
ARC = Arc((5.0, 2.0), 10.0, 0.3, np.radians(240.0))  # L = 41.9 mm
ARC_TAPER = Section(2.0, 0.3, LinearTaper(0.6, 0.3, ARC.length))

NEWTON_TOL = 1e-8
"""Relative agreement of a converged path with a reference the model reproduces exactly:
Newton stops at a residual that leaves up to 2.5e-9 (measured below: the tapers'
compliances at N = 1 to 10, the notches' rotations at N = 8 to 32); quadrature and
rounding leave below 1e-12."""


def cantilever(shape, section: Section, offset=(0.0, 0.0)) -> Mechanism:
    """``shape`` clamped to the ground "g" at its start, carrying body "t" at its end.

    ``offset`` (mm) moves the tip body's reference point off the flexure's
    end (its end node's rigid attachment then has a lever); the target is the end.
    """
    start, end = shape.end_points
    bodies = {
        "g": Body("g", np.array([start]), is_ground=True),
        "t": Body("t", np.array([end + np.asarray(offset, float), end])),
    }
    flexure = Flexure("f", shape, ("g", "t"), "g", section)
    return Mechanism(bodies, (flexure,), "g", MATERIAL, "t", np.array(end, float))


def notch(contour: str) -> Mechanism:
    """A straight notch hinge of ``contour`` along x as a cantilever."""
    shape = Segment((0.0, 0.0), (NOTCH_LENGTH, 0.0))
    return cantilever(shape, Section(DEPTH, WAIST, NOTCHES[contour]))


def force_case(mech: Mechanism, fx: float, fy: float, levels: int = 2) -> LoadCase:
    """Dead force (fx, fy), N, at the target point."""
    angle, size = float(np.arctan2(fy, fx)), float(np.hypot(fx, fy))
    return LoadCase("F", (Force("t", mech.target_point, angle, size),), levels)


def moment_case(value: float, levels: int = 2) -> LoadCase:
    """Moment (N mm) on the tip body."""
    return LoadCase("M", (Moment("t", value),), levels)


def tip(mech: Mechanism, model: str, case: LoadCase) -> np.ndarray:
    """(dx, dy, rotation) of the target at full load, mm and rad."""
    lp = run_reduced(mech, parse_model(model), case)
    return np.array([lp.dx[-1], lp.dy[-1], lp.rotation[-1]])


def integral(f, a: float, b: float, breaks=()) -> float:
    """scipy quad to 1e-13 relative, split at the ``breaks`` inside (a, b)."""
    inner = [p for p in breaks if a < p < b]
    return quad(f, a, b, points=inner or None, epsabs=0.0, epsrel=1e-13, limit=400)[0]


def stiffness(section: Section, s) -> tuple[float, float, float]:
    """EI (N mm^2), EA (N) and kGA (N) at arc length s from h(s) = section.thickness_at(s)."""
    E, G, h = MATERIAL.youngs_modulus, MATERIAL.shear_modulus, float(section.thickness_at(s))
    area = section.depth * h
    return E * area * h * h / 12.0, E * area, SHEAR_CORRECTION * G * area


def castigliano(shape, section: Section, shear: bool = False) -> np.ndarray:
    """Tip compliance (3, 3) of the cantilever by quad of b b^T / EI, / EA (and / kGA).

    The section at s carries M = M0 + (P_L - P(s)) x F, N = F . t and
    V = F . n for tip loads (Fx, Fy, M0) at the end point P_L.
    """
    L = shape.length
    end = shape.point(L)

    def integrand(s, i, j):
        lever = end - shape.point(s)
        a = float(shape.tangent_angle(s))
        t = np.array([np.cos(a), np.sin(a), 0.0])
        bm, bv = np.array([-lever[1], lever[0], 1.0]), np.array([-t[1], t[0], 0.0])
        EI, EA, kGA = stiffness(section, s)
        return bm[i] * bm[j] / EI + t[i] * t[j] / EA + (bv[i] * bv[j] / kGA if shear else 0.0)

    return np.array(
        [
            [integral(lambda s, i=i, j=j: integrand(s, i, j), 0.0, L) for j in range(3)]
            for i in range(3)
        ]
    )


def compliance(mech: Mechanism, model: str, reference: np.ndarray) -> np.ndarray:
    """The model's tip compliance (3, 3): the response to a small Fx, Fy and M per unit load.

    Each load moves the tip along itself by 1e-6 of the flexure's length (or
    turns it by 1e-6 rad) by the ``reference`` compliance, and is applied both
    ways: the difference of the two responses has no quadratic part (the
    foreshortening, 1e-6 of the response), its cubic part is ~1e-12 of it and
    the rounding of the node positions (~1e-15 mm) ~1e-10.
    """
    length = mech.flexures[0].shape.length
    sizes = 1e-6 * np.array([length, length, 1.0]) / np.diag(reference)

    def response(k: int, sign: float) -> np.ndarray:
        size = sign * sizes[k]
        cases = (force_case(mech, size, 0.0), force_case(mech, 0.0, size), moment_case(size))
        return tip(mech, model, cases[k])

    return np.column_stack(
        [(response(k, 1.0) - response(k, -1.0)) / (2.0 * sizes[k]) for k in range(3)]
    )


def column_error(got: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Each column's largest deviation relative to the column's largest entry."""
    return np.abs(got - ref).max(axis=0) / np.abs(ref).max(axis=0)


def eb_rotation_compliance(profile) -> float:
    """Integral of ds / EI over a notch, 1/(N mm), by quad."""
    section = Section(DEPTH, WAIST, profile)
    return integral(
        lambda s: 1.0 / stiffness(section, s)[0], 0.0, profile.length, profile.breakpoints
    )


def observed_order(values) -> float:
    """log2 of the ratio of successive differences of values at N, 2N, 4N."""
    a, b, c = values
    return float(np.log2(abs(a - b) / abs(b - c)))


# --- 1. the elements' stiffness and their stations -------------------------------------------


@pytest.mark.parametrize("n", [1, 5])
@pytest.mark.parametrize(
    "shape, section",
    [(STRAIGHT, STRAIGHT_TAPER), (ARC, ARC_TAPER)]
    + [
        (Segment((0.0, 0.0), (NOTCH_LENGTH, 0.0)), Section(DEPTH, WAIST, p))
        for p in NOTCHES.values()
    ],
    ids=["taper", "arc-taper", *NOTCHES],
)
def test_element_stiffness_inverts_the_quad_flexibility(shape, section, n):
    # F = l0/ds * int [[(1-xi)^2, -xi(1-xi)], [., xi^2]] / EI + shear term; k_b = F^-1 and
    # EA's part 1 / (l0/ds * int ds / EA); measured agreement 2e-16 - 2e-15 at these N
    stations = graded_stations(shape, section, n)
    points = shape.point(stations)
    chords = np.hypot(*np.diff(points, axis=0).T)
    got = element_stiffness(section, MATERIAL, stations, chords, SHEAR_CORRECTION)
    breaks = section.profile.breakpoints
    for e in range(n):
        a, b = stations[e], stations[e + 1]
        scale = chords[e] / (b - a)

        def part(f, a=a, b=b, scale=scale):
            return scale * integral(f, a, b, breaks)

        def xi(s, a=a, b=b):
            return (s - a) / (b - a)

        shear = part(lambda s: 1.0 / stiffness(section, s)[2]) / chords[e] ** 2
        f11 = part(lambda s: (1.0 - xi(s)) ** 2 / stiffness(section, s)[0]) + shear
        f22 = part(lambda s: xi(s) ** 2 / stiffness(section, s)[0]) + shear
        f12 = -part(lambda s: xi(s) * (1.0 - xi(s)) / stiffness(section, s)[0]) + shear
        expected = np.linalg.inv([[f11, f12], [f12, f22]])
        mine = np.array([[got.k11[e], got.k12[e]], [got.k12[e], got.k22[e]]])
        assert np.abs(mine - expected).max() <= 1e-12 * np.abs(expected).max()
        axial = 1.0 / part(lambda s: 1.0 / stiffness(section, s)[1])
        assert got.k_axial[e] == pytest.approx(axial, rel=1e-12)
        area = integral(lambda s: float(section.area_at(s)), a, b, breaks) / (b - a)
        assert got.mean_area[e] == pytest.approx(area, rel=1e-12)


@pytest.mark.parametrize("contour", list(NOTCHES))
def test_stations_share_the_density_equally_and_gather_at_the_waist(contour):
    # equal shares of rho(s) = (h_min / h)^2 on a straight notch (quad between stations);
    # the elements at the waist are the shortest, those in the blank the longest
    shape, section = (
        Segment((0.0, 0.0), (NOTCH_LENGTH, 0.0)),
        Section(DEPTH, WAIST, NOTCHES[contour]),
    )
    n = 12
    stations = graded_stations(shape, section, n)
    density = station_density(shape, section)
    shares = [
        integral(lambda s: float(density(s)), a, b, section.profile.breakpoints)
        for a, b in zip(stations[:-1], stations[1:])
    ]
    np.testing.assert_allclose(shares, np.mean(shares), rtol=1e-10)
    np.testing.assert_allclose(
        density(np.linspace(0.0, NOTCH_LENGTH, 7)),
        (WAIST / NOTCHES[contour].thickness(np.linspace(0.0, NOTCH_LENGTH, 7))) ** 2,
        rtol=1e-14,
    )
    lengths = np.diff(stations)
    assert min(lengths[n // 2 - 1 : n // 2 + 1]) == lengths.min()
    assert max(lengths[0], lengths[-1]) == lengths.max()
    np.testing.assert_allclose(lengths, lengths[::-1], rtol=1e-9)  # symmetric notch


def test_equal_taper_ends_give_the_uniform_flexure():
    # a taper h -> h is a uniform section by another code path: equal stations (to
    # round-off), k22 = k11 = 4 EI / l0, the same path to 1e-9 relative
    h = 0.45
    uniform, tapered = Section(2.0, h), Section(2.0, h, LinearTaper(h, h, ARC.length))
    stations = graded_stations(ARC, tapered, 12)
    np.testing.assert_allclose(stations, np.linspace(0.0, ARC.length, 13), rtol=0, atol=1e-13)
    case = force_case(cantilever(ARC, uniform), 0.3, -0.2, levels=4)
    for model in ("beam:12", "beam:5[shear]"):
        np.testing.assert_allclose(
            tip(cantilever(ARC, tapered), model, case),
            tip(cantilever(ARC, uniform), model, case),
            rtol=1e-9,
        )


# --- 2. small loads: linear compliance --------------------------------------------------------


@pytest.mark.parametrize("n", [1, 3, 10])
@pytest.mark.parametrize("shear", [False, True], ids=["euler-bernoulli", "timoshenko"])
def test_straight_taper_has_the_exact_linear_compliance_at_any_n(n, shear):
    # each element's flexibility is exact for a straight beam loaded at its nodes, so the
    # tapered cantilever's tip compliance (force and moment) is Castigliano's at any N
    mech = cantilever(STRAIGHT, STRAIGHT_TAPER)
    ref = castigliano(STRAIGHT, STRAIGHT_TAPER, shear)
    got = compliance(mech, f"beam:{n}" + ("[shear]" if shear else ""), ref)
    assert column_error(got, ref).max() < NEWTON_TOL


def test_tapered_arc_compliance_converges_at_second_order():
    # the chord polygon's O(1/N^2) error, as for a uniform arc: measured column errors
    # 0.74 / 0.53 / 0.29 % at N = 20, 0.185 / 0.134 / 0.073 % at N = 40 (orders 1.99-2.0)
    mech = cantilever(ARC, ARC_TAPER)
    ref = castigliano(ARC, ARC_TAPER)
    coarse, fine = (column_error(compliance(mech, f"beam:{n}", ref), ref) for n in (20, 40))
    assert fine.max() < 0.003
    orders = np.log2(coarse / fine)
    assert np.all((orders > 1.9) & (orders < 2.1))


@pytest.mark.parametrize("contour", list(NOTCHES))
def test_notch_rotation_under_a_small_moment_is_the_eb_integral(contour):
    mech = notch(contour)
    moment = 1e-6 / eb_rotation_compliance(NOTCHES[contour])  # 1e-6 rad
    rotation = tip(mech, "beam:8[eb]", moment_case(moment))[2]
    assert rotation == pytest.approx(
        moment * eb_rotation_compliance(NOTCHES[contour]), rel=NEWTON_TOL
    )


# --- 3. large loads: exact rotation, second-order shape -------------------------------------


def elastica_under_moment(profile, moment: float) -> np.ndarray:
    """Tip (dx, dy) of a straight beam along x under an end moment (theta' = M / EI, solve_ivp)."""
    section = Section(DEPTH, WAIST, profile)
    solution = solve_ivp(
        lambda s, y: [moment / stiffness(section, s)[0], np.cos(y[0]), np.sin(y[0])],
        (0.0, profile.length),
        [0.0, 0.0, 0.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-14,
    )
    return np.array([solution.y[1, -1] - profile.length, solution.y[2, -1]])


@pytest.mark.parametrize("contour", list(NOTCHES))
def test_notch_under_a_large_moment(contour):
    # one radian of tip rotation: exact at any N (every element carries the end moment,
    # no shear, no stretch; measured 5e-15); the tip position converges at second order:
    # measured errors / L at N = 8, 16, 32 of 3.1e-4 .. 5.7e-4, 7.4e-5 .. 1.3e-4,
    # 1.8e-5 .. 3.2e-5 over the four contours, observed orders 2.02 - 2.12
    profile = NOTCHES[contour]
    moment = 1.0 / eb_rotation_compliance(profile)
    mech = notch(contour)
    reference = elastica_under_moment(profile, moment)
    errors = []
    for n in (8, 16, 32):
        dx, dy, rotation = tip(mech, f"beam:{n}[eb]", moment_case(moment, levels=5))
        assert rotation == pytest.approx(1.0, rel=NEWTON_TOL)
        errors.append(np.hypot(dx - reference[0], dy - reference[1]) / NOTCH_LENGTH)
    assert errors[1] < 2e-4
    orders = np.log2(np.array(errors[:-1]) / errors[1:])
    assert np.all((orders > 1.9) & (orders < 2.2))


@pytest.mark.parametrize("contour", ["circular", "corner-filleted"])
def test_notch_under_a_large_force_converges_at_second_order(contour):
    # a transverse tip force turning the tip by 0.29 rad: the observed order of the tip
    # rotation at N = 16, 32, 64 (measured 2.017 circular, 2.017 corner-filleted; 2.05
    # and 2.07 at N = 8, 16, 32)
    profile = NOTCHES[contour]
    force = 0.6 / (eb_rotation_compliance(profile) * NOTCH_LENGTH)
    mech = notch(contour)
    case = force_case(mech, 0.0, force, levels=5)
    rotations = [tip(mech, f"beam:{n}[eb]", case)[2] for n in (16, 32, 64)]
    assert 1.9 < observed_order(rotations) < 2.2


# --- 4. tangent, section forces, mass, validity -----------------------------------------------


def test_gradient_and_hessian_of_a_notch_match_central_differences():
    # k22 != k11 on a notch's elements off its middle (not symmetric about their own
    # middles): the tangent's unequal rotation rows against differences of the energy
    # and gradient (h = 1e-5: ~1e-10 observed, as for the uniform beam)
    mech = cantilever(
        Segment((0.0, 0.0), (NOTCH_LENGTH, 0.0)),
        Section(1.0, WAIST, NOTCHES["elliptical"]),
        (2.0, -1.0),
    )
    conn = BeamConnector(mech.flexures[0], mech, 5, shear=True)
    assert np.abs(conn._k22 - conn._k11).max() > 0.5 * np.abs(conn._k11).max()
    rng = np.random.default_rng(3)
    inner = conn.initial_internal().reshape(-1, 3)
    inner += rng.normal(size=inner.shape) * [0.1, 0.1, 0.2]
    q = np.concatenate([[0.1, -0.2, 0.3], [0.2, 0.5, -0.4], inner.ravel()])

    def evaluate(x):
        e, g, h = conn.evaluate(x[:3], x[3:6], x[6:])
        return e, g, local_hessian(conn, h).toarray()

    _, g, H = evaluate(q)
    step = 1e-5
    plus = [evaluate(q + d) for d in step * np.eye(q.size)]
    minus = [evaluate(q - d) for d in step * np.eye(q.size)]
    g_fd = np.array([(p[0] - m[0]) / (2 * step) for p, m in zip(plus, minus)])
    H_fd = np.array([(p[1] - m[1]) / (2 * step) for p, m in zip(plus, minus)])
    assert np.linalg.norm(g_fd - g) / np.linalg.norm(g) < 1e-6
    assert np.linalg.norm(H_fd - H) / np.linalg.norm(H) < 1e-6
    np.testing.assert_array_equal(H, H.T)


def test_section_forces_and_mass_of_a_notch():
    # under an end moment every station (the graded nodes, both sides of each) carries
    # N = 0 and |M| = the moment; the lumped masses add up to rho * int A ds
    mech = notch("circular")
    n = 10
    moment = 1e-3
    case = moment_case(moment)
    system = build_system(mech, parse_model(f"beam:{n}[eb]"))
    *_, last = trace(system, system.loads(case), LoadControl(case.factors()))
    conn = system.connectors[0]
    forces = conn.section_forces(*system.local_states(last.state)[0])
    flexure = mech.flexures[0]
    stations = graded_stations(flexure.shape, flexure.section, n)
    np.testing.assert_allclose(np.unique(forces.at), stations / NOTCH_LENGTH, rtol=0, atol=1e-15)
    np.testing.assert_allclose(forces.axial, 0.0, atol=1e-6 * moment / WAIST)
    np.testing.assert_allclose(np.abs(forces.moment), moment, rtol=NEWTON_TOL)
    density = 7.8e-9  # t/mm^3
    area = integral(lambda s: float(flexure.section.area_at(s)), 0.0, NOTCH_LENGTH)
    assert conn.mass_points(density).mass.sum() == pytest.approx(density * area, rel=1e-12)


def test_outer_fibre_stress_takes_the_thickness_at_each_station():
    # a pure moment M: sigma(s) = 6 M / (b h(s)^2) at every station, largest at the waist
    mech = notch("elliptical")
    moment = 1e-3
    path = run_reduced(mech, parse_model("beam:10[eb]"), moment_case(moment))
    profile = path.stress_profile["f"]
    at = np.asarray(profile["at"])
    expected = 6.0 * moment / (DEPTH * NOTCHES["elliptical"].thickness(at * NOTCH_LENGTH) ** 2)
    np.testing.assert_allclose(profile["stress"], expected, rtol=NEWTON_TOL)
    assert path.peak_stress["f"][-1] == pytest.approx(6.0 * moment / (DEPTH * WAIST**2), rel=1e-8)
    assert path.peak_stress_at["f"][-1] == pytest.approx(0.5, abs=1e-12)


@pytest.mark.parametrize("share", [0.5, 1.5])
def test_validity_checks_the_outer_fibre_strain_at_the_waist(share):
    # the waist's outer fibre strains 6 M / (E b t^2) under an end moment M; an even N puts
    # a station there (the density is symmetric); beyond MAX_STRAIN the state is invalid
    mech = notch("circular")
    moment = share * MAX_STRAIN * MATERIAL.youngs_modulus * DEPTH * WAIST**2 / 6.0
    path = run_reduced(mech, parse_model("beam:10[eb]"), moment_case(moment, levels=3))
    assert path.valid[-1] is (share < 1.0)
    if share > 1.0:
        reason = path.validity[-1]
        assert "outer fibre strained" in reason and f"at {0.5 * NOTCH_LENGTH:.4g} mm" in reason


# --- 5. free-form centre lines -----------------------------------------------------------------


@pytest.mark.parametrize("taper", [False, True], ids=["uniform", "taper"])
@pytest.mark.parametrize("load", ["force", "moment"])
def test_spline_through_points_of_an_arc_is_the_arc(taper, load):
    # nodes at equal (or graded) true arc lengths on the spline through 13 points of the
    # arc: beam:100 gives the arc's beam:100 to within the spline's own distance from the
    # arc (tip displacement and rotation: measured up to 6.4e-5 uniform, 1.4e-4 tapered)
    angles = np.linspace(ARC.start_angle, ARC.end_angle, 13)
    points = np.column_stack([np.cos(angles), np.sin(angles)]) * ARC.radius + ARC.center
    spline = Spline(tuple(map(tuple, points)))
    results = []
    for shape in (ARC, spline):
        profile = LinearTaper(0.6, 0.3, shape.length) if taper else None
        mech = cantilever(shape, Section(2.0, 0.3, profile))
        case = force_case(mech, 0.05, -0.03, 6) if load == "force" else moment_case(0.5, 6)
        results.append(tip(mech, "beam:100", case))
    arc, free = results
    assert np.hypot(*(free - arc)[:2]) < 2e-3 * np.hypot(*arc[:2])
    assert abs(free[2] - arc[2]) < 2e-3 * abs(arc[2])
