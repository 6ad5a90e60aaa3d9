"""Thickness profiles of flexures whose section varies along the centre line.

A profile gives the in-plane thickness h(s) (mm) of a flexure at arc length
``s`` (mm) from its first end, for ``0 <= s <= length``. A flexure of uniform
thickness has no profile (:attr:`flexval.geometry.mechanism.Section.profile`
is None), so every model keeps its closed forms for it.

Two families:

- :class:`LinearTaper`: h varies linearly from ``start`` to ``end``
  (scene syntax ``thickness = [h_start, h_end]`` on any shape).
- :class:`NotchProfile`: the classic notch hinges, a straight flexure whose
  thickness is symmetric about its axis and about its middle, thinnest
  (``t``) at s = L/2 and ``H`` (the blank) at both ends. With
  ``u = 2 s / L - 1`` in [-1, 1]:

  - *circular*: each cut-out is the circular arc through the ends and the
    middle, of radius R = ((L/2)^2 + ((H - t)/2)^2) / (H - t);
    h = t + 2 (R - sqrt(R^2 - (s - L/2)^2));
  - *elliptical*: h = t + (H - t) (1 - sqrt(1 - u^2));
  - *corner-filleted*: quarter-circle fillets of radius r at both ends,
    h = t on [r, L - r] and h = t + 2 (r - sqrt(r^2 - (r - x)^2)) within r
    of either end (x the distance to that end), so H = t + 2 r;
  - *power*: h = t + (H - t) |u|^n.

Quadrature of section properties along such a profile splits at
:attr:`breakpoints` (where h or a derivative is not smooth) so that
Gauss rules keep their order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np

NOTCH_CONTOURS = ("circular", "elliptical", "corner-filleted", "power")
"""The notch contours a scene may name (``contour = ...``)."""

SEMICIRCLE_ROUND_OFF = 1e-5
"""Relative slack of a circular notch's limit H <= t + L (semicircular cut-outs): a scene
gives its points to a few significant digits (the built-in notch four-bar's axis, from
(0, 0) to (1.2127, 4.8507), is 4.99999 mm long for 5 mm, and its blank H = t + 5 mm), and a
blank that much above t + L is the semicircular hinge itself (its modelled end thickness
is off by about the same fraction); a taller one would need cut-outs larger than half a
circle."""


class ThicknessProfile(Protocol):
    """What every thickness profile provides (lengths in mm)."""

    kind: ClassVar[str]
    length: float

    def thickness(self, s: np.ndarray | float) -> np.ndarray:
        """In-plane thickness h(s) at arc length s from the first end, mm."""
        ...

    @property
    def min_thickness(self) -> float: ...

    @property
    def max_thickness(self) -> float: ...

    @property
    def breakpoints(self) -> tuple[float, ...]: ...

    def scaled(self, factor: float) -> ThicknessProfile: ...

    def parameters(self) -> dict: ...


@dataclass(frozen=True)
class LinearTaper:
    """Thickness linear in arc length, from ``start`` (s = 0) to ``end`` (s = length), mm."""

    start: float
    end: float
    length: float

    kind: ClassVar[str] = "taper"

    def thickness(self, s: np.ndarray | float) -> np.ndarray:
        """h(s) = start + (end - start) s / length, mm."""
        s = np.asarray(s, dtype=float)
        return self.start + (self.end - self.start) * (s / self.length)

    @property
    def min_thickness(self) -> float:
        """The thinner end's thickness, mm."""
        return min(self.start, self.end)

    @property
    def max_thickness(self) -> float:
        """The thicker end's thickness, mm."""
        return max(self.start, self.end)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Where h is twice, four times, ... the thinner end's, short of the thicker end (mm).

        A linear taper is smooth, but a section integral of a steep one is
        not: 1/h^3 falls by 2^3 = 8 between two of these points, and by 10^12
        over a taper of ratio 10^4, whose thin end a uniform rule cannot
        resolve. Split there, every stretch's integrand varies by at most 8
        and the Gauss rules keep their accuracy; a taper of ratio 2 or less
        has none.
        """
        thin, thick = self.min_thickness, self.max_thickness
        if thick <= 2.0 * thin:
            return ()
        doublings = np.arange(1, math.ceil(math.log2(thick / thin)))
        h = thin * 2.0**doublings
        h = h[h < thick]
        s = (h - self.start) / (self.end - self.start) * self.length
        return tuple(sorted(float(x) for x in s))

    def scaled(self, factor: float) -> LinearTaper:
        """The taper with every length multiplied by ``factor``."""
        return LinearTaper(self.start * factor, self.end * factor, self.length * factor)

    def parameters(self) -> dict:
        """Scene-file form: ``thickness = [start, end]`` (mm)."""
        return {"thickness": [self.start, self.end]}


FLAT_ROUND_OFF = 1e-9
"""A corner-filleted notch whose fillets leave a flat part shorter than this share of its
length has none: the fillets meet at the middle (H = t + L, to round-off)."""


@dataclass(frozen=True)
class NotchProfile:
    """Thickness of a notch hinge of axis length ``length`` (mm).

    Parameters
    ----------
    contour : str
        One of :data:`NOTCH_CONTOURS`.
    t : float
        Smallest thickness, at the middle, mm (> 0).
    height : float
        Thickness H at both ends (the blank), mm (> t).
    length : float
        Axis length L, mm.
    fillet_radius : float or None
        Corner-filleted only: r in (0, L/2], mm (then H = t + 2 r).
    exponent : float or None
        Power only: n > 0.
    """

    contour: str
    t: float
    height: float
    length: float
    fillet_radius: float | None = None
    exponent: float | None = None

    kind: ClassVar[str] = "notch"

    def __post_init__(self) -> None:
        if self.contour not in NOTCH_CONTOURS:
            raise ValueError(f"contour must be one of {NOTCH_CONTOURS}, not {self.contour!r}")
        if not 0.0 < self.t < self.height:
            raise ValueError(f"need 0 < t < H, got t = {self.t} mm, H = {self.height} mm")
        if self.contour == "corner-filleted":
            r = self.fillet_radius
            if r is None or not 0.0 < r <= 0.5 * self.length * (1.0 + FLAT_ROUND_OFF):
                raise ValueError(f"fillet radius must be in (0, L/2], got {r} mm")
        if self.contour == "circular" and self.height > (self.t + self.length) * (
            1.0 + SEMICIRCLE_ROUND_OFF
        ):
            raise ValueError(
                f"a circular notch needs H <= t + L (cut-outs of at most half a circle), got "
                f"H = {self.height} mm, t + L = {self.t + self.length} mm"
            )
        if self.contour == "power" and (self.exponent is None or not self.exponent > 0.0):
            raise ValueError(f"exponent must be positive, got {self.exponent}")

    @property
    def circle_radius(self) -> float:
        """Radius R of a circular notch's cut-outs, mm."""
        half, depth = 0.5 * self.length, 0.5 * (self.height - self.t)
        return (half * half + depth * depth) / (2.0 * depth)

    def thickness(self, s: np.ndarray | float) -> np.ndarray:
        """h(s) at arc length s (mm) from the axis start, mm (formulas in the module text)."""
        s = np.asarray(s, dtype=float)
        L, t, H = self.length, self.t, self.height
        if self.contour == "circular":
            R = self.circle_radius
            d = s - 0.5 * L
            return t + 2.0 * (R - np.sqrt(np.maximum(R * R - d * d, 0.0)))
        if self.contour == "elliptical":
            u = 2.0 * s / L - 1.0
            return t + (H - t) * (1.0 - np.sqrt(np.maximum(1.0 - u * u, 0.0)))
        if self.contour == "power":
            u = np.abs(2.0 * s / L - 1.0)
            return t + (H - t) * u**self.exponent
        r = self.fillet_radius
        x = np.minimum(s, L - s)  # distance to the nearer end
        inside = np.maximum(r - x, 0.0)  # 0 on the flat part
        return t + 2.0 * (r - np.sqrt(np.maximum(r * r - inside * inside, 0.0)))

    @property
    def min_thickness(self) -> float:
        """t, mm."""
        return self.t

    @property
    def max_thickness(self) -> float:
        """H, mm."""
        return self.height

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """The fillets' tangent points (corner-filleted) or the middle (power, n not even), mm."""
        if self.contour == "corner-filleted":
            r = float(self.fillet_radius)
            # no flat part left between fillets that meet (to round-off: a flat of 1e-9 L
            # would be a stretch no mesh or integral can grade)
            return (r, self.length - r) if 2.0 * r < self.length * (1.0 - FLAT_ROUND_OFF) else ()
        if self.contour == "power" and self.exponent % 2.0 != 0.0:
            return (0.5 * self.length,)  # |u|^n is smooth at u = 0 for even n only
        return ()

    def scaled(self, factor: float) -> NotchProfile:
        """The notch with every length multiplied by ``factor``."""
        r = None if self.fillet_radius is None else self.fillet_radius * factor
        return NotchProfile(
            self.contour,
            self.t * factor,
            self.height * factor,
            self.length * factor,
            r,
            self.exponent,
        )

    def parameters(self) -> dict:
        """Scene-file form: contour, thickness (t), height (H) and the contour's own field."""
        out = {"contour": self.contour, "thickness": self.t, "height": self.height}
        if self.fillet_radius is not None:
            out["fillet_radius"] = self.fillet_radius
        if self.exponent is not None:
            out["exponent"] = self.exponent
        return out


