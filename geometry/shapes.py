"""Flexure centre-line shapes: circular arcs, straight segments and free-form splines.

A shape is parametrised by arc length ``s`` in mm, from its *start* point to
its *end* point. For an arc the start is at polar angle ``axis - width/2``
around the centre and the curve runs counterclockwise (paper, Sect. 2.3,
Fig. 3). A :class:`Spline` is the C2 cubic spline through given points,
parametrised by its true arc length. Each shape also gives its ellipse of
elasticity (paper Eqs. 1-4) for a uniform section, the linear bending
compliance data used by the DCMM and EE models (closed forms for arcs and
segments, quadrature for splines; any section law:
:func:`flexval.geometry.compliance.curve_compliance`).

All lengths are mm and all angles are radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar, Protocol

import numpy as np

from .arclength import ArcLengthMap
from .kinematics import rotate
from .profiles import quadrature_panels

_SERIES_TOP = 1.0
"""Largest half-angle gamma (rad) for which :func:`arc_semi_axes` sums Taylor series."""
_K = np.arange(2, 18)
_FACT = np.array([math.factorial(n) for n in range(2 * int(_K[-1]) + 3)], float)
_A2_SERIES = -((-1.0) ** _K) * 4.0 ** (_K - 1) / (2.0 * _FACT[2 * _K + 1])
_B2_SERIES = (-1.0) ** _K * 4.0 ** (_K - 1) * (_K - 1) / _FACT[2 * _K + 2]
_POWERS = 2 * _K - 2  # the power of gamma in each term of the series


def arc_semi_axes(width: float) -> tuple[float, float]:
    """Semi-axes a, b of a uniform arc's ellipse of elasticity, in units of its length L.

    Paper Eqs. 3-4 with r = L / width, gamma = width / 2::

        a^2 / L^2 = (1 - sin(2 gamma) / (2 gamma)) / (8 gamma^2)
        b^2 / L^2 = (1/2 + sin(2 gamma) / (4 gamma) - (sin(gamma) / gamma)^2) / (4 gamma^2)

    These closed forms lose digits to cancellation as the arc flattens
    (b -> 0 like width / sqrt(720); in the r^2 - OC^2 - a^2 form b is lost
    entirely below about 0.01 deg). Up to gamma = 1 rad their Taylor series
    are summed instead, term by term without cancellation::

        a^2 / L^2 = sum_{k>=1} (-1)^(k+1) 4^(k-1) gamma^(2k-2) / (2 (2k+1)!)
        b^2 / L^2 = sum_{k>=2} (-1)^k 4^(k-1) (k-1) gamma^(2k-2) / (2k+2)!

    (16 terms: the first omitted term is below 1e-30 of the sum for
    gamma <= 1). Above gamma = 1 the closed forms cancel at most a factor
    about 40, so both branches stay within a few 1e-15 relative
    (tests/test_geometry.py measures it against quadrature).

    Parameters
    ----------
    width : float
        Arc angle 2 gamma, rad, in [0, 2 pi) (0 for a straight beam).

    Returns
    -------
    a, b : float
        Semi-axes across (a) and along (b) the symmetry axis divided by L
        (dimensionless).
    """
    g = 0.5 * width
    if g <= _SERIES_TOP:  # the k = 1 term of a^2 is 1/12
        powers = g**_POWERS
        a2 = 1.0 / 12.0 + float(_A2_SERIES @ powers)
        b2 = float(_B2_SERIES @ powers)
    else:
        a2 = float((1.0 - np.sin(2.0 * g) / (2.0 * g)) / (8.0 * g**2))
        b2 = float((0.5 + np.sin(2.0 * g) / (4.0 * g) - (np.sin(g) / g) ** 2) / (4.0 * g**2))
    return math.sqrt(a2), math.sqrt(max(b2, 0.0))  # rounded as np.sqrt rounds


def _directions(angle: np.ndarray) -> np.ndarray:
    """Unit vectors (cos, sin) of angles (rad) of any shape, shape (..., 2).

    (``np.stack`` costs more than the trigonometry on the short arrays of a flexure.)
    """
    out = np.empty((*np.shape(angle), 2))
    out[..., 0], out[..., 1] = np.cos(angle), np.sin(angle)
    return out


@dataclass(frozen=True)
class Ellipse:
    """Ellipse of elasticity of a flexure (paper Eqs. 1-5).

    Attributes
    ----------
    weight : float
        Elastic weight w = L / EI in 1/(N mm): the rotational compliance.
    center : ndarray, shape (2,)
        Centre of elasticity C in mm.
    a, b : float
        Semi-axes in mm. ``a`` lies along ``axes[:, 0]`` (e1), ``b`` along
        ``axes[:, 1]`` (e2). For an arc, e2 is the arc's symmetry axis and
        a**2 is the variance of the centre line across it.
    axes : ndarray, shape (2, 2)
        Columns are the unit vectors e1, e2 (a right-handed frame).

    Notes
    -----
    The compliance matrix in the frame {C, e1, e2} is
    ``diag(w b**2, w a**2, w)`` (Eq. 5): a force along e1 is resisted by
    bending with lever arms spread along e2 (variance b**2), and vice versa.
    """

    weight: float
    center: np.ndarray
    a: float
    b: float
    axes: np.ndarray

    def compliance(self) -> np.ndarray:
        """Diagonal compliance diag(w b^2, w a^2, w) in {C, e1, e2} (mm/N, 1/(N mm))."""
        w = self.weight
        return np.diag([w * self.b**2, w * self.a**2, w])


class Shape(Protocol):
    """What every flexure centre line provides (lengths in mm, angles in rad).

    Callers use these members instead of testing for Arc or Segment.
    """

    kind: ClassVar[str]

    @property
    def length(self) -> float: ...

    @property
    def curvature(self) -> float: ...

    @property
    def width(self) -> float: ...

    @property
    def end_points(self) -> np.ndarray: ...

    @property
    def max_thickness(self) -> float: ...

    def point(self, s: np.ndarray | float) -> np.ndarray: ...

    def tangent_angle(self, s: np.ndarray | float) -> np.ndarray: ...

    def tangent(self, s: np.ndarray | float) -> np.ndarray: ...

    def curvature_at(self, s: np.ndarray | float) -> np.ndarray: ...

    def split(self, n: int) -> list[Shape]: ...

    def ellipse(self, bending_stiffness: float) -> Ellipse: ...

    def symmetry_frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...

    def closes_on_itself(self, thickness: float) -> bool: ...

    def moved(self, angle: float, shift: np.ndarray) -> Shape: ...

    def scaled(self, factor: float) -> Shape: ...

    def parameters(self) -> dict: ...


@dataclass(frozen=True)
class Arc:
    """Uniform circular arc given as in the paper (Sect. 2.3, Fig. 3).

    Parameters
    ----------
    center : (float, float)
        Centre O of the circle, mm.
    radius : float
        Radius r, mm (> 0).
    axis : float
        Direction of the arc's symmetry axis from O, rad.
    width : float
        Angular amplitude 2*gamma, rad, in (0, 2*pi).
    """

    center: tuple[float, float]
    radius: float
    axis: float
    width: float

    kind: ClassVar[str] = "arc"

    @property
    def start_angle(self) -> float:
        """Polar angle of the start point around the centre, rad."""
        return self.axis - 0.5 * self.width

    @property
    def end_angle(self) -> float:
        """Polar angle of the end point around the centre, rad."""
        return self.axis + 0.5 * self.width

    @property
    def length(self) -> float:
        """Centre-line length r * width, mm."""
        return self.radius * self.width

    @property
    def curvature(self) -> float:
        """Signed initial curvature 1/r, 1/mm (counterclockwise positive)."""
        return 1.0 / self.radius

    def curvature_at(self, s: np.ndarray | float) -> np.ndarray:
        """Signed curvature 1/r at arc length(s) s (mm), 1/mm (constant)."""
        return np.full(np.shape(s), 1.0 / self.radius)

    def _polar(self, s: np.ndarray | float) -> np.ndarray:
        return self.start_angle + np.asarray(s, dtype=float) / self.radius

    def point(self, s: np.ndarray | float) -> np.ndarray:
        """Point(s) at arc length s (mm) from the start, shape (..., 2), mm."""
        phi = self._polar(s)
        out = _directions(phi)
        out *= self.radius
        out += self.center
        return out

    def tangent_angle(self, s: np.ndarray | float) -> np.ndarray:
        """Direction of the unit tangent (increasing s) at s, rad."""
        return self._polar(s) + 0.5 * np.pi

    def tangent(self, s: np.ndarray | float) -> np.ndarray:
        """Unit tangent(s) at arc length s, shape (..., 2)."""
        return _directions(self.tangent_angle(s))

    @property
    def end_points(self) -> np.ndarray:
        """Start and end points, shape (2, 2), mm (:meth:`point` at 0 and the length, on floats)."""
        (cx, cy), r = self.center, self.radius
        return np.array(
            [
                [cx + r * math.cos(phi), cy + r * math.sin(phi)]
                for phi in (self.start_angle, self.start_angle + self.length / r)
            ]
        )

    def split(self, n: int) -> list[Arc]:
        """The arc cut into n equal sub-arcs, from start to end."""
        dw = self.width / n
        return [
            Arc(self.center, self.radius, self.start_angle + (k + 0.5) * dw, dw) for k in range(n)
        ]

    @property
    def max_thickness(self) -> float:
        """The diameter 2 r, mm: a band at least this thick has no inner edge."""
        return 2.0 * self.radius

    def symmetry_frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Centre of elasticity C (mm) and the unit axes e1, e2 of the arc.

        e2 is the symmetry axis (from the centre towards the apex), e1 =
        R(-90 deg) e2 points to the start end; C lies on e2 at
        r sin(gamma) / gamma from the centre (paper Eqs. 1-2).
        """
        gamma = 0.5 * self.width
        c, s = math.cos(self.axis), math.sin(self.axis)  # floats: a few numbers
        oc = self.radius * math.sin(gamma) / gamma
        return (
            np.array([self.center[0] + oc * c, self.center[1] + oc * s]),
            np.array([s, -c]),
            np.array([c, s]),
        )

    def ellipse(self, bending_stiffness: float) -> Ellipse:
        """Ellipse of elasticity for bending stiffness EI (N mm^2), Eqs. 1-4.

        The semi-axes come from :func:`arc_semi_axes`, accurate to rounding
        down to vanishing arc angles.
        """
        center, e1, e2 = self.symmetry_frame()
        a, b = arc_semi_axes(self.width)
        return Ellipse(
            weight=self.length / bending_stiffness,
            center=center,
            a=self.length * a,
            b=self.length * b,
            axes=np.array([e1, e2]).T,  # columns e1, e2
        )

    def closes_on_itself(self, thickness: float) -> bool:
        """True if the ends are at most ``thickness`` (mm) apart: the solid band would close."""
        return float(np.hypot(*(self.end_points[0] - self.end_points[1]))) <= thickness

    def moved(self, angle: float, shift: np.ndarray) -> Arc:
        """The arc rotated by ``angle`` (rad) about the origin, then shifted by ``shift`` (mm)."""
        c = rotate(angle, np.asarray(self.center)) + shift
        return Arc((float(c[0]), float(c[1])), self.radius, self.axis + angle, self.width)

    def scaled(self, factor: float) -> Arc:
        """The arc with every length (centre, radius) multiplied by ``factor``; angles kept."""
        c = np.asarray(self.center, float) * factor
        return Arc(tuple(map(float, c)), self.radius * factor, self.axis, self.width)

    def parameters(self) -> dict:
        """The scene-file parameters: centre and radius (mm), axis and width (deg)."""
        return {
            "center": list(self.center),
            "radius_mm": self.radius,
            "axis_deg": math.degrees(self.axis),
            "width_deg": math.degrees(self.width),
        }


