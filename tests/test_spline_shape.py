"""The free-form centre line :class:`Spline`: its arc length against an independent
quadrature, its tangent and curvature against differences of its points, its
split and transforms, and a spline through points of an arc against the arc."""

import math
import pickle

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.interpolate import CubicSpline

from flexval.geometry import Arc, Material, Section
from flexval.geometry.compliance import curve_compliance
from flexval.geometry.shapes import Spline, SplinePiece, quadrature_ellipse

POINTS = ((0.0, 0.0), (4.0, 1.5), (7.0, -1.0), (11.0, 0.5), (13.0, 3.0))


def _reference(points):
    """scipy's spline through the points by chord length, and its speed |r'(u)|."""
    pts = np.asarray(points, float)
    knots = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    spline = CubicSpline(knots, pts, axis=0)
    d = spline.derivative()
    return spline, knots, lambda u: float(np.hypot(*d(u)))


def _arc_length_by_quad(points, u_end):
    _, knots, speed = _reference(points)
    return sum(
        quad(speed, a, min(b, u_end), epsabs=1e-14, epsrel=1e-13)[0]
        for a, b in zip(knots[:-1], knots[1:])
        if a < u_end
    )


def test_arc_length_and_its_inverse_match_quadrature_of_the_speed():
    spline = Spline(POINTS)
    _, knots, _ = _reference(POINTS)
    assert spline.length == pytest.approx(_arc_length_by_quad(POINTS, knots[-1]), abs=1e-12)
    s = np.linspace(0.0, spline.length, 23)
    u = spline.parameter(s)
    by_quad = np.array([_arc_length_by_quad(POINTS, x) for x in u])
    # quad's own accuracy is about 1e-13 here: the map is exact to the brief's 1e-12 mm
    assert np.abs(by_quad - s).max() < 1e-12
    assert np.all(np.diff(u) > 0.0)


def test_points_lie_on_scipys_spline_and_the_ends_are_the_given_points():
    spline = Spline(POINTS)
    reference, _, _ = _reference(POINTS)
    s = np.linspace(0.0, spline.length, 17)
    np.testing.assert_allclose(spline.point(s), reference(spline.parameter(s)), atol=1e-13)
    np.testing.assert_array_equal(spline.point(0.0), POINTS[0])
    np.testing.assert_allclose(spline.point(spline.length), POINTS[-1], atol=1e-12)
    np.testing.assert_array_equal(spline.end_points, [POINTS[0], POINTS[-1]])


def test_three_points_give_the_parabola_through_them():
    """Not-a-knot with three points: one quadratic, so the curvature of y = x^2 / 4."""
    spline = Spline(((-2.0, 1.0), (0.0, 0.0), (2.0, 1.0)))
    s = np.linspace(0.0, spline.length, 9)
    x, y = spline.point(s).T
    np.testing.assert_allclose(y, x**2 / 4.0, atol=1e-12)
    # y = x^2/4 parameterised by chord length is still that parabola
    kappa = 0.5 / (1.0 + (x / 2.0) ** 2) ** 1.5
    np.testing.assert_allclose(spline.curvature_at(s), kappa, rtol=1e-10)


def test_tangent_and_curvature_match_differences_of_the_points():
    spline = Spline(POINTS)
    s = np.linspace(0.5, spline.length - 0.5, 13)
    h = 1e-5
    d = (spline.point(s + h) - spline.point(s - h)) / (2 * h)
    np.testing.assert_allclose(spline.tangent(s), d, atol=1e-8)
    turn = (spline.tangent_angle(s + h) - spline.tangent_angle(s - h)) / (2 * h)
    np.testing.assert_allclose(spline.curvature_at(s), turn, atol=1e-6)
    # unit speed: the parameter is arc length
    np.testing.assert_allclose(np.hypot(*d.T), 1.0, atol=1e-9)


def test_tangent_angle_is_continuous_through_a_full_turn():
    """A spline round most of a circle: the angle grows by the net turning, without 2 pi jumps."""
    phi = np.linspace(0.0, 6.0, 13)
    spline = Spline(tuple(zip(5.0 * np.cos(phi), 5.0 * np.sin(phi))))
    angles = spline.tangent_angle(np.linspace(0.0, spline.length, 400))
    assert np.all(np.diff(angles) > 0.0) and np.diff(angles).max() < 0.1
    # the net turning is the integral of the curvature, (x' y'' - y' x'') / |r'|^2 du
    reference, knots, _ = _reference(spline.points)
    d1, d2 = reference.derivative(), reference.derivative(2)

    def turn_rate(u):
        (x1, y1), (x2, y2) = d1(u), d2(u)
        return (x1 * y2 - y1 * x2) / (x1 * x1 + y1 * y1)

    turning = sum(quad(turn_rate, a, b, epsabs=1e-14)[0] for a, b in zip(knots[:-1], knots[1:]))
    assert spline.width == pytest.approx(turning, abs=1e-12)


