"""The elements of a ``beam:N`` flexure whose section varies along it.

A uniform flexure keeps its N equal elements and closed-form stiffness
(:class:`flexval.reducedmodels.beam.elements.BeamConnector`); a tapered or notched one
takes both from here.

**Stations.** The nodes lie on the centre line at arc lengths s_0 = 0 <
s_1 < ... < s_N = L (mm) that share the density

    rho(s) = ((kappa0(s) / kappa_max)^2 + (h_min / h(s))^6)^(1/3)

equally, kappa_max = 2 MAX_STRAIN / h_min (:mod:`flexval.reducedmodels.core.validity`):
the least chord error for N elements, short where the centre line or the bending curves.

**Element stiffness.** Each element is a straight two-node beam over its chord l0 whose
section law is the flexure's over the element's arc, stretched onto the chord; the
unit-load method gives its flexibility (xi in [0, 1] along it)

    F = l0 * integral over xi of [[(1-xi)^2, -xi(1-xi)], [-xi(1-xi), xi^2]] / EI d xi
        + (l0 * integral of d xi / (kappa G A)) / l0^2 [[1, 1], [1, 1]]   (shear only),

k_b = F^-1 and the axial stiffness 1 / (l0 * integral of d xi / EA): exact for the linear
statics of a straight non-uniform beam loaded at its nodes. The integrals are Gauss rules
split at the profile's breakpoints (:func:`flexval.geometry.profiles.quadrature_panels`).
Both derivations are in the documentation's models page, "Other shapes and varying
sections".

Units: mm, N, MPa, N mm.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from flexval.geometry.mechanism import Material, Section
from flexval.geometry.profiles import quadrature_panels
from flexval.geometry.shapes import Shape

from ..core.validity import MAX_STRAIN

GAUSS_ORDER = 8
"""Gauss-Legendre points per panel, in the stations' density integral and the elements'."""

PANELS = 64
"""Panels over the whole flexure: the stations' density integral has this many (in
proportion to the stretches between breakpoints); an element's integrals have
PANELS times its share of the length, at least four (so a single element is
integrated as :func:`flexval.geometry.profiles.quadrature_panels` integrates a flexure)."""

STATION_ITERATIONS = 8
"""Most Newton iterations placing a station inside its panel (three or four reach round-off)."""


@dataclass(frozen=True)
class ElementStiffness:
    """The elements' stiffness and flexibility tables, (N,) each.

    Attributes
    ----------
    k_axial : array
        Axial stiffness 1 / integral of ds / EA, N/mm.
    k11, k12, k22 : array
        Local bending stiffness k_b = [[k11, k12], [k12, k22]], N mm.
    bending_flexibility : array
        Integral of ds / EI over the element (the turn per unit moment), 1/(N mm).
    mean_area : array
        Mean area over the element's arc, mm^2 (times a density: its mass per length).
    """

    k_axial: np.ndarray
    k11: np.ndarray
    k12: np.ndarray
    k22: np.ndarray
    bending_flexibility: np.ndarray
    mean_area: np.ndarray


def panel_edges(length: float, breakpoints: tuple[float, ...], panels: int = PANELS) -> np.ndarray:
    """Edges (mm) of panels on [0, length], clustered at the ends of each stretch between breaks.

    Each stretch [a, b] is cut at a + (b - a)(1 - cos theta)/2 for theta
    evenly spaced in [0, pi] (the map of
    :func:`flexval.geometry.profiles.quadrature_panels`), in proportion to
    its length and at least four panels.
    """
    cuts = [0.0, *sorted(b for b in breakpoints if 0.0 < b < length), length]
    edges = [np.zeros(1)]
    for a, b in zip(cuts[:-1], cuts[1:]):
        n = max(4, math.ceil(panels * (b - a) / length))
        theta = np.linspace(0.0, math.pi, n + 1)[1:]
        edges.append(a + 0.5 * (b - a) * (1.0 - np.cos(theta)))
    out = np.concatenate(edges)
    out[-1] = length
    return out


def reference_rule(panels: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights on [0, 1] clustered at both ends: a stretch's rule scaled to its length.

    :func:`flexval.geometry.profiles.quadrature_panels` on the unit interval
    (``panels`` panels of :data:`GAUSS_ORDER` points): a square-root
    behaviour of h at either end (elliptical and corner-filleted notches)
    becomes a smooth integrand.
    """
    return quadrature_panels(1.0, (), panels, GAUSS_ORDER)