@dataclass(frozen=True)
class Segment:
    """Straight flexure from ``start`` to ``end`` (the zero-curvature limit), mm."""

    start: tuple[float, float]
    end: tuple[float, float]

    kind: ClassVar[str] = "segment"
    width: ClassVar[float] = 0.0
    """Arc angle, rad: 0, the straight limit of an arc."""
    max_thickness: ClassVar[float] = math.inf
    """Any thickness fits a straight band, mm."""

    @property
    def _vector(self) -> np.ndarray:
        return np.asarray(self.end, dtype=float) - np.asarray(self.start, dtype=float)

    @property
    def length(self) -> float:
        """Length, mm."""
        return float(np.hypot(*self._vector))

    @property
    def curvature(self) -> float:
        """Initial curvature, 0 (1/mm)."""
        return 0.0

    def curvature_at(self, s: np.ndarray | float) -> np.ndarray:
        """Curvature at arc length(s) s (mm): 0, 1/mm."""
        return np.zeros(np.shape(s))

    def point(self, s: np.ndarray | float) -> np.ndarray:
        """Point(s) at arc length s (mm) from the start, shape (..., 2), mm."""
        s = np.asarray(s, dtype=float)
        u = self._vector / self.length
        return np.asarray(self.start, dtype=float) + s[..., None] * u

    def tangent_angle(self, s: np.ndarray | float) -> np.ndarray:
        """Direction of the tangent, rad (constant)."""
        v = self._vector
        return np.full(np.shape(s), np.arctan2(v[1], v[0]))

    def tangent(self, s: np.ndarray | float) -> np.ndarray:
        """Unit tangent(s), shape (..., 2)."""
        return _directions(self.tangent_angle(s))

    @property
    def end_points(self) -> np.ndarray:
        """Start and end points, shape (2, 2), mm."""
        return np.array([self.start, self.end], dtype=float)

    def split(self, n: int) -> list[Segment]:
        """The segment cut into n equal parts, from start to end."""
        p = self.point(np.linspace(0.0, self.length, n + 1))
        return [Segment(tuple(p[k]), tuple(p[k + 1])) for k in range(n)]

    def ellipse(self, bending_stiffness: float) -> Ellipse:
        """Ellipse of elasticity (degenerate: b = 0), EI in N mm^2.

        The straight limit of Eqs. 1-4: w = L/EI, C at the midpoint,
        a^2 = L^2/12 along the segment and b = 0 across it.
        """
        L = self.length
        e1 = self._vector / L
        e2 = np.array([-e1[1], e1[0]])
        return Ellipse(
            weight=L / bending_stiffness,
            center=np.asarray(self.point(0.5 * L)),
            a=L / np.sqrt(12.0),
            b=0.0,
            axes=np.array([[e1[0], e2[0]], [e1[1], e2[1]]]),
        )

    def symmetry_frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Midpoint C (mm) and unit axes: e1 from the end to the start, e2 = R(90 deg) e1.

        The straight limit of :meth:`Arc.symmetry_frame` (e1 to the start end).
        """
        start, end = self.end_points
        e1 = (start - end) / self.length
        return 0.5 * (start + end), e1, np.array([-e1[1], e1[0]])

    def closes_on_itself(self, thickness: float) -> bool:
        """Never: a straight band cannot close on itself."""
        return False

    def moved(self, angle: float, shift: np.ndarray) -> Segment:
        """The segment rotated by ``angle`` (rad) about the origin, then shifted (mm)."""
        a = rotate(angle, np.asarray(self.start)) + shift
        b = rotate(angle, np.asarray(self.end)) + shift
        return Segment(tuple(map(float, a)), tuple(map(float, b)))

    def scaled(self, factor: float) -> Segment:
        """The segment with its end points multiplied by ``factor``."""
        return Segment(
            tuple(map(float, np.asarray(self.start, float) * factor)),
            tuple(map(float, np.asarray(self.end, float) * factor)),
        )

    def parameters(self) -> dict:
        """The scene-file parameters: start and end points, mm."""
        return {"start": list(map(float, self.start)), "end": list(map(float, self.end))}


UNWRAP_SAMPLES = 8
"""Samples per arc-length panel on which a free curve's tangent angle is unwrapped."""