def corner_filleted_height(t: float, fillet_radius: float) -> float:
    """H = t + 2 r of a corner-filleted hinge, mm."""
    return t + 2.0 * fillet_radius


def quadrature_panels(
    length: float, breakpoints: tuple[float, ...], panels: int = 64, order: int = 8
) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss-Legendre nodes and weights on [0, length] (mm), split at breakpoints.

    Each stretch between breakpoints is mapped by s = a + (b - a)(1 - cos θ)/2
    and θ in [0, π] cut into panels (in proportion to the stretch's length,
    at least 4) of ``order`` Gauss points. The map clusters the nodes at the
    stretch's ends, where notch contours have their singular derivatives
    (elliptical and corner-filleted ends, a power contour's middle), and
    turns a square-root end behaviour into a smooth integrand: with the
    defaults the section integrals of every built-in contour are exact to
    about 1e-13 relative.

    Returns
    -------
    s, w : ndarray
        Nodes (mm) and weights (mm), ascending in s.
    """
    x, wx = np.polynomial.legendre.leggauss(order)
    cuts = np.array([0.0, *sorted(b for b in breakpoints if 0.0 < b < length), length])
    nodes, weights = [], []
    for a, b in zip(cuts[:-1], cuts[1:]):
        n = max(4, math.ceil(panels * (b - a) / length))
        edges = np.linspace(0.0, math.pi, n + 1)
        half = 0.5 * np.diff(edges)[:, None]
        theta = (0.5 * (edges[:-1] + edges[1:])[:, None] + half * x).ravel()
        nodes.append(a + 0.5 * (b - a) * (1.0 - np.cos(theta)))
        weights.append((half * wx).ravel() * 0.5 * (b - a) * np.sin(theta))
    return np.concatenate(nodes), np.concatenate(weights)
