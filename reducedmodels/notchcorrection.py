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
table also holds the notch's stress concentration: K at the waist (the continuum's recovered
surface fibre peak under a moment over the beam formula there), K(s) along the hinge and
the shear's shift delta(s) of the moment under a force; a reduced model's surface fibre
stress on a hinge is K(s) times its beam formula with the moment taken at s - delta(s)
(:meth:`NotchFactors.surface_stress`, which its connector gives the recorder:
:mod:`flexval.reducedmodels.core.peaks`).

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

STATIONS = np.linspace(0.0, 1.0, 33)
"""Where the table holds K(s) along a hinge: xi from an end (0) to the waist (1), xi = 1/2 at
the contour's :func:`junction` (a fillet's tangent point), linear in arc length on either
side, the same on both halves of the symmetric hinge. 32 intervals put 16 over a fillet, whose
concentration peaks just inside its tangent point."""

SMOOTH_JUNCTION = 0.25
"""The junction (fraction of the length) of a contour without one: xi is then 2 s / L."""


def junction(profile) -> float:
    """The arc-length fraction of a notch ``profile``'s first fillet tangent point (a
    corner-filleted contour's r / L, at most 1/2), :data:`SMOOTH_JUNCTION` for a contour
    without one."""
    if profile.contour != "corner-filleted":
        return SMOOTH_JUNCTION
    return min(float(profile.fillet_radius) / float(profile.length), 0.5)


def station_fractions(profile) -> np.ndarray:
    """The arc-length fractions (from the first end, on the first half) of :data:`STATIONS`
    on a notch ``profile``."""
    j = junction(profile)
    xi = STATIONS
    return np.where(xi <= 0.5, 2.0 * xi * j, j + (2.0 * xi - 1.0) * (0.5 - j))


def _stations_at(fractions, junction_fraction: float) -> np.ndarray:
    """xi (:data:`STATIONS`' coordinate) of arc-length ``fractions`` on a hinge whose junction
    lies at ``junction_fraction``: :func:`station_fractions` inverted, the hinge folded about
    its waist."""
    f = np.asarray(fractions, float)
    f = np.minimum(f, 1.0 - f)
    j = junction_fraction
    if j >= 0.5:  # fillets that meet: no flat part
        return np.clip(f / (2.0 * j), 0.0, 1.0)
    return np.clip(np.where(f <= j, f / (2.0 * j), 0.5 + (f - j) / (2.0 * (0.5 - j))), 0.0, 1.0)


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
    profile : tuple of float
        K(s): the continuum's surface fibre stress under a moment over the beam formula
        6 M / (b h(s)^2) at :data:`STATIONS` (:meth:`surface_stress` reads it).
    shift : tuple of float
        delta(s) / L at :data:`STATIONS` on the first half: the surface above station s
        carries the moment at s - delta(s) (:meth:`surface_stress`); the second half's is
        the mirror's, of opposite sign.
    junction : float
        The hinge's :func:`junction`, which places :data:`STATIONS` along it.
    """

    bending: float
    shear: float
    stress: float
    inside: bool
    where: str
    profile: tuple[float, ...] = ()
    shift: tuple[float, ...] = ()
    junction: float = SMOOTH_JUNCTION
    plans: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)
    """:meth:`surface_stress`'s interpolation weights and factors per section and stations,
    kept: a hinge's model gives its forces at the same stations path after path."""

    def surface_stress(self, forces, section) -> tuple[np.ndarray, np.ndarray]:
        """The hinge's surface fibre stress along it: K(s) (|N(s)|/A + |M(s - delta(s))|
        h/(2 I)), MPa, at :data:`SURFACE_POINTS` and the forces' own stations.

        N and M are linear between the forces' stations (exact between a beam's nodes, which
        carry no distributed load), the table's profiles linear between theirs. Under a
        moment the peak sits where K(s)/h(s)^2 is largest (a filleted hinge's just inside a
        fillet, not on its flat); under a force across the hinge the beam formula's own peak
        leaves the waist for sections where the contour curves more (a power contour of n 3,
        a fillet's tangent point), where K is not the waist's (5 % above it on a power
        contour of n 3), and the shift adds the shear's share (up to 2 % on short hinges).

        Parameters
        ----------
        forces : flexval.reducedmodels.core.sections.SectionForces
            N (N) and M (N mm) at arc-length fractions ``forces.at`` from the first end, (m,)
            or (k, m).
        section : flexval.geometry.Section
            The hinge's section.

        Returns
        -------
        at : ndarray (p,)
            Arc-length fractions of the points from the first end.
        stress : ndarray (p,) or (k, p)
            MPa.
        """
        stations = np.ascontiguousarray(forces.at, float)
        key = (section, stations.tobytes())
        plan = self.plans.get(key)
        if plan is None:
            if len(self.plans) >= PLANS_KEPT:
                self.plans.clear()
            plan = self.plans[key] = self._surface_plan(stations, section)
        at, (lower, upper, w), (lower_n, upper_n, w_n), per_axial, per_moment = plan
        moment = np.asarray(forces.moment, float)
        axial = np.asarray(forces.axial, float)
        shifted = (1.0 - w) * moment[..., lower] + w * moment[..., upper]
        along = (1.0 - w_n) * axial[..., lower_n] + w_n * axial[..., upper_n]
        return at, np.abs(along) * per_axial + np.abs(shifted) * per_moment

    def _surface_plan(self, stations: np.ndarray, section) -> tuple:
        """What :meth:`surface_stress` needs of the stations and the section alone: the
        points, the linear weights of the shifted moment's and of the normal force's sources
        among the stations, and K/A (1/mm^2) and K h/(2 I) (1/mm^3) at the points."""
        from .core.sections import constants_at

        at = np.union1d(stations, SURFACE_POINTS)
        xi = _stations_at(at, self.junction)
        side = np.where(at <= 0.5, 1.0, -1.0)
        shift = side * np.interp(xi, STATIONS, self.shift)
        source = np.clip(at - shift, stations[0], stations[-1])
        h, area, inertia = constants_at(section, at)
        concentration = np.interp(xi, STATIONS, self.profile)
        out = (
            at,
            _weights(stations, source),
            _weights(stations, at),
            concentration / area,
            concentration * h / (2.0 * inertia),
        )
        for array in (out[0], *out[1], *out[2], out[3], out[4]):
            array.flags.writeable = False
        return out


