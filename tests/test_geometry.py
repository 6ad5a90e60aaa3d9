"""Geometry of the built-in scenes against hand derivation, and the ellipse of
elasticity (paper Eqs. 1-4) against an independent quadrature of the elastic
weight's moments along the arc."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from flexval.geometry import Arc, Segment, load_scene
from flexval.geometry.shapes import arc_semi_axes


def test_open_chain_links_match_hand_derivation():
    # e12: centre (0, 3), r = 3, spans 30..270 deg -> (3 cos30, 3 + 3 sin30) and (0, 0)
    mech = load_scene("open_chain").mechanism
    e12 = next(f for f in mech.flexures if f.name == "e12")
    np.testing.assert_allclose(e12.end_point_of("1"), [0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(
        e12.end_point_of("2"), [3 * math.cos(math.radians(30)), 4.5], atol=1e-12
    )
    np.testing.assert_allclose(e12.end_point_of("2"), [2.598, 4.500], atol=5e-4)
    # link 2 joins e12's end to e23's start at polar -150 deg around (9.09, 8.25), r = 3.5
    link2 = mech.bodies["2"].points
    np.testing.assert_allclose(
        link2[1], [9.09 - 3.5 * math.cos(math.radians(30)), 8.25 - 1.75], atol=1e-12
    )
    np.testing.assert_allclose(link2, [[2.598, 4.500], [6.059, 6.500]], atol=5e-4)
    # link 3 joins e23's end (12.59, 8.25) to e34's end at polar 265 deg
    np.testing.assert_allclose(mech.bodies["3"].points[0], [12.59, 8.25], atol=1e-12)
    p = [12.59 + 2.5 * math.cos(math.radians(265)), 15.75 + 2.5 * math.sin(math.radians(265))]
    np.testing.assert_allclose(mech.bodies["3"].points[1], p, atol=1e-12)
    assert mech.target_body == "4" and mech.ground == "1"


def test_closed_chain_is_grounded_at_both_anchors():
    mech = load_scene("closed_chain").mechanism
    ground = mech.bodies["1"].points
    # arc ends lie within 0.01 mm of the paper's anchors (its 2-decimal data)
    np.testing.assert_allclose(ground, [[0.0, 0.0], [100.0, 0.0]], atol=0.01)
    assert sorted(mech.bodies) == ["1", "2", "3", "4"]
    assert {f.name: f.start_body for f in mech.flexures} == {
        "e12": "2",
        "e24": "4",
        "e13": "1",
        "e34": "3",
    }
    # body 4 holds e24 and e34: a loop
    assert len(mech.bodies["4"].points) == 2


def _moments_by_quadrature(arc: Arc):
    """Zeroth, first and second moments of the centre line (uniform elastic weight)."""
    L = arc.length
    m0 = L
    m1 = np.array([quad(lambda s, k=k: arc.point(s)[k], 0, L)[0] for k in range(2)])
    c = m1 / m0
    S = np.array(
        [
            [
                quad(lambda s, i=i, j=j: (arc.point(s)[i] - c[i]) * (arc.point(s)[j] - c[j]), 0, L)[
                    0
                ]
                for j in range(2)
            ]
            for i in range(2)
        ]
    )
    return m0, c, S / m0


@pytest.mark.parametrize("width_deg", [10.0, 90.0, 150.0, 240.0, 270.0, 350.0])
@pytest.mark.parametrize("axis_deg", [-75.0, 0.0, 130.0])
def test_ellipse_of_elasticity_matches_quadrature(width_deg, axis_deg):
    arc = Arc((1.3, -2.0), 3.5, math.radians(axis_deg), math.radians(width_deg))
    EI = 0.175
    ell = arc.ellipse(EI)
    m0, c, S = _moments_by_quadrature(arc)
    assert ell.weight == pytest.approx(m0 / EI, rel=1e-12)
    np.testing.assert_allclose(ell.center, c, atol=1e-10)
    # S = a^2 e1 e1^T + b^2 e2 e2^T (principal second moments per unit weight)
    e1, e2 = ell.axes[:, 0], ell.axes[:, 1]
    S_ell = ell.a**2 * np.outer(e1, e1) + ell.b**2 * np.outer(e2, e2)
    np.testing.assert_allclose(S_ell, S, atol=1e-9 * arc.radius**2)
    assert e1[0] * e2[1] - e1[1] * e2[0] == pytest.approx(1.0)


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def test_ellipse_compliance_is_the_castigliano_compliance_at_the_centre():
    """A unit force along e1 at C displaces C by w b^2 along e1 (bending only)."""
    arc = Arc((0.0, 0.0), 2.0, 0.3, math.radians(200))
    EI = 2.0
    ell = arc.ellipse(EI)
    for k, expected in enumerate([ell.weight * ell.b**2, ell.weight * ell.a**2]):
        F = ell.axes[:, k]
        # M(s) = (p(s) - C) x F ; delta.F = int M^2 / EI ds
        m2 = quad(lambda s, F=F: _cross(arc.point(s) - ell.center, F) ** 2, 0, arc.length)[0]
        assert m2 / EI == pytest.approx(expected, rel=1e-10)


def test_straight_segment_is_the_zero_curvature_limit():
    L, EI = 10.0, 3.0
    seg = Segment((0.0, 0.0), (L, 0.0))
    ell = seg.ellipse(EI)
    assert ell.weight == pytest.approx(L / EI)
    np.testing.assert_allclose(ell.center, [L / 2, 0.0])
    assert ell.a == pytest.approx(L / math.sqrt(12)) and ell.b == 0.0
    # a very flat arc with the same chord tends to the segment
    for width in [1e-2, 1e-3]:
        r = L / (2 * math.sin(width / 2))
        arc = Arc((L / 2, -r * math.cos(width / 2)), r, math.pi / 2, width)
        ea = arc.ellipse(EI)
        np.testing.assert_allclose(arc.end_points, [[L, 0.0], [0.0, 0.0]], atol=1e-9)
        assert ea.weight == pytest.approx(L / EI, rel=width**2)
        assert ea.a == pytest.approx(ell.a, rel=width**2)
        assert ea.b < 0.1 * width * L
        np.testing.assert_allclose(ea.center, ell.center, atol=width * L)


def test_arc_parametrisation():
    arc = Arc((1.0, 2.0), 2.0, 0.5, 2.0)
    s = np.linspace(0, arc.length, 7)
    p = arc.point(s)
    np.testing.assert_allclose(np.hypot(*(p - [1.0, 2.0]).T), 2.0)
    # tangent is the derivative of the position
    h = 1e-6
    t = (arc.point(s + h) - arc.point(s - h)) / (2 * h)
    np.testing.assert_allclose(t, arc.tangent(s), atol=1e-8)
    parts = arc.split(4)
    np.testing.assert_allclose(parts[0].end_points[0], arc.end_points[0], atol=1e-12)
    np.testing.assert_allclose(parts[-1].end_points[1], arc.end_points[1], atol=1e-12)
    assert sum(q.length for q in parts) == pytest.approx(arc.length)


def test_rigid_transform_keeps_connectivity():
    mech = load_scene("closed_chain").mechanism
    moved = mech.transformed(0.7, np.array([5.0, -3.0]))
    for f, g in zip(mech.flexures, moved.flexures):
        assert f.start_body == g.start_body
        assert g.shape.length == pytest.approx(f.shape.length)
    assert moved.size() == pytest.approx(mech.size())


def _semi_axes_by_quadrature(width: float) -> tuple[float, float]:
    """a/L, b/L of an arc from its compliance integrals, written without cancellation.

    With gamma = width / 2 and t = phi / gamma in [-1, 1] (unit length), the
    variances of the centre line across and along the symmetry axis are
    a^2 = int sin^2(gamma t) dt / (8 gamma^2) and b^2 = gamma^2 / 8 int y^2 dt,
    y = D - 2 (sin(gamma t / 2) / gamma)^2, where D = (gamma - sin gamma) /
    gamma^3 is itself the quadrature int_0^1 2 (sin(gamma v / 2) / gamma)^2 dv:
    every integrand is O(1) however small the arc, so double precision
    quadrature (relative tolerance 2e-14) is an independent reference.
    """
    g = 0.5 * width
    kw = {"epsabs": 0.0, "epsrel": 2e-14, "limit": 200}
    a2 = quad(lambda t: (math.sin(g * t) / g) ** 2, -1.0, 1.0, **kw)[0] / 8.0
    d = quad(lambda v: 2.0 * (math.sin(0.5 * g * v) / g) ** 2, 0.0, 1.0, **kw)[0]
    b2 = (
        g
        * g
        / 8.0
        * quad(lambda t: (d - 2.0 * (math.sin(0.5 * g * t) / g) ** 2) ** 2, -1.0, 1.0, **kw)[0]
    )
    return math.sqrt(a2), math.sqrt(b2)


@pytest.mark.parametrize(
    "width_deg", [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0, 57.0, 114.59, 114.6, 120.0, 180.0, 270.0, 359.0]
)
def test_ellipse_semi_axes_are_accurate_down_to_vanishing_arcs(width_deg):
    # measured worst relative error over 68 widths from 1e-4 to 359 deg: 3.4e-15 (b, just above
    # the series/closed-form switch at 114.59 deg); 1e-14 leaves a 3x margin
    width = math.radians(width_deg)
    np.testing.assert_allclose(
        arc_semi_axes(width), _semi_axes_by_quadrature(width), rtol=1e-14, atol=0.0
    )
    arc = Arc((0.4, -1.0), 7.0, 0.3, width)
    ell = arc.ellipse(2.0)
    np.testing.assert_allclose(
        [ell.a, ell.b],
        np.multiply(arc.length, _semi_axes_by_quadrature(width)),
        rtol=1e-14,
        atol=0.0,
    )


@pytest.mark.parametrize("width_deg", [1e-4, 1e-3, 1e-2])
def test_ellipse_semi_axes_follow_the_flat_arc_limit(width_deg):
    # hand expansion: a^2/L^2 = 1/12 - gamma^2/60 + O(gamma^4), b^2/L^2 = gamma^2/180 - gamma^4/1260
    # + O(gamma^6); the omitted terms are below 1e-15 relative here
    g = 0.5 * math.radians(width_deg)
    a, b = arc_semi_axes(2.0 * g)
    assert a == pytest.approx(math.sqrt(1.0 / 12.0 - g * g / 60.0), rel=1e-15)
    assert b == pytest.approx(g * math.sqrt(1.0 / 180.0 - g * g / 1260.0), rel=1e-15)


SHAPES = [
    Arc((1.3, -2.0), 3.5, 0.4, math.radians(250.0)),
    Arc((0.0, 0.0), 2.0, -2.0, 0.01),
    Segment((1.0, 2.0), (-4.0, 7.5)),
]


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize(
    "angle,shift", [(0.7, (3.0, -1.0)), (-2.5, (0.0, 0.0)), (math.pi, (-8.0, 2.0))]
)
def test_moved_shapes_move_every_point_rigidly(shape, angle, shift):
    moved = shape.moved(angle, np.array(shift))
    s = np.linspace(0.0, shape.length, 9)
    c, si = math.cos(angle), math.sin(angle)
    expected = shape.point(s) @ np.array([[c, -si], [si, c]]).T + shift
    np.testing.assert_allclose(moved.point(s), expected, atol=1e-12 * (1 + np.abs(expected).max()))
    assert moved.length == pytest.approx(shape.length, rel=1e-14)
    assert moved.kind == shape.kind


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("factor", [1e-3, 0.5, 25.0])
def test_scaled_shapes_scale_every_point(shape, factor):
    scaled = shape.scaled(factor)
    s = np.linspace(0.0, shape.length, 9)
    np.testing.assert_allclose(
        scaled.point(s * factor),
        shape.point(s) * factor,
        atol=1e-12 * factor * (1 + np.abs(shape.point(s)).max()),
    )
    assert scaled.width == shape.width


@pytest.mark.parametrize("shape", SHAPES)
def test_symmetry_frame_is_the_ellipse_centre_and_a_right_handed_frame_to_the_start(shape):
    center, e1, e2 = shape.symmetry_frame()
    ell = shape.ellipse(1.0)
    np.testing.assert_allclose(center, ell.center, atol=1e-14 * (1 + np.abs(center).max()))
    assert e1[0] * e2[1] - e1[1] * e2[0] == pytest.approx(1.0)
    # e1 points from the end side to the start side (the arc is symmetric about e2)
    start, end = shape.end_points
    assert (start - end) @ e1 > 0.0 and abs((start - end) @ e2) < 1e-9 * shape.length


@pytest.mark.parametrize(
    "width_deg,h,closes",
    [(358.0, 0.1, True), (350.0, 0.1, False), (300.0, 2.6, True), (300.0, 2.4, False)],
)
def test_arc_closes_on_itself_when_its_ends_are_within_the_thickness(width_deg, h, closes):
    arc = Arc((0.0, 0.0), 2.5, 0.3, math.radians(width_deg))
    gap = float(np.hypot(*(arc.end_points[0] - arc.end_points[1])))
    assert arc.closes_on_itself(h) is closes and (gap <= h) is closes
    assert not Segment((0.0, 0.0), (0.01, 0.0)).closes_on_itself(h)
