"""The one stability rule: Sylvester's inertia, each pivot judged against its own round-off.

An equilibrium is stable when its tangent K has no negative eigenvalue beyond the one
each Lagrange multiplier makes. By Sylvester's law of inertia K = L D L^T (any symmetric
permutation, 1 x 1 and 2 x 2 blocks in D) has as many negative eigenvalues as D, so the
count comes from the factorisation the solves need anyway. Which pivots count is decided
by round-off, not by a tolerance: a pivot d_k is computed to within gamma_w sigma_k,

    sigma_k = |K_kk| + sum_j L_kj^2 |d_j|      (the diagonal of |L| |D| |L^T|),

gamma_w = w u / (1 - w u) for w terms and the unit round-off u (Higham,
*Accuracy and Stability of Numerical Algorithms*, 2nd ed., Sect. 3.1 and
Thm. 10.3). A pivot below -gamma_w sigma_k is negative; one within
+-gamma_w sigma_k has no sign the arithmetic can tell and is not counted; a
2 x 2 block is judged by its determinant. Why the rule holds whatever the
units and the resolution is in the documentation's concepts page ("One
stability rule"), the 2 x 2 blocks in ARCHITECTURE.md ("The core").

Every tangent storage (dense, banded, sparse; a batch's blocks) counts its negative
eigenvalues by this rule in its own factorisation: the compiled kernels of
:mod:`flexval.reducedmodels.kernels.stabilitykernel` (``one_negative``, ``pair_negative``,
``band_negative``; loaded on first use, so a stable path of a model that runs no compiled
code does not load numba) or :func:`count_pivots`, with the tolerance :func:`tolerance`.

Units: pivots and scales in the units of K's diagonal (N/mm, N, N mm); the
rule itself is dimensionless.
"""

from __future__ import annotations

import functools
from types import ModuleType

import numpy as np

from .roundoff import UNIT_ROUNDOFF, tolerance  # noqa: F401  (part of the rule's interface)


@functools.cache
def kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.stabilitykernel`; each kernel is compiled, or loaded
    from the on-disk cache, where it is first called, off the path's clock
    (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import stabilitykernel

    return stabilitykernel


def band_count(band: np.ndarray) -> int | None:
    """Negative eigenvalues of a symmetric band matrix (upper band form (b + 1, n)) by the rule:
    multipliers paired (:func:`paired_band`), then ``stabilitykernel.band_negative``; None
    when a pivot cannot be judged."""
    paired, pairs = paired_band(band)
    negative = kernels().band_negative(paired, pairs, 0, band.shape[1])
    return None if negative < 0 else int(negative)


def count_pivots(pivots: np.ndarray, scales: np.ndarray, gamma: float) -> int:
    """The 1 x 1 pivots negative beyond round-off (vectorised :func:`one_negative`)."""
    return int(np.count_nonzero(pivots < -gamma * scales))


def paired_band(band: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A band whose rows with a zero diagonal follow an unknown they couple to, and the pairs.

    A Lagrange multiplier's row has a zero diagonal: eliminated alone it is a
    zero pivot. Each such row is paired with the coupled row of largest
    |K_zj| / sqrt|K_jj| (unchanged by the units of either) not yet taken and
    moved right after it, so that the two are one 2 x 2 pivot of
    :func:`~flexval.reducedmodels.kernels.stabilitykernel.band_negative`, whose
    determinant -K_zj^2 < 0 is the multiplier's own negative eigenvalue.
    Returns (the reordered band in the same form, ``pairs``: True at the
    first row of each pair); the band as it is and no
    pairs when no diagonal is zero or a zero row couples to nothing free.
    """
    b = band.shape[0] - 1
    n = band.shape[1]
    diagonal = band[b]
    zero = np.flatnonzero(diagonal == 0.0)  # a multiplier's row
    pairs = np.zeros(n + 1, bool)
    if zero.size == 0:
        return band, pairs
    rows, cols, values = [], [], []
    for t in range(b + 1):  # entries (j - t, j), upper triangle
        j = np.arange(t, n)
        value = band[b - t, j]
        keep = value != 0.0
        rows.append(j[keep] - t)
        cols.append(j[keep])
        values.append(value[keep])
    rows, cols, values = np.concatenate(rows), np.concatenate(cols), np.concatenate(values)
    partner = {}
    taken = np.zeros(n, bool)
    taken[zero] = True
    for z in zero.tolist():
        near = np.flatnonzero((rows == z) | (cols == z))
        others = np.where(rows[near] == z, cols[near], rows[near])
        with np.errstate(divide="ignore"):  # another multiplier's: never taken
            strength = np.abs(values[near]) / np.sqrt(np.abs(diagonal[others]))
        best, best_value = -1, 0.0
        for other, value in zip(others.tolist(), strength.tolist()):
            if other != z and not taken[other] and value > best_value:
                best, best_value = other, value
        if best < 0:
            return band, np.zeros(n + 1, bool)
        taken[best] = True
        partner[best] = z
    order = []
    for i in range(n):
        if diagonal[i] == 0.0 and i in partner.values():
            continue
        order.append(i)
        if i in partner:
            pairs[len(order) - 1] = True
            order.append(partner[i])
    position = np.empty(n, np.int64)
    position[np.asarray(order)] = np.arange(n)
    i, j = position[rows], position[cols]
    low, high = np.minimum(i, j), np.maximum(i, j)
    width = int((high - low).max(initial=0))
    paired = np.zeros((width + 1, n), order="F")
    paired[width + low - high, high] = values
    return paired, pairs