SURFACE_POINTS = np.linspace(0.0, 1.0, 513)
"""Arc-length fractions at which :meth:`NotchFactors.surface_stress` evaluates a hinge's
surface stress besides the model's own stations: 1/512 of the length apart, a tenth of the
narrowest concentration peak of the table (a slender filleted hinge's, just inside its
fillet), which ``beam:100``'s element ends alone sample at 2 % below its top."""


PLANS_KEPT = 64
"""Most :meth:`NotchFactors.surface_stress` plans a hinge's factors keep (sections and
stations of the models that ran it)."""


def _weights(x: np.ndarray, at: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The lower and upper neighbours among the non-decreasing ``x`` (m,) of each of ``at``
    (p,) and the upper one's weight: values given at ``x``, linear in between and held
    beyond the ends, are (1 - w) v[lower] + w v[upper] at ``at``."""
    upper = np.clip(np.searchsorted(x, at, side="right"), 1, x.size - 1)
    lower = upper - 1
    span = x[upper] - x[lower]
    w = np.clip(np.where(span > 0.0, (at - x[lower]) / np.where(span > 0.0, span, 1.0), 0.0), 0, 1)
    return lower, upper, w


@cache
def calibration_table() -> dict:
    """The calibration table, read once."""
    text = resources.files("flexval.reducedmodels").joinpath("data", TABLE).read_text()
    return json.loads(text)


@cache
def _slices() -> dict[tuple[str, float | None], tuple]:
    """Per contour (and power exponent): the interpolants of (r_b, r_s, K, K(s) and
    delta(s) / L at the stations) over (log t/L, log H/t), Clough-Tocher and nearest-point."""
    from scipy.interpolate import CloughTocher2DInterpolator, NearestNDInterpolator

    groups: dict[tuple[str, float | None], list] = {}
    for row in calibration_table()["rows"]:
        groups.setdefault((row["contour"], row["exponent"]), []).append(row)
    out = {}
    for key, rows in groups.items():
        xy = np.array([[math.log(r["t_over_l"]), math.log(r["h_over_t"])] for r in rows])
        values = np.array(
            [[r["bending"], r["shear"], r["stress"], *r["profile"], *r["shift"]] for r in rows]
        )
        out[key] = (CloughTocher2DInterpolator(xy, values), NearestNDInterpolator(xy, values))
    return out


def _at(key: tuple[str, float | None], x: float, y: float) -> tuple[np.ndarray, bool]:
    """(r_b, r_s, K, K(s)..., delta(s)/L...) of one slice at (log t/L, log H/t), and whether
    it is inside it."""
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
    count = STATIONS.size
    profile = tuple(float(v) for v in values[3 : 3 + count])
    shift = tuple(float(v) for v in values[3 + count : 3 + 2 * count])
    # a fillet's tangent point at r / L = (H - t) / (2 L) (H = t + 2 r)
    joint = SMOOTH_JUNCTION
    if contour == "corner-filleted":
        joint = min(0.5 * (h_over_t - 1.0) * t_over_l, 0.5)
    return NotchFactors(
        float(values[0]), shear, float(values[2]), bool(inside), where, profile, shift, joint
    )


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