def station_density(shape: Shape, section: Section) -> Callable[[np.ndarray], np.ndarray]:
    """rho(s) of the module text (dimensionless) at arc lengths s (mm) of a varying section."""
    h_min = section.thickness
    kappa_max = 2.0 * MAX_STRAIN / h_min  # 1/mm

    def density(s: np.ndarray) -> np.ndarray:
        own = shape.curvature_at(s) / kappa_max
        return (own * own + (h_min / section.thickness_at(s)) ** 6) ** (1.0 / 3.0)

    return density


def graded_stations(shape: Shape, section: Section, n: int) -> np.ndarray:
    """Node arc lengths (n + 1,), mm, sharing the integral of :func:`station_density` equally.

    The density's integral is taken panel by panel (:func:`panel_edges`,
    split at the profile's breakpoints; :func:`reference_rule` on each);
    each interior station is then found inside its panel by Newton on the
    integral from the panel's start, to round-off.

    Parameters
    ----------
    shape : Shape
        The centre line (its length and curvature).
    section : Section
        A varying section: h(s), mm, for s from 0 to the shape's length.
    n : int
        Number of elements, >= 1.
    """
    length = shape.length
    density = station_density(shape, section)

    u, w = reference_rule(4)
    edges = panel_edges(length, section.profile.breakpoints)
    a, b = edges[:-1], edges[1:]
    shares = (density(a[:, None] + (b - a)[:, None] * u) @ w) * (b - a)
    cumulative = np.concatenate([[0.0], np.cumsum(shares)])
    targets = cumulative[-1] * np.arange(1, n) / n
    j = np.clip(np.searchsorted(cumulative, targets, side="right") - 1, 0, a.size - 1)
    start, remaining = a[j], targets - cumulative[j]
    s = start + (b[j] - start) * np.clip(remaining / shares[j], 0.0, 1.0)
    for _ in range(STATION_ITERATIONS):
        span = s - start
        step = ((density(start[:, None] + span[:, None] * u) @ w) * span - remaining) / density(s)
        s = np.clip(s - step, a[j], b[j])
        if np.all(np.abs(step) <= 4.0 * np.finfo(float).eps * length):
            break
    return np.concatenate([[0.0], s, [length]])


def element_stiffness(
    section: Section,
    material: Material,
    stations: np.ndarray,
    chords: np.ndarray,
    shear_correction: float | None,
) -> ElementStiffness:
    """Each element's stiffness from the section law over its arc (formulas in the module text).

    Parameters
    ----------
    section : Section
        Depth and the thickness profile h(s) (s from the flexure's first end, mm).
    material : Material
        E, nu (MPa).
    stations : array (N + 1,)
        The nodes' arc lengths, mm, increasing.
    chords : array (N,)
        The elements' initial chord lengths l0, mm.
    shear_correction : float or None
        kappa for Timoshenko elements (shear flexibility), None for Euler-Bernoulli.
    """
    breaks = () if section.profile is None else section.profile.breakpoints
    inner = [b for b in breaks if stations[0] < b < stations[-1]]
    cuts = np.union1d(stations, inner)
    left, right = cuts[:-1], cuts[1:]
    element = np.searchsorted(stations, left, side="right") - 1
    total = float(stations[-1] - stations[0])
    panels = max(4, math.ceil(PANELS * float((right - left).max()) / total))
    u, wu = reference_rule(panels)
    width = right - left
    s = left[:, None] + width[:, None] * u
    weight = width[:, None] * wu
    start, span = stations[element], np.diff(stations)[element]
    xi = (s - start[:, None]) / span[:, None]
    area = section.area_at(s)
    bend = weight / (material.youngs_modulus * section.inertia_at(s))
    n_elements = chords.size

    def per_element(values: np.ndarray) -> np.ndarray:
        return np.bincount(element, values.sum(axis=1), minlength=n_elements)

    scale = chords / np.diff(stations)  # the arc's section law stretched onto the chord
    f11 = scale * per_element(bend * (1.0 - xi) ** 2)
    f22 = scale * per_element(bend * xi**2)
    f12 = -scale * per_element(bend * xi * (1.0 - xi))
    if shear_correction is not None:
        shear = weight / (shear_correction * material.shear_modulus * area)
        extra = scale * per_element(shear) / chords**2
        f11, f22, f12 = f11 + extra, f22 + extra, f12 + extra
    det = f11 * f22 - f12 * f12
    axial = scale * per_element(weight / (material.youngs_modulus * area))
    return ElementStiffness(
        k_axial=1.0 / axial,
        k11=f22 / det,
        k12=-f12 / det,
        k22=f11 / det,
        bending_flexibility=scale * per_element(bend),
        mean_area=per_element(weight * area) / np.diff(stations),
    )
