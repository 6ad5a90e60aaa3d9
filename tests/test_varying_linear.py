"""``ee`` and ``dcmm:N`` on flexures whose section varies or whose centre line is a spline,
against independent references: the Euler-Bernoulli compliance integrals of each notch
contour by scipy's quad, the closed forms of a linearly tapered cantilever, a quad of the
tapered arc's Castigliano integrals, and the arc a spline through its points approximates.

Small loads: the models' responses are linear to about the load's relative size
(1e-6 here), so every comparison holds to 1e-5 unless said otherwise; the brief's
bound is 0.3 %."""

import math

import numpy as np
import pytest
from builders import tip_force, tip_moment
from scipy.integrate import quad

from flexval.geometry import Arc, Material, Section, Segment
from flexval.geometry.mechanism import FlexureSpec, assemble
from flexval.geometry.profiles import LinearTaper, NotchProfile
from flexval.geometry.shapes import Spline
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.models import run_reduced

E, NU, DEPTH = 2000.0, 0.3, 1.5
MATERIAL = Material(E, NU)

NOTCHES = {
    "circular": NotchProfile("circular", 0.1, 1.0, 2.0),
    "elliptical": NotchProfile("elliptical", 0.1, 1.0, 2.0),
    "corner-filleted": NotchProfile("corner-filleted", 0.1, 0.7, 2.0, fillet_radius=0.3),
    "power": NotchProfile("power", 0.1, 1.0, 2.0, exponent=3.0),
}


def clamped(shape, section, target=None):
    """The flexure clamped to ground "g" at its start, free body "t" at its end."""
    ends = shape.end_points
    spec = FlexureSpec("f", shape, ("g", "t"), section, start_body="g")
    point = ends[1] if target is None else np.asarray(target, float)
    return assemble([spec], "g", ends[0][None], MATERIAL, "t", point)


def response(mech, model: str, case) -> np.ndarray:
    """(ux, uy, rotation) of the target at full load, mm and rad."""
    lp = run_reduced(mech, parse_model(model), case)
    assert lp.converged and all(lp.valid)
    return np.array([lp.dx[-1], lp.dy[-1], lp.rotation[-1]])


def notch_rotational_compliance(profile: NotchProfile) -> float:
    """∫ ds / EI over the notch by quad, 1/(N mm)."""

    def integrand(s):
        return 12.0 / (E * DEPTH * float(profile.thickness(s)) ** 3)

    points = sorted({*profile.breakpoints, 0.5 * profile.length})
    return quad(integrand, 0.0, profile.length, points=points, epsabs=0.0, epsrel=1e-12, limit=400)[
        0
    ]


@pytest.mark.parametrize("contour", NOTCHES)
@pytest.mark.parametrize("model", ["ee[eb]", "dcmm:1[eb]", "dcmm:3[eb]"])
def test_notch_rotation_under_a_moment_is_the_euler_bernoulli_integral(contour, model):
    """Measured: within 6e-15 relative for every contour and model (bound: the load's 1e-6)."""
    profile = NOTCHES[contour]
    axis = np.array([math.cos(0.4), math.sin(0.4)]) * profile.length
    mech = clamped(Segment((1.0, 2.0), tuple(axis + [1.0, 2.0])), Section(DEPTH, 0.1, profile))
    moment = 1e-3
    rotation = response(mech, model, tip_moment(moment, levels=2))[2]
    assert rotation == pytest.approx(moment * notch_rotational_compliance(profile), rel=1e-6)