CURVATURE_SAMPLES = 2048
"""Samples of a free curve's curvature for its largest value (:attr:`_FreeCurve.max_thickness`)."""

REFINED_PEAKS = 64
"""The largest sampled values of a function along a free curve that :func:`largest_along`
refines to the true local maximum (a sharp loop's peak lies between two samples, each of
which already stands out)."""


def largest_along(function, length: float, samples: int) -> tuple[float, float]:
    """(s, value) of the largest value of ``function(s)`` over [0, length] (mm).

    ``function`` takes an array of s. Sampled at ``samples`` + 1 points;
    the :data:`REFINED_PEAKS` largest samples are then refined at once, each
    between its neighbours, by golden-section search (vectorised: every
    step evaluates all of them in one call), so that a peak narrower than
    the sample spacing (a tight loop of a spline) is found, not skipped.
    """
    s = np.linspace(0.0, length, samples + 1)
    values = np.asarray(function(s), float)
    order = np.argsort(values)[::-1][:REFINED_PEAKS]
    low = s[np.maximum(order - 1, 0)]
    high = s[np.minimum(order + 1, samples)]
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = high - ratio * (high - low), low + ratio * (high - low)
    fa, fb = np.asarray(function(a), float), np.asarray(function(b), float)
    while np.max(high - low) > 1e-9 * max(length, 1e-300):
        left = fa >= fb  # the maximum lies in [low, b]
        high = np.where(left, b, high)
        low = np.where(left, low, a)
        b, fb = np.where(left, a, b), np.where(left, fa, fb)
        a_new = np.where(left, high - ratio * (high - low), a)
        b_new = np.where(left, b, low + ratio * (high - low))
        moved = np.where(left, a_new, b_new)
        fm = np.asarray(function(moved), float)
        a, fa = np.where(left, a_new, b), np.where(left, fm, fb)
        b, fb = np.where(left, b, b_new), np.where(left, fb, fm)
    refined = np.concatenate([values[order], fa, fb])
    places = np.concatenate([s[order], a, b])
    k = int(np.argmax(refined))
    return float(places[k]), float(refined[k])


