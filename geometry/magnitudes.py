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
    ellipse of elasticity (b only for arcs: it is 0 for a segment); for a
    section that varies along the flexure, the smallest I, A, EI and EA and
    the compliances by quadrature; then the mechanism's size (mm).
    """
    E = mech.material.youngs_modulus
    for f in mech.flexures:
        if not f.section.is_uniform:
            _check_varying(mech, f)
            continue
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
        _refuse_degenerate(mech, f, quantities, inputs)
    size = mech.size()
    if is_degenerate(size):
        raise SceneError(
            mech.source,
            "flexures",
            size,
            "the mechanism's size (largest distance between its points) is zero, "
            "subnormal or not finite",
        )


def _check_varying(mech: Mechanism, f) -> None:
    """The checks of :func:`check_magnitudes` for a section that varies along the flexure.

    The stiffnesses at the thinnest section (the smallest EI and EA), then the
    compliances by quadrature (:func:`flexval.geometry.compliance.curve_compliance`):
    ∫ ds / EI, ∫ ds / EA and the ellipse's w a^2 (and w b^2 for an arc).
    """
    from .compliance import curve_compliance

    E = mech.material.youngs_modulus
    b, h = f.section.depth, f.section.thickness
    L = f.shape.length
    inputs = (
        f"E = {E:g} MPa, b = {b:g} mm, h = {h:g} to {f.section.max_thickness:g} mm, L = {L:g} mm"
    )
    inertia, area = b * h**3 / 12.0, b * h
    quantities = [
        ("length L", L, "mm"),
        ("smallest second moment I = b h^3 / 12", inertia, "mm^4"),
        ("smallest area A = b h", area, "mm^2"),
        ("smallest bending stiffness EI", E * inertia, "N mm^2"),
        ("smallest axial stiffness EA", E * area, "N"),
    ]
    if not any(is_degenerate(v) for _, v, _ in quantities):
        found = curve_compliance(f.shape, f.section, mech.material)
        ell = found.ellipse
        quantities += [
            ("rotational compliance ∫ ds / EI", ell.weight, "1/(N mm)"),
            ("axial compliance ∫ ds / EA", float(np.trace(found.axial)), "mm/N"),
            ("bending compliance w a^2", ell.weight * ell.a**2, "mm/N"),
        ]
        if f.shape.kind == "arc":
            quantities.append(("bending compliance w b^2", ell.weight * ell.b**2, "mm/N"))
    _refuse_degenerate(mech, f, quantities, inputs)


def _refuse_degenerate(mech: Mechanism, f, quantities: list, inputs: str) -> None:
    """Raise SceneError naming the first degenerate (name, value, unit) of ``quantities``."""
    for what, value, unit in quantities:
        if is_degenerate(value):
            raise SceneError(
                mech.source,
                f"flexures.{f.name}",
                f.name,
                f"its {what} = {value:g} {unit} is zero, subnormal or not "
                f"finite ({inputs}): the inputs are too extreme to compute with",
            )
