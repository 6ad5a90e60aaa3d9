"""Notch hinges as the continuum bends them: beam theory's compliance with calibrated factors.

The reduced models take a flexure's compliance from its section's integrals, bending
∫ ds/EI(s) above all. A notch hinge's sections are short and deep: where the contour
widens, the fibres far from the axis carry less than beam theory's linear strain, and the
hinge is more compliant than ∫ ds/EI by about 1 % (slender, shallow notches) up to 50 %
(short, deep ones), whatever the reduced model's resolution. The continuum reference (2D
elasticity of the true outline) measures that excess; ``benchmarks/calibrate_notch.py``
tabulates it (``data/notch_table.json``) over the contours, t/L and H/t:

    r_b = theta_continuum / theta_beam under an end moment   (bending),
    r_s = the rest of the end deflection under a force across the axis, in units of the
          Timoshenko shear integral ∫ ds/(k G A), k = 5/6        (shear).

A corrected hinge takes E / r_b and G / r_s (:func:`corrected_material`) and its reduced
models add the shear term (the material's ``shear_flexible``): its end rotation under a
moment, and its rotation and deflection under a force, are the continuum's (to the table's
interpolation error). r_b does not depend on Poisson's ratio (within 0.1 % over 0.25-0.42);
r_s (1 + nu) nearly does not (within 0.8 %), so the table holds r_s at nu = 0.33. The
table also holds the notch's stress concentration K at the waist (the continuum's recovered
surface fibre peak under a moment over the beam formula there): a reduced model's peak
fibre stress on a hinge is K times its beam formula (:mod:`flexval.validation.studies.yieldpoint`).

The table is interpolated in (log t/L, log H/t) by a C1 piecewise-cubic (Clough-Tocher)
interpolant over its points; power contours by their exponent too (a cubic spline in log n
through the tabulated exponents: the factors are convex in n). A hinge outside the table's
range takes the nearest tabulated hinge's factors and is marked (:attr:`NotchFactors.inside`
False).

Units: mm, MPa; the factors are ratios.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from dataclasses import dataclass
from functools import cache
from importlib import resources

import numpy as np

from flexval.geometry import Flexure, Material

TABLE = "notch_table.json"
"""The calibration table in :mod:`flexval.reducedmodels`' data."""


@dataclass(frozen=True)
class NotchFactors:
    """The compliance factors of one notch hinge.

    Attributes
    ----------
    bending : float
        r_b: the hinge's bending compliance over ∫ ds/EI.
    shear : float
        r_s: its transverse shear compliance over ∫ ds/(k G A), at its own Poisson's ratio.
    stress : float
        K: the continuum's surface fibre peak under a moment over the beam formula
        6 M / (b t^2) at the waist (the stress concentration of the notch).
    inside : bool
        Whether the hinge lies in the calibrated range (else: the nearest tabulated hinge's).
    where : str
        The hinge's shape ratios, for messages (``t/L 0.1, H/t 11``).
    """

    bending: float
    shear: float
    stress: float
    inside: bool
    where: str


@cache
def calibration_table() -> dict:
    """The calibration table, read once."""
    text = resources.files("flexval.reducedmodels").joinpath("data", TABLE).read_text()
    return json.loads(text)


@cache
def _slices() -> dict[tuple[str, float | None], tuple]:
    """Per contour (and power exponent): the interpolants of (r_b, r_s, K) over
    (log t/L, log H/t), Clough-Tocher and nearest-point."""
    from scipy.interpolate import CloughTocher2DInterpolator, NearestNDInterpolator

    groups: dict[tuple[str, float | None], list] = {}
    for row in calibration_table()["rows"]:
        groups.setdefault((row["contour"], row["exponent"]), []).append(row)
    out = {}
    for key, rows in groups.items():
        xy = np.array([[math.log(r["t_over_l"]), math.log(r["h_over_t"])] for r in rows])
        values = np.array([[r["bending"], r["shear"], r["stress"]] for r in rows])
        out[key] = (CloughTocher2DInterpolator(xy, values), NearestNDInterpolator(xy, values))
    return out


def _at(key: tuple[str, float | None], x: float, y: float) -> tuple[np.ndarray, bool]:
    """(r_b, r_s, K) of one slice at (log t/L, log H/t), and whether it is inside it."""
    smooth, nearest = _slices()[key]
    found = np.asarray(smooth(x, y), float).reshape(-1)
    if np.all(np.isfinite(found)):
        return found, True
    return np.asarray(nearest(x, y), float).reshape(-1), False


def factors_of(flexure: Flexure, poisson_ratio: float) -> NotchFactors | None:
    """The calibrated factors of ``flexure`` (None unless it is a notch hinge)."""
    profile = flexure.section.profile
    if profile is None or getattr(profile, "kind", None) != "notch":
        return None
    return _factors(
        profile.contour,
        profile.t / profile.length,
        profile.height / profile.t,
        None if profile.exponent is None else float(profile.exponent),
        float(poisson_ratio),
    )


@functools.lru_cache(maxsize=4096)
def _factors(
    contour: str, t_over_l: float, h_over_t: float, exponent: float | None, poisson_ratio: float
) -> NotchFactors:
    """:func:`factors_of` by the hinge's shape ratios, remembered: a report or a study builds
    the same hinges' models again and again, and a power contour's spline is costly to build."""
    x, y = math.log(t_over_l), math.log(h_over_t)
    where = f"t/L {t_over_l:.4g}, H/t {h_over_t:.4g}"
    if contour == "power":
        from scipy.interpolate import CubicSpline

        exponents = sorted(n for (c, n) in _slices() if c == "power")
        n = exponent
        where += f", n {n:g}"
        inside = exponents[0] <= n <= exponents[-1]
        n = min(max(n, exponents[0]), exponents[-1])
        found = [_at(("power", e), x, y) for e in exponents]
        inside = inside and all(ok for _, ok in found)
        spline = CubicSpline(np.log(exponents), np.array([v for v, _ in found]), axis=0)
        values = spline(math.log(n))
    else:
        values, inside = _at((contour, None), x, y)
    calibrated = calibration_table()["poisson_ratio"]
    shear = float(values[1]) * (1.0 + calibrated) / (1.0 + poisson_ratio)
    return NotchFactors(float(values[0]), shear, float(values[2]), bool(inside), where)


def corrected_material(material: Material, factors: NotchFactors) -> Material:
    """The material a corrected hinge's reduced models take: E / r_b, G / r_s (through
    Poisson's ratio: G = E / (2 (1 + nu))) and the shear term included, MPa."""
    young = material.youngs_modulus / factors.bending
    shear_modulus = material.shear_modulus / factors.shear
    return dataclasses.replace(
        material,
        youngs_modulus=young,
        poisson_ratio=young / (2.0 * shear_modulus) - 1.0,
        shear_flexible=True,
    )


def takes_correction(spec) -> bool:
    """Whether the model ``spec`` (a ModelSpec) takes this module's correction on its notch
    hinges: its family offers the plain Euler-Bernoulli option ``eb`` (the reduced
    families) and the spec does not set it."""
    return spec.model_family.option("eb") is not None and not spec.kwargs.get("eb")
