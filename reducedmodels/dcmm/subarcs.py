"""The linear compliance of a flexure's equal parts: what DCMM and the EE build on.

A flexure cut into n parts of equal arc length (``shape.split(n)``, from its
start to its end) gives each part its ellipse of elasticity (paper Eqs. 1-4)
and the diagonal compliance diag(c1, c2, c3) at the ellipse's centre along
its axes e1, e2 (Eq. 5):

    c1 = w b^2,  c2 = w a^2,  c3 = w   (mm/N, mm/N, 1/(N mm)),

with the axial compliance ∫ ds / EA along the part replacing the vanishing
w b^2 of a straight part (b = 0). Uniform arcs and segments take the closed
forms of :meth:`flexval.geometry.shapes.Arc.ellipse` and
:meth:`~flexval.geometry.shapes.Segment.ellipse`; a section that varies
along the flexure (a taper, a notch) or a free-form centre line takes the
same quantities by quadrature over the part's window [s0, s1] of the
flexure (:func:`flexval.geometry.compliance.curve_compliance`; the profile
is parameterised on the whole flexure's arc length). A curved part keeps
the paper's bending-only compliance, as a uniform arc does; a part whose
ellipse is flat to rounding (a spline through collinear points) is straight.

Units: mm, N, MPa, rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexval.geometry import Flexure, Material
from flexval.geometry.compliance import curve_compliance
from flexval.geometry.shapes import Ellipse, Shape

from ..core.geometrycache import per_centre_line
from ..core.validity import MAX_RELATIVE_ROTATION, bending_rotation_limit

STRAIGHT_SPREAD = 1e-10
"""A part whose ellipse's b is below this fraction of its length is straight (rounding of a
flat quadrature): its axial compliance replaces w b^2."""


@dataclass(frozen=True)
class SubArc:
    """One part of a flexure and its linear compliance.

    Attributes
    ----------
    shape : Shape
        The part's centre line.
    start, end : float
        Its window on the flexure, arc length from the flexure's first end, mm.
    ellipse : Ellipse
        Its ellipse of elasticity (centre mm, axes, weight 1/(N mm)).
    compliance : tuple of float
        (c1, c2, c3): along e1 and e2 at the centre (mm/N) and in rotation (1/(N mm)).
    strain_limit : float
        Relative rotation of its two end bodies at which the thinnest
        section's outer fibre reaches the strain limit, rad
        (:func:`~flexval.reducedmodels.core.validity.bending_rotation_limit`), for
        a section that varies along the flexure; infinite for a uniform one
        (whose parts keep :data:`~flexval.reducedmodels.core.validity.MAX_RELATIVE_ROTATION`
        alone, as the paper's arcs do).
    """

    shape: Shape
    start: float
    end: float
    ellipse: Ellipse
    compliance: tuple[float, float, float]
    strain_limit: float = math.inf

    @property
    def turn_limit(self) -> float:
        """The smaller of the strain limit and MAX_RELATIVE_ROTATION, rad."""
        return min(self.strain_limit, MAX_RELATIVE_ROTATION)


def has_closed_form(flexure: Flexure) -> bool:
    """True for a uniform arc or segment: its parts take the closed-form ellipses."""
    return flexure.section.is_uniform and flexure.shape.kind in ("arc", "segment")


def split_parts(shape: Shape, n: int) -> tuple[tuple[Shape, float, float], ...]:
    """The n parts of ``shape`` and their windows [s0, s1] on it (mm)."""
    length = shape.length
    windows = [length * k / n for k in range(n)] + [length]
    return tuple(zip(shape.split(n), windows, windows[1:]))


@per_centre_line
def _unit_parts(shape: Shape, n: int) -> tuple[tuple[Shape, float, float, Ellipse], ...]:
    """The parts of a closed-form centre line, their windows and their ellipses for EI = 1
    (whose weight is the part's length; the arrays read-only, shared by every caller)."""
    out = []
    for part, s0, s1 in split_parts(shape, n):
        unit = part.ellipse(1.0)
        unit.center.flags.writeable = False
        unit.axes.flags.writeable = False
        out.append((part, s0, s1, unit))
    return tuple(out)


def sub_arcs(flexure: Flexure, material: Material, n: int) -> list[SubArc]:
    """The flexure cut into n parts of equal arc length, from its start to its end."""
    shape = flexure.shape
    if has_closed_form(flexure):
        EI = flexure.bending_stiffness(material)
        EA = flexure.axial_stiffness(material)
        out = []
        for part, s0, s1, unit in _unit_parts(shape, n):
            # the part's ellipse(EI): its weight L / EI, its geometry that of EI = 1
            ell = Ellipse(unit.weight / EI, unit.center, unit.a, unit.b, unit.axes)
            w = ell.weight
            compliance = [w * ell.b**2, w * ell.a**2, w]  # Ellipse.compliance()
            if ell.b == 0.0:
                compliance[0] = part.length / EA
            out.append(SubArc(part, s0, s1, ell, tuple(compliance)))
        return out
    return [
        _by_quadrature(flexure, material, part, s0, s1) for part, s0, s1 in split_parts(shape, n)
    ]


def _by_quadrature(
    flexure: Flexure, material: Material, part: Shape, s0: float, s1: float
) -> SubArc:
    """A part's ellipse and compliance by quadrature over its window [s0, s1] (mm)."""
    found = curve_compliance(flexure.shape, flexure.section, material, s0, s1)
    ell = found.ellipse
    w = ell.weight
    if part.kind == "segment" or ell.b <= STRAIGHT_SPREAD * (s1 - s0):
        e1 = np.asarray(part.tangent(0.5 * part.length), float)
        e2 = np.array([-e1[1], e1[0]])
        ell = Ellipse(w, ell.center, ell.a, 0.0, np.column_stack([e1, e2]))
        across = w * ell.a**2
        if material.shear_flexible:  # a calibrated notch: Timoshenko's shear term too
            across += float(e2 @ found.shear @ e2)
        compliance = (float(e1 @ found.axial @ e1), across, w)
    else:
        compliance = (w * ell.b**2, w * ell.a**2, w)
    return SubArc(part, s0, s1, ell, compliance, _strain_limit(flexure, material, w, s0, s1))


def thinnest(flexure: Flexure, s0: float = 0.0, s1: float | None = None) -> float:
    """The smallest thickness of the flexure between arc lengths s0 and s1 (mm), mm.

    Every built-in profile is monotone on either side of the flexure's middle
    (a taper everywhere), so the smallest value lies at a window end or at
    the middle when the window holds it.
    """
    length = flexure.shape.length
    s1 = length if s1 is None else s1
    candidates = np.array([s0, s1, min(max(0.5 * length, s0), s1)])
    return float(np.min(flexure.section.thickness_at(candidates)))


def _strain_limit(flexure: Flexure, material: Material, weight: float, s0: float, s1: float):
    """The part's relative rotation at which its thinnest fibre reaches the strain limit, rad."""
    if flexure.section.is_uniform:
        return math.inf
    return bending_rotation_limit(
        weight, material.youngs_modulus, flexure.section.depth, thinnest(flexure, s0, s1)
    )
