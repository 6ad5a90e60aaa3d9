"""Flexure centre-line shapes: uniform circular arcs and straight segments.

A shape is parametrised by arc length ``s`` in mm, from its *start* point to
its *end* point. For an arc the start is at polar angle ``axis - width/2``
around the centre and the curve runs counterclockwise (paper, Sect. 2.3,
Fig. 3). Each shape also gives its ellipse of elasticity (paper Eqs. 1-4),
the linear bending compliance data used by the DCMM and EE models.

All lengths are mm and all angles are radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, Protocol, Union

import numpy as np

from .kinematics import rotate

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
        """The segment rotated by ``angle`` (rad) about the origin, then shifted by ``shift`` (mm)."""
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


FlexureShape = Union[Arc, Segment]