def test_notch_tip_force_is_castiglianos_integral():
    """Transverse and axial tip force on a circular notch: ∫ (L - s)^2 / EI and ∫ 1 / EA."""
    profile = NOTCHES["circular"]
    mech = clamped(Segment((0.0, 0.0), (2.0, 0.0)), Section(DEPTH, 0.1, profile))
    L = profile.length

    def integral(f):
        return quad(f, 0.0, L, points=[0.5 * L], epsabs=0.0, epsrel=1e-12, limit=400)[0]

    h = profile.thickness
    bending = integral(lambda s: 12.0 * (L - s) ** 2 / (E * DEPTH * float(h(s)) ** 3))
    axial = integral(lambda s: 1.0 / (E * DEPTH * float(h(s))))
    force = 1e-4
    for model in ("ee[eb]", "dcmm:1[eb]", "dcmm:4[eb]"):  # beam theory's own integrals
        uy = response(mech, model, tip_force(mech, 0.0, force, levels=2))[1]
        ux = response(mech, model, tip_force(mech, force, 0.0, levels=2))[0]
        assert uy == pytest.approx(force * bending, rel=1e-5)
        assert ux == pytest.approx(force * axial, rel=1e-6)


def tapered_cantilever(h0: float, h1: float, L: float) -> dict[str, float]:
    """Closed forms of a cantilever whose thickness runs linearly from h0 (clamp) to h1 (tip).

    With r = h1 / h0 and h(s) = h0 + (h1 - h0) s / L, integrating M / EI
    (x = h(s) as the variable):

        tip force P:   deflection 12 P L^3 / (E b h0^3) (3/2 - 2 r + r^2/2 + ln r) / (r - 1)^3,
                       rotation   6 P L^2 / (E b h0^2 h1),
        tip moment M:  rotation   6 M L (r + 1) / (E b h0^3 r^2),

    (each reduces to the uniform beam's P L^3 / 3EI, P L^2 / 2EI, M L / EI at r = 1).
    Per unit load.
    """
    r = h1 / h0
    return {
        "force_deflection": 12.0
        * L**3
        / (E * DEPTH * h0**3)
        * (1.5 - 2.0 * r + 0.5 * r * r + math.log(r))
        / (r - 1.0) ** 3,
        "force_rotation": 6.0 * L**2 / (E * DEPTH * h0**2 * h1),
        "moment_rotation": 6.0 * L * (r + 1.0) / (E * DEPTH * h0**3 * r * r),
    }


@pytest.mark.parametrize("model", ["ee", "dcmm:2", "dcmm:5"])
def test_tapered_cantilever_matches_its_closed_forms(model):
    h0, h1, L = 0.4, 0.15, 12.0
    mech = clamped(Segment((0.0, 0.0), (L, 0.0)), Section(DEPTH, h1, LinearTaper(h0, h1, L)))
    exact = tapered_cantilever(h0, h1, L)
    force, moment = 1e-5, 1e-5
    _, uy, theta = response(mech, model, tip_force(mech, 0.0, force, levels=2))
    assert uy == pytest.approx(force * exact["force_deflection"], rel=1e-5)
    assert theta == pytest.approx(force * exact["force_rotation"], rel=1e-5)
    rotation = response(mech, model, tip_moment(moment, levels=2))[2]
    assert rotation == pytest.approx(moment * exact["moment_rotation"], rel=1e-6)


def test_tapered_arc_matches_a_quadrature_of_castiglianos_integrals():
    """A clamped arc tapered from 0.5 to 0.2 mm: the 3x3 tip compliance of ee (bending, as the
    paper's ellipse of elasticity) against its integral g g^T / EI(s) by quad, and dcmm:4 in
    the small-load limit."""
    arc = Arc((0.0, 0.0), 8.0, math.radians(80.0), math.radians(140.0))
    taper = LinearTaper(0.5, 0.2, arc.length)
    mech = clamped(arc, Section(DEPTH, 0.2, taper))
    tip = arc.end_points[1]

    def g(s):
        x, y = arc.point(s)
        return np.array([y - tip[1], tip[0] - x, 1.0])

    def flexibility(i, j):
        def f(s):
            return g(s)[i] * g(s)[j] * 12.0 / (E * DEPTH * float(taper.thickness(s)) ** 3)

        return quad(f, 0.0, arc.length, epsabs=0.0, epsrel=1e-12, limit=200)[0]

    C = np.array([[flexibility(i, j) for j in range(3)] for i in range(3)])
    load = 1e-5
    for model, rel in (("ee", 1e-6), ("dcmm:4", 1e-4)):
        columns = [
            response(mech, model, tip_force(mech, load, 0.0, levels=2)),
            response(mech, model, tip_force(mech, 0.0, load, levels=2)),
            response(mech, model, tip_moment(load, levels=2)),
        ]
        found = np.array(columns).T / load
        np.testing.assert_allclose(found, C, rtol=rel, atol=rel * np.abs(C).max())