def quadrature_ellipse(shape: Shape, bending_stiffness: float, start: float, end: float) -> Ellipse:
    """Ellipse of elasticity of ``shape`` between arc lengths ``start``, ``end`` (mm), uniform EI.

    Paper Eqs. 1-4 by Gauss quadrature (:func:`flexval.geometry.profiles.quadrature_panels`):
    w = (end - start) / EI, C the centroid of the centre line, a^2 and b^2
    its variances along and across the principal axes. e1 is the axis of
    larger spread (a >= b), turned to point towards the start end; e2 =
    R(90 deg) e1 (as for an arc, where e2 points to the apex).
    """
    u, wq = quadrature_panels(end - start, ())
    r = np.asarray(shape.point(start + u), float)
    length = float(wq.sum())
    center = wq @ r / length
    d = r - center
    values, vectors = np.linalg.eigh((d * wq[:, None]).T @ d / length)  # ascending
    e1 = vectors[:, 1]
    if float(e1 @ (np.asarray(shape.point(start), float) - center)) < 0.0:
        e1 = -e1
    e2 = np.array([-e1[1], e1[0]])
    return Ellipse(
        weight=(end - start) / bending_stiffness,
        center=center,
        a=float(np.sqrt(max(values[1], 0.0))),
        b=float(np.sqrt(max(values[0], 0.0))),
        axes=np.column_stack([e1, e2]),
    )


