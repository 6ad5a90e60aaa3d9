"""The width effect on a flexure's bending stiffness: the classical theory of anticlastic curvature.

A flexure of depth b (out of plane), thickness h (in plane) and Young's
modulus E bends in its plane with the stiffness E·I (I = b h³/12) when it is
narrow: each fibre across the depth is free to contract or swell laterally,
so the section curls the other way across the depth (anticlastic curvature).
A wide one cannot curl and bends as a plate, with E·I/(1 - nu²). Which of the
two holds is decided by Searle's parameter beta = b² / (R h), R the radius of
curvature of the centre line. Across the depth the mid-surface is a beam on
an elastic foundation, free at z = ±b/2 (Searle 1908; Ashwell 1950; Conway
and Nickola 1965), and the moment of the whole section gives

    M / (E I kappa) = (1 - nu² q(phi)) / (1 - nu²),
    q(phi) = (2 / phi) (cosh phi - cos phi) / (sinh phi + sin phi),
    phi = (3 (1 - nu²))^(1/4) sqrt(beta),

1 for a narrow flexure, 1/(1 - nu²) for a wide one. The theory is linear: a
straight flexure has the ratio 1 exactly (its clamps stiffen a deep one all
the same: :mod:`flexval.geometry.clampedleaf`). The derivation, a straight
strip bent to a finite radius, what the formula does not cover and the
references are in the documentation's models page, "Flexures of finite
depth".

Units: mm (b, h, R); beta and the ratio are dimensionless.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from .clampedleaf import clamped_leaf_ratio
from .mechanism import Flexure, Material, Mechanism
from .profiles import quadrature_panels
from .shapes import Arc, Segment

SERIES_LIMIT = 4.0
"""phi below which the edge-effect term is summed from its power series.

Written as series in x = phi⁴, 1 - q = sum_(k>=1) 4k x^k / (4k+2)! over
sum_(k>=0) x^k / (4k+1)!: every term positive, so no cancellation where
q -> 1 and the closed form loses all digits of 1 - q. Up to phi = 4 the
:data:`SERIES_TERMS` terms reach round-off; beyond it q < 0.5 and the closed
form (scaled by cosh phi, finite for any phi) is exact to round-off."""

SERIES_TERMS = 16
"""Terms of each series: at phi = 4 those beyond the eleventh are below 1e-25 of the sum."""

QUADRATURE_PANELS = 64
"""Gauss panels over a varying flexure (:func:`flexval.geometry.profiles.quadrature_panels`)."""

_K = np.arange(SERIES_TERMS)
_DEN = np.array([1.0 / math.factorial(4 * k + 1) for k in range(SERIES_TERMS)])
_NUM = np.array([4.0 * k / math.factorial(4 * k + 2) for k in range(SERIES_TERMS)])


def searle_parameter(depth, thickness, radius) -> np.ndarray:
    """Searle's parameter beta = b² / (R h), dimensionless (vectorised).

    Parameters
    ----------
    depth, thickness, radius : array_like
        b, h and the radius of curvature R, mm (R = inf: straight, beta = 0;
        a negative R is taken by its size).
    """
    b, h, r = (np.asarray(v, float) for v in (depth, thickness, radius))
    return b * b / (np.abs(r) * h)


def edge_parameter(beta, poisson_ratio) -> np.ndarray:
    """phi = lambda b = (3 (1 - nu²))^(1/4) sqrt(beta): the depth in edge-effect lengths."""
    nu = np.asarray(poisson_ratio, float)
    return (3.0 * (1.0 - nu * nu)) ** 0.25 * np.sqrt(np.asarray(beta, float))


def _curled_share(phi: np.ndarray) -> np.ndarray:
    """1 - q(phi): the share of the depth that bends as a plate (0 at phi = 0, 1 at inf)."""
    out = np.empty_like(phi)
    small = phi < SERIES_LIMIT
    x = phi[small, None] ** 4
    powers = x**_K
    out[small] = (powers @ _NUM) / (powers @ _DEN)
    p = phi[~small]
    scale = np.exp(-p) * 2.0 / (1.0 + np.exp(-2.0 * p))  # 1 / cosh, without overflow
    q = (2.0 / p) * (1.0 - np.cos(p) * scale) / (np.tanh(p) + np.sin(p) * scale)
    out[~small] = 1.0 - q
    return out


def stiffness_ratio(beta, poisson_ratio) -> np.ndarray:
    """D_eff / (E I): the bending stiffness of a strip over the narrow beam's (vectorised).

    ``(1 - nu² q(phi)) / (1 - nu²)`` of the module text: 1 at beta = 0 (narrow
    beam, plane stress), increasing to 1 / (1 - nu²) as beta -> inf (plate,
    plane strain). Linear theory of a strip of initial radius R bent by a
    small change of curvature (see the module text for a straight strip bent
    to radius R, and for what it does not cover).

    Parameters
    ----------
    beta : array_like
        Searle's parameter b² / (R h) (:func:`searle_parameter`), >= 0.
    poisson_ratio : array_like
        nu, in (-1, 0.5].

    Raises
    ------
    ValueError
        If beta is negative or not finite, or nu is outside (-1, 0.5].
    """
    beta = np.asarray(beta, float)
    nu = np.asarray(poisson_ratio, float)
    if not np.all(np.isfinite(beta) & (beta >= 0.0)):
        raise ValueError(f"Searle's parameter must be finite and >= 0, got {beta}")
    if not np.all((nu > -1.0) & (nu <= 0.5)):
        raise ValueError(f"Poisson's ratio must lie in (-1, 0.5], got {nu}")
    phi, nu = np.broadcast_arrays(edge_parameter(beta, nu), nu)
    share = _curled_share(np.array(phi, float).ravel()).reshape(phi.shape)
    return 1.0 + nu * nu / (1.0 - nu * nu) * share


def flexure_ratio(flexure: Flexure, poisson_ratio: float) -> float:
    """The bending stiffness ratio of one flexure (:func:`stiffness_ratio`).

    A uniform arc: beta = b² / (R h) with its radius R. A uniform segment:
    the plate stiffening its clamps give it (:func:`flexval.geometry.clampedleaf.
    clamped_leaf_ratio`, calibrated against the 3D solid), where the strip theory alone
    gives 1 (a straight strip whose section curls freely). A varying section (taper,
    notch hinge) or a spline centre line: the local ratio r(s) from the local
    curvature and thickness, beta(s) = b² |kappa(s)| / h(s) (the strip theory
    taken section by section, valid where both change little over a length b),
    averaged so that the flexure's rotational compliance under a pure moment,
    ∫ ds / (E r I), is kept: 1 / r_mean = ∫ ds / (r I) / ∫ ds / I. The
    compliance gathers where I is least, so the thinnest part weighs most.

    Parameters
    ----------
    flexure : Flexure
        Depth, thickness law and centre line (mm).
    poisson_ratio : float
        nu of its material.
    """
    shape, section = flexure.shape, flexure.section
    if section.is_uniform and isinstance(shape, Segment):
        return clamped_leaf_ratio(section.depth, shape.length, poisson_ratio)
    if section.is_uniform and isinstance(shape, Arc):
        return _arc_ratio(section.depth, section.thickness, shape.radius, poisson_ratio)
    beta, weight = _along(flexure)
    return float(weight.sum() / (weight / stiffness_ratio(beta, poisson_ratio)).sum())


def flexure_searle(flexure: Flexure) -> float:
    """Searle's parameter of one flexure, dimensionless.

    b² / (R h) on a uniform arc, 0 on a uniform segment; on a varying section
    or a spline, the local beta(s) = b² |kappa(s)| / h(s) averaged with the
    weight of :func:`flexure_ratio`, ds / I(s) (where the bending compliance
    gathers).
    """
    shape, section = flexure.shape, flexure.section
    if section.is_uniform and isinstance(shape, Segment):
        return 0.0
    if section.is_uniform and isinstance(shape, Arc):
        return float(searle_parameter(section.depth, section.thickness, shape.radius))
    beta, weight = _along(flexure)
    return float((weight * beta).sum() / weight.sum())


def searle_parameters(mechanism: Mechanism) -> dict[str, float]:
    """:func:`flexure_searle` of each of a mechanism's flexures, by name."""
    return {f.name: flexure_searle(f) for f in mechanism.flexures}