def test_a_spline_through_points_of_an_arc_gives_the_arcs_ee_and_dcmm():
    """The spline through k points of an arc approaches the arc: its ee and dcmm:3 tip
    responses to a force and a moment differ from the arc's by (measured, k = 9, 17, 33, 65)
    2.7e-5, 4.4e-7, 3.3e-8 and 2.3e-9 of the largest, dividing by 60, 13 and 15 at each
    doubling of the points (the interpolation's fourth order, 16, once the not-a-knot ends
    no longer dominate). The bounds leave a factor 3 on the finest gap and 1.5 on the
    slowest division."""
    arc = Arc((0.0, 0.0), 10.0, math.radians(90.0), math.radians(120.0))
    section = Section(DEPTH, 0.3)
    reference = clamped(arc, section)
    case_force = tip_force(reference, 2e-5, -1e-5, levels=2)
    case_moment = tip_moment(1e-4, levels=2)
    gaps = []
    for k in (9, 17, 33):
        spline = Spline(tuple(map(tuple, arc.point(np.linspace(0.0, arc.length, k)))))
        mech = clamped(spline, section)
        gap = 0.0
        for model in ("ee", "dcmm:3"):
            for case in (case_force, case_moment):
                a, b = response(reference, model, case), response(mech, model, case)
                gap = max(gap, float(np.abs(b - a).max() / np.abs(a).max()))
        gaps.append(gap)
    assert gaps[-1] < 1e-7
    assert gaps[0] / gaps[1] > 8.0 and gaps[1] / gaps[2] > 8.0, gaps


def test_linear_stress_of_a_notch_peaks_at_its_thinnest_section():
    """ee's section stress under a moment: 6 M / (b h(s)^2) at every station, largest at t."""
    profile = NOTCHES["circular"]
    mech = clamped(Segment((0.0, 0.0), (2.0, 0.0)), Section(DEPTH, 0.1, profile))
    moment = 1e-3
    lp = run_reduced(mech, parse_model("ee"), tip_moment(moment, levels=2))
    at = np.array(lp.stress_profile["f"]["at"])
    stress = np.array(lp.stress_profile["f"]["stress"])
    expected = 6.0 * moment / (DEPTH * profile.thickness(at * profile.length) ** 2)
    np.testing.assert_allclose(stress, expected, rtol=1e-9)
    assert lp.peak_stress["f"][-1] == pytest.approx(stress.max(), rel=1e-12)


def test_dcmm_mass_of_a_tapered_flexure_is_its_integral():
    """Mass points of dcmm:3 on a tapered segment: total rho ∫ A(s) ds and centre of mass
    ∫ s A ds / ∫ A ds against quad (the lumping keeps both exact at rest)."""
    from flexval.reducedmodels.dcmm.connector import DcmmConnector

    L, density = 12.0, 1.2e-9
    taper = LinearTaper(0.4, 0.15, L)
    mech = clamped(Segment((0.0, 0.0), (L, 0.0)), Section(DEPTH, 0.15, taper))
    connector = DcmmConnector(mech.flexures[0], mech, 3)
    points = connector.mass_points(density)
    mass = float(points.mass.sum())
    centre = (points.mass @ (connector._refs + points.rel)) / mass
    area = quad(lambda s: DEPTH * float(taper.thickness(s)), 0.0, L)[0]
    moment = quad(lambda s: s * DEPTH * float(taper.thickness(s)), 0.0, L)[0]
    assert mass == pytest.approx(density * area, rel=1e-13)
    np.testing.assert_allclose(centre, [moment / area, 0.0], atol=1e-12)
