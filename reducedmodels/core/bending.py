"""How a straight flexure of varying section bends freely: the kinematics of its compliance.

Under a pure moment every section of a straight flexure carries the same M, so a part of it
from s = 0 to l bends to the angle phi W(s) at s, W(s) = ∫_0^s ds / EI over ∫_0^l ds / EI
(0 at its start, 1 at its end), and its end lies at

    E(phi) = ∫_0^l (cos(phi W(s)), sin(phi W(s))) ds

in the frame of its start (x along its axis at rest). A reduced model that lumps the part's
compliance at a point (a pivot, a DCMM sub-arc's centre of elasticity) turns its two bodies
about that point instead; the difference is what its bodies' material points there part by,
O(phi^2), nothing for a compliance gathered at the point, L phi^2 / 12 for a uniform part.
:func:`centre_separation` gives it at the centre of elasticity x_c = l - ∫_0^l W ds,

    g(phi) = E(phi) + R(phi) (x_c - l, 0) - (x_c, 0),

as the even and odd series of its two components; a notch hinge's models take it so that a
moment bends them as the hinge bends (:mod:`flexval.reducedmodels.prbm.pivot`,
:mod:`flexval.reducedmodels.kernels.dcmmkernel`). W and its moments come from the
trapezoidal rule on :data:`SAMPLES` intervals (the contour's breakpoints added): relative
errors below 1e-6.

Units: mm, rad.
"""

from __future__ import annotations

import functools
import math

import numpy as np

SAMPLES = 4096
"""Intervals of the trapezoidal rule for W(s) and its moments over a flexure or a part."""

TERMS = 7
"""Terms of each series of :func:`centre_separation` a DCMM sub-arc takes: the first left
out is below (phi / 2)^15 / 15! of its length, 2e-17 at phi = 1 rad."""


def cumulative_compliance(section, s0: float, s1: float) -> tuple[np.ndarray, np.ndarray]:
    """Arc length from ``s0`` (mm, towards ``s1``, which may lie before it) and W there, 0..1:
    the share of ∫ ds / EI from ``s0``, of a varying ``section`` (its profile's h(s))."""
    lo, hi = min(s0, s1), max(s0, s1)
    inner = [b for b in section.profile.breakpoints if lo < b < hi]
    s = np.union1d(np.linspace(lo, hi, SAMPLES + 1), inner)
    w = 1.0 / np.asarray(section.inertia_at(s), float)  # 1 / EI up to E, which cancels
    if s1 < s0:
        s, w = s[::-1], w[::-1]
    along = np.abs(s - s0)
    steps = np.diff(along)
    cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * steps)])
    return along, cumulative / cumulative[-1]


def trapezoid(values: np.ndarray, along: np.ndarray) -> float:
    """∫ values d(along) by the trapezoidal rule."""
    return float(np.sum(0.5 * (values[1:] + values[:-1]) * np.diff(along)))


@functools.lru_cache(maxsize=1024)
def centre_separation(
    section, s0: float, s1: float, terms: int
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The series of g(phi) (module text) of the part [s0, s1] of a straight flexure of varying
    ``section``, run from ``s0``: (a_1..a_terms), (b_1..b_terms), mm, with

        g_x = sum a_k phi^2k,   g_y = sum b_k phi^(2k + 1),
        a_k = (-1)^k (m_2k + x_c - l) / (2k)!,   b_k = (-1)^k (m_(2k+1) + x_c - l) / (2k + 1)!,

    m_j = ∫_0^l W^j ds (cos and sin of phi W term by term, and of phi in R(phi)); the
    constant and linear terms vanish at the centre of elasticity. Remembered per part: a
    study builds the same hinges again and again."""
    along, share = cumulative_compliance(section, s0, s1)
    moments = [trapezoid(share**j, along) for j in range(2 * terms + 2)]
    offset = -moments[1]  # x_c - l, x_c = l - m_1
    a = tuple(
        (-1) ** k * (moments[2 * k] + offset) / math.factorial(2 * k) for k in range(1, terms + 1)
    )
    b = tuple(
        (-1) ** k * (moments[2 * k + 1] + offset) / math.factorial(2 * k + 1)
        for k in range(1, terms + 1)
    )
    return a, b