def _along(flexure: Flexure) -> tuple[np.ndarray, np.ndarray]:
    """beta(s) at Gauss nodes along a flexure and the weights ds / I(s) up to b / 12 (mm⁻²)."""
    shape, section = flexure.shape, flexure.section
    breaks = () if section.profile is None else section.profile.breakpoints
    s, w = quadrature_panels(shape.length, breaks, QUADRATURE_PANELS)
    h = section.thickness_at(s)
    return section.depth**2 * np.abs(shape.curvature_at(s)) / h, w / h**3


@functools.lru_cache(maxsize=4096)
def _arc_ratio(depth: float, thickness: float, radius: float, poisson_ratio: float) -> float:
    """:func:`stiffness_ratio` of a uniform arc (mm), remembered: a mechanism's model is built
    again for every path of a report, a study or a benchmark, and numpy's overhead on one
    value is a tenth of an ``ee`` path."""
    beta = searle_parameter(depth, thickness, radius)
    return float(stiffness_ratio(beta, poisson_ratio))


def effective_material(material: Material, ratio: float) -> Material:
    """The material a flexure of bending stiffness ``ratio`` E I takes, MPa.

    E becomes ratio·E and nu becomes ratio (1 + nu) - 1, so that the shear
    modulus G = E / (2 (1 + nu)) is kept: the depth stiffens bending (and, in
    a reduced model that takes one E, the axial stiffness by as much, of no
    consequence on a slender flexure whose compliance is bending's), not the
    shear of the section. At ratio = 1 it is the material itself; at
    ratio = 1 / (1 - nu²) it is :meth:`~flexval.geometry.Material.plane_strain`'s
    pair E / (1 - nu²), nu / (1 - nu) (to round-off).
    """
    if ratio == 1.0:
        return material
    nu = material.poisson_ratio
    return dataclasses.replace(
        material,
        youngs_modulus=material.youngs_modulus * ratio,
        poisson_ratio=ratio * (1.0 + nu) - 1.0,
    )