class _FreeCurve:
    """What a free-form centre line derives from its point, tangent and curvature (mm, rad).

    Subclasses provide ``length``, ``point``, ``tangent_angle``,
    ``curvature_at`` and ``end_points``.
    """

    @property
    def width(self) -> float:
        """Net turning of the tangent from start to end, rad (an arc's angle)."""
        return float(self.tangent_angle(self.length) - self.tangent_angle(0.0))

    @property
    def curvature(self) -> float:
        """Mean signed curvature, net turning / length, 1/mm (see :meth:`curvature_at`)."""
        return self.width / self.length

    def tangent(self, s: np.ndarray | float) -> np.ndarray:
        """Unit tangent(s) at arc length s, shape (..., 2)."""
        return _directions(self.tangent_angle(s))

    @property
    def max_thickness(self) -> float:
        """Twice the smallest radius of curvature, mm: a thicker band has no inner edge there."""
        _, top = largest_along(
            lambda s: np.abs(self.curvature_at(s)), self.length, CURVATURE_SAMPLES
        )
        return math.inf if top == 0.0 else 2.0 / top

    def ellipse(self, bending_stiffness: float) -> Ellipse:
        """Ellipse of elasticity for a uniform EI (N mm^2), by :func:`quadrature_ellipse`."""
        return quadrature_ellipse(self, bending_stiffness, 0.0, self.length)

    def symmetry_frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Centre of elasticity C (mm) and the principal axes e1 (towards the start), e2."""
        ell = self.ellipse(1.0)
        return ell.center, ell.axes[:, 0], ell.axes[:, 1]

    def closes_on_itself(self, thickness: float) -> bool:
        """True if the ends are at most ``thickness`` (mm) apart: the solid band would close."""
        start, end = self.end_points
        return float(np.hypot(*(start - end))) <= thickness


@dataclass(frozen=True)
class Spline(_FreeCurve):
    """Free-form centre line: the C2 cubic spline through ``points`` (mm), by arc length.

    The spline is ``scipy.interpolate.CubicSpline`` through the points,
    parameterised by cumulative chord length, with not-a-knot ends (its
    default: three points give the parabola through them). Its true arc
    length s comes from :class:`flexval.geometry.arclength.ArcLengthMap`
    (to about 1e-13 of the length), so ``point(s)`` is at arc length s from
    the first point, like every other shape.

    Parameters
    ----------
    points : sequence of (float, float)
        At least three points, mm; consecutive points distinct.

    Raises
    ------
    ValueError
        If there are fewer than three points, two consecutive ones coincide,
        or the curve has a cusp.
    """

    points: tuple[tuple[float, float], ...]

    kind: ClassVar[str] = "spline"

    def __post_init__(self) -> None:
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 3:
            raise ValueError(f"a spline needs at least 3 points [x, y], got {self.points!r}")
        if np.any(np.hypot(*np.diff(pts, axis=0).T) == 0.0):
            raise ValueError("consecutive spline points must be distinct")
        object.__setattr__(self, "points", tuple((float(x), float(y)) for x, y in pts))

    def __getstate__(self) -> dict:
        return {"points": self.points}  # the curve is rebuilt on first use

    def __setstate__(self, state: dict) -> None:
        object.__setattr__(self, "points", state["points"])

    @cached_property
    def _curve(self):
        """(spline r(u), its derivative, the arc-length map, unwrapped tangent-angle samples)."""
        from scipy.interpolate import CubicSpline  # only scenes with splines pay its import

        pts = np.asarray(self.points)
        knots = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
        spline = CubicSpline(knots, pts, axis=0)
        derivative = spline.derivative()
        arc = ArcLengthMap(derivative, knots)
        fractions = np.arange(UNWRAP_SAMPLES) / UNWRAP_SAMPLES
        u = np.append(arc.edges[:-1, None] + np.diff(arc.edges)[:, None] * fractions, knots[-1])
        d = derivative(u.ravel())
        angles = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
        return spline, derivative, arc, (arc.arc_length(u.ravel()), angles)

    @property
    def length(self) -> float:
        """Arc length, mm."""
        return self._curve[2].length

    def parameter(self, s: np.ndarray | float) -> np.ndarray:
        """Chord-length parameter u (mm) of the points at arc length(s) s (mm)."""
        return self._curve[2].parameter(s)

    def point(self, s: np.ndarray | float) -> np.ndarray:
        """Point(s) at arc length s (mm) from the start, shape (..., 2), mm."""
        return self._curve[0](self.parameter(s))

    def tangent_angle(self, s: np.ndarray | float) -> np.ndarray:
        """Direction of the unit tangent at s, rad, continuous along the curve from the start's."""
        _, derivative, _, (grid, angles) = self._curve
        d = derivative(self.parameter(s))
        raw = np.arctan2(d[..., 1], d[..., 0])
        near = np.interp(s, grid, angles)
        return raw + 2.0 * np.pi * np.round((near - raw) / (2.0 * np.pi))

    def curvature_at(self, s: np.ndarray | float) -> np.ndarray:
        """Signed curvature (x' y'' - y' x'') / |r'|^3 at arc length(s) s (mm), 1/mm."""
        spline, derivative, _, _ = self._curve
        u = self.parameter(s)
        d1, d2 = derivative(u), spline(u, 2)
        speed = np.hypot(d1[..., 0], d1[..., 1])
        return (d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]) / speed**3

    @property
    def end_points(self) -> np.ndarray:
        """The first and last points, shape (2, 2), mm."""
        return np.array([self.points[0], self.points[-1]])

    def split(self, n: int) -> list[SplinePiece]:
        """The spline cut into n parts of equal arc length, from start to end."""
        L = self.length
        cuts = [L * k / n for k in range(n)] + [L]
        return [SplinePiece(self, a, b) for a, b in zip(cuts[:-1], cuts[1:])]

    def moved(self, angle: float, shift: np.ndarray) -> Spline:
        """The spline rotated by ``angle`` (rad) about the origin, then shifted (mm)."""
        pts = rotate(angle, np.asarray(self.points)) + np.asarray(shift, float)
        return Spline(tuple(map(tuple, pts.tolist())))

    def scaled(self, factor: float) -> Spline:
        """The spline through the points multiplied by ``factor``."""
        return Spline(tuple(map(tuple, (np.asarray(self.points) * factor).tolist())))

    def parameters(self) -> dict:
        """The scene-file parameters: the points, mm."""
        return {"points": [list(p) for p in self.points]}


