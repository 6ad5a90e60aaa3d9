"""Linear compliance of any elastic curve by quadrature of its section properties.

For a flexure clamped at its first end and loaded at its second, the
linear (small-displacement) compliance follows from Castigliano's theorem:
a wrench (Fx, Fy, M) applied at a point P gives the bending moment
m(s) = M + (Px - x) Fy - (Py - y) Fx at the centre-line point (x, y)(s),
the normal force N = F . t and the shear force V = F . n, so that

    C = ∫ g g^T / EI ds + ∫ [t; 0][t; 0]^T / EA ds + ∫ [n; 0][n; 0]^T / (k G A) ds,
    g(s) = (y - Py, Px - x, 1),

over the flexure (t the unit tangent, n the unit normal, k the shear
correction). The bending part is the ellipse of elasticity (paper Eqs.
1-5), which exists for any curve and any section law:

    w = ∫ ds / EI,    C = (1/w) ∫ r ds / EI,    J = ∫ (r - C)(r - C)^T ds / EI,

its semi-axes a^2, b^2 the eigenvalues of J over w (a along e1, the
direction of larger spread, b along e2 = e1 turned by +90 deg). For a
uniform arc or segment these are the closed forms of
:meth:`flexval.geometry.shapes.Arc.ellipse`; the quadrature serves
tapered, notched and free-form flexures.

Units: mm, N, MPa, rad; compliances in mm/N, 1/N, 1/(N mm).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .profiles import quadrature_panels
from .shapes import Ellipse, Shape

SHEAR_CORRECTION = 5.0 / 6.0
"""Shear correction factor k of a rectangular section (Timoshenko)."""


@dataclass(frozen=True)
class CurveCompliance:
    """Linear compliance data of one flexure (or a stretch of it).

    Attributes
    ----------
    ellipse : Ellipse
        Bending: weight w (1/(N mm)), centre C (mm), semi-axes and axes.
    axial : ndarray, shape (2, 2)
        ∫ t t^T / EA ds, mm/N.
    shear : ndarray, shape (2, 2)
        ∫ n n^T / (k G A) ds, mm/N.
    """

    ellipse: Ellipse
    axial: np.ndarray
    shear: np.ndarray

    def matrix(self, point: np.ndarray, axial: bool = True, shear: bool = False) -> np.ndarray:
        """3x3 compliance at ``point`` (mm) in global axes: (ux, uy, θ) per (Fx, Fy, M).

        The free end's displacement and rotation, measured at ``point``,
        under a wrench applied there (mm/N, 1/N, 1/(N mm)).
        """
        e = self.ellipse
        d = np.asarray(point, float) - e.center
        axes = e.axes
        spread = axes @ np.diag([e.a**2, e.b**2]) @ axes.T * e.weight  # J
        out = np.empty((3, 3))
        # g = (y - Py, Px - x, 1) about C plus the shift of P from C
        out[0, 0] = spread[1, 1] + e.weight * d[1] ** 2
        out[1, 1] = spread[0, 0] + e.weight * d[0] ** 2
        out[0, 1] = out[1, 0] = -spread[0, 1] - e.weight * d[0] * d[1]
        out[0, 2] = out[2, 0] = -e.weight * d[1]
        out[1, 2] = out[2, 1] = e.weight * d[0]
        out[2, 2] = e.weight
        if axial:
            out[:2, :2] += self.axial
        if shear:
            out[:2, :2] += self.shear
        return out


def curve_compliance(
    shape: Shape,
    section,
    material,
    start: float = 0.0,
    end: float | None = None,
    panels: int = 64,
) -> CurveCompliance:
    """Compliance integrals of ``shape`` between arc lengths ``start`` and ``end`` (mm).

    Parameters
    ----------
    shape : Shape
        The centre line (any shape with ``point``, ``tangent`` and ``length``).
    section : Section
        Depth and thickness, uniform or with a profile h(s) (s from the
        shape's first end, mm).
    material : Material
        E and nu (MPa).
    start, end : float
        The stretch, mm (default: the whole flexure).
    panels : int
        Gauss panels over the whole length (see
        :func:`flexval.geometry.profiles.quadrature_panels`).
    """
    length = shape.length
    end = length if end is None else end
    profile = section.profile
    breaks = () if profile is None else profile.breakpoints
    inner = tuple(b - start for b in breaks if start < b < end)
    u, wq = quadrature_panels(end - start, inner, max(4, round(panels * (end - start) / length)))
    s = start + u
    E, G = material.youngs_modulus, material.shear_modulus
    bend = wq / (E * section.inertia_at(s))
    r = np.asarray(shape.point(s), float)
    t = np.asarray(shape.tangent(s), float)
    n = np.stack([-t[:, 1], t[:, 0]], axis=1)
    w = float(bend.sum())
    center = bend @ r / w
    d = r - center
    spread = (d * bend[:, None]).T @ d
    values, vectors = np.linalg.eigh(spread)  # ascending
    e1 = vectors[:, 1]
    e2 = np.array([-e1[1], e1[0]])
    a2, b2 = max(values[1], 0.0) / w, max(values[0], 0.0) / w
    ellipse = Ellipse(
        weight=w,
        center=center,
        a=float(np.sqrt(a2)),
        b=float(np.sqrt(b2)),
        axes=np.column_stack([e1, e2]),
    )
    axial_w = wq / (E * section.area_at(s))
    shear_w = wq / (SHEAR_CORRECTION * G * section.area_at(s))
    return CurveCompliance(
        ellipse=ellipse,
        axial=(t * axial_w[:, None]).T @ t,
        shear=(n * shear_w[:, None]).T @ n,
    )