def test_split_gives_equal_pieces_that_join():
    spline = Spline(POINTS)
    parts = spline.split(4)
    assert all(isinstance(p, SplinePiece) for p in parts)
    np.testing.assert_allclose([p.length for p in parts], spline.length / 4, rtol=1e-14)
    for p, q in zip(parts, parts[1:]):
        np.testing.assert_array_equal(p.end_points[1], q.end_points[0])
    np.testing.assert_allclose(parts[-1].end_points[1], POINTS[-1], atol=1e-12)
    halves = parts[1].split(2)
    assert halves[1].start == pytest.approx(parts[1].start + parts[1].length / 2, rel=1e-15)
    np.testing.assert_array_equal(halves[1].point(0.1), spline.point(halves[1].start + 0.1))


def test_moved_scaled_and_pickled_splines_are_the_same_curve():
    spline = Spline(POINTS)
    angle, shift = 0.7, np.array([3.0, -2.0])
    moved = spline.moved(angle, shift)
    s = np.linspace(0.0, spline.length, 7)
    c, si = math.cos(angle), math.sin(angle)
    expected = spline.point(s) @ np.array([[c, si], [-si, c]]) + shift
    np.testing.assert_allclose(moved.point(s), expected, atol=1e-12)
    assert moved.length == pytest.approx(spline.length, rel=1e-14)
    assert spline.scaled(2.5).length == pytest.approx(2.5 * spline.length, rel=1e-14)
    copy = pickle.loads(pickle.dumps(spline))
    assert copy == spline
    np.testing.assert_array_equal(copy.point(s), spline.point(s))
    assert moved.parameters() == {"points": [list(p) for p in moved.points]}


@pytest.mark.parametrize("points", [((0, 0), (1, 1)), ((0, 0), (1, 1), (1, 1), (2, 0))])
def test_bad_points_are_refused(points):
    with pytest.raises(ValueError):
        Spline(points)


def test_uniform_ellipse_matches_the_compliance_quadrature():
    """Two implementations of the ellipse (shape's own, curve_compliance) on one spline."""
    spline = Spline(POINTS)
    section, material = Section(1.0, 0.3), Material(2000.0, 0.3)
    EI = material.youngs_modulus * section.depth * section.thickness**3 / 12
    own = spline.ellipse(EI)
    general = curve_compliance(spline, section, material).ellipse
    assert own.weight == pytest.approx(general.weight, rel=1e-14)
    np.testing.assert_allclose(own.center, general.center, atol=1e-12)
    assert own.a == pytest.approx(general.a, rel=1e-12)
    assert own.b == pytest.approx(general.b, rel=1e-11)
    piece = quadrature_ellipse(spline, EI, 2.0, 6.0)
    sub = curve_compliance(spline, section, material, 2.0, 6.0).ellipse
    np.testing.assert_allclose(piece.center, sub.center, atol=1e-12)
    assert piece.a == pytest.approx(sub.a, rel=1e-12)


def _arc_spline(arc: Arc, k: int) -> Spline:
    return Spline(tuple(map(tuple, arc.point(np.linspace(0.0, arc.length, k)))))


def test_a_spline_through_points_of_an_arc_converges_to_the_arc_at_fourth_order():
    """Length, centre of elasticity and semi-axes of the spline through k points of an arc.

    Cubic interpolation is fourth order in the spacing: each doubling of the
    intervals divides every difference by about 16 (measured 2^4.2 to 2^6.5
    from 8 to 32 intervals on this arc); curvature converges at second order.
    """
    arc = Arc((1.0, 2.0), 10.0, 0.7, 2.4)
    exact = arc.ellipse(1.0)
    errors = []
    for k in (9, 17, 33):
        spline = _arc_spline(arc, k)
        ell = spline.ellipse(1.0)
        errors.append(
            [
                abs(spline.length / arc.length - 1.0),
                float(np.abs(ell.center - exact.center).max()) / arc.radius,
                abs(ell.a / exact.a - 1.0),
                abs(ell.b / exact.b - 1.0),
            ]
        )
    errors = np.array(errors)
    order = np.log2(errors[:-1] / errors[1:])
    assert np.all(order > 3.5), order
    assert errors[-1].max() < 2e-7
    np.testing.assert_allclose(ell.axes, exact.axes, atol=1e-7)
    kappa = _arc_spline(arc, 33).curvature_at(np.linspace(0.0, arc.length, 50))
    assert np.abs(kappa * arc.radius - 1.0).max() < 5e-3