@dataclass(frozen=True)
class SplinePiece(_FreeCurve):
    """The part of a :class:`Spline` between arc lengths ``start`` and ``end`` (mm).

    Its own arc length s runs from 0 at the parent's ``start``; a piece of a
    flexure cut by :meth:`Spline.split`.
    """

    parent: Spline
    start: float
    end: float

    kind: ClassVar[str] = "spline"

    @property
    def length(self) -> float:
        """end - start, mm."""
        return self.end - self.start

    def point(self, s: np.ndarray | float) -> np.ndarray:
        """Point(s) at arc length s (mm) from the piece's start, mm."""
        return self.parent.point(self.start + np.asarray(s, float))

    def tangent_angle(self, s: np.ndarray | float) -> np.ndarray:
        """The parent's tangent angle at the same point, rad."""
        return self.parent.tangent_angle(self.start + np.asarray(s, float))

    def curvature_at(self, s: np.ndarray | float) -> np.ndarray:
        """The parent's curvature at the same point, 1/mm."""
        return self.parent.curvature_at(self.start + np.asarray(s, float))

    @property
    def end_points(self) -> np.ndarray:
        """Start and end points, shape (2, 2), mm."""
        return self.parent.point(np.array([self.start, self.end]))

    def split(self, n: int) -> list[SplinePiece]:
        """The piece cut into n parts of equal arc length."""
        cuts = [self.start + self.length * k / n for k in range(n)] + [self.end]
        return [SplinePiece(self.parent, a, b) for a, b in zip(cuts[:-1], cuts[1:])]

    def moved(self, angle: float, shift: np.ndarray) -> SplinePiece:
        """The same piece of the moved parent (rad, mm)."""
        return SplinePiece(self.parent.moved(angle, shift), self.start, self.end)

    def scaled(self, factor: float) -> SplinePiece:
        """The same piece of the scaled parent."""
        return SplinePiece(self.parent.scaled(factor), self.start * factor, self.end * factor)

    def parameters(self) -> dict:
        """The parent's points and the piece's arc-length window [start, end], mm."""
        return {**self.parent.parameters(), "window_mm": [self.start, self.end]}


FlexureShape = Arc | Segment | Spline
