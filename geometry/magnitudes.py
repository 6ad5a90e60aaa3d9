"""Degenerate magnitudes: derived quantities too small or too large to compute with.

Every input value can be a valid positive number while a product of them is
not: a thickness of 1e-110 mm cubed underflows to zero in EI, E = 1e-300 MPa
gives a subnormal EI whose inverse overflows. Each derived quantity the
models divide by or multiply with (EI, EA, the compliances of the ellipse of
elasticity, the mechanism's size) must be a finite normal double; otherwise
the scene is refused, naming the flexure and the quantity. Units: mm, N, MPa.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

import numpy as np

from .errors import SceneError

if TYPE_CHECKING:
    from .mechanism import Mechanism

SMALLEST_NORMAL = sys.float_info.min
"""Smallest positive normal double (2.2e-308): below it a quantity has lost precision."""


def is_degenerate(value: float) -> bool:
    """True if ``value`` is zero, subnormal, infinite or NaN (sign ignored)."""
    return not (np.isfinite(value) and abs(value) >= SMALLEST_NORMAL)


def check_magnitudes(mech: Mechanism) -> None:
    """Raise SceneError if a derived stiffness, compliance or length is degenerate.

    Checked per flexure: length L (mm), I (mm^4), A (mm^2), EI (N mm^2),
    EA (N), the rotational compliance L / EI (1/(N mm)), the axial compliance
    L / EA (mm/N) and the bending compliances w a^2, w b^2 (mm/N) of the
    ellipse of elasticity (b only for arcs: it is 0 for a segment); then the
    mechanism's size (mm).
    """
    E = mech.material.youngs_modulus
    for f in mech.flexures:
        b, h = f.section.depth, f.section.thickness
        L, EI, EA = (
            f.shape.length,
            f.bending_stiffness(mech.material),
            f.axial_stiffness(mech.material),
        )
        inputs = f"E = {E:g} MPa, b = {b:g} mm, h = {h:g} mm, L = {L:g} mm"
        quantities = [
            ("length L", L, "mm"),
            ("second moment I = b h^3 / 12", f.section.inertia, "mm^4"),
            ("area A = b h", f.section.area, "mm^2"),
            ("bending stiffness EI", EI, "N mm^2"),
            ("axial stiffness EA", EA, "N"),
        ]
        if not any(is_degenerate(v) for _, v, _ in quantities):
            ell = f.shape.ellipse(EI)
            quantities += [
                ("rotational compliance L / EI", ell.weight, "1/(N mm)"),
                ("axial compliance L / EA", L / EA, "mm/N"),
                ("bending compliance w a^2", ell.weight * ell.a**2, "mm/N"),
            ]
            if f.shape.curvature != 0.0:
                quantities.append(("bending compliance w b^2", ell.weight * ell.b**2, "mm/N"))
        for what, value, unit in quantities:
            if is_degenerate(value):
                raise SceneError(
                    mech.source,
                    f"flexures.{f.name}",
                    f.name,
                    f"its {what} = {value:g} {unit} is zero, subnormal or not "
                    f"finite ({inputs}): the inputs are too extreme to compute with",
                )
    size = mech.size()
    if is_degenerate(size):
        raise SceneError(
            mech.source,
            "flexures",
            size,
            "the mechanism's size (largest distance between its points) is zero, "
            "subnormal or not finite",
        )
