"""The one stability rule: Sylvester's inertia, each pivot judged against its own round-off.

An equilibrium is stable when its tangent K has no negative eigenvalue
beyond the one each Lagrange multiplier makes. By Sylvester's law of
inertia K = L D L^T (any symmetric permutation, 1 x 1 and 2 x 2 blocks in
D) has as many negative eigenvalues as D, so the count comes from the
factorisation the solves need anyway, at no cost beyond it.

Which pivots count is decided by round-off, not by a tolerance. In floating
point a pivot d_k = K_kk - sum_j L_kj^2 d_j is computed with an error of at
most gamma_w times the sum of the magnitudes it was formed from,

    sigma_k = |K_kk| + sum_j L_kj^2 |d_j|      (the diagonal of |L| |D| |L^T|),

gamma_w = w u / (1 - w u) for w terms and the unit round-off u (Higham,
*Accuracy and Stability of Numerical Algorithms*, 2nd ed., Sect. 3.1 and
Thm. 10.3: the computed factor is exact for K + dK with |dK| <= gamma
|L| |D| |L^T|). A pivot below -gamma_w sigma_k is negative whatever that
round-off did; one within +-gamma_w sigma_k has no sign the arithmetic can
tell, and is not counted. The rule is scale-free: a change of units scales
d_k and sigma_k alike (D S^2 for a diagonal S), and a finer resolution,
whose short elements make |K| large, makes each column's own sigma_k large
with it, never the bound of another column. (A bound against the largest
entry of K, as a margin times |K|, grows with the axial stiffness of the
shortest element while the buckling pivot does not, and hides buckling on
fine meshes.) Where the critical pivot itself falls below its own round-off
the resolution is beyond what double precision can judge.

A 2 x 2 pivot block [[p, q], [q, r]] (Bunch and Kaufman's, or a multiplier
paired with the unknown it constrains) is judged by its determinant
p r - q^2, whose round-off is at most 2 gamma (sigma_p sigma_r + q^2): a
negative determinant is one negative eigenvalue, a positive one two of p's
sign, and one within round-off has one eigenvalue without a sign (then
counted by p and r alone).

Every tangent storage (dense, banded, sparse; a batch's blocks) counts its
negative eigenvalues with :func:`one_negative` and :func:`pair_negative` and
the tolerance :func:`tolerance`, in its own factorisation.

Units: pivots and scales in the units of K's diagonal (N/mm, N, N mm); the
rule itself is dimensionless.
"""

from __future__ import annotations

import numpy as np

from .jit import kernel

UNIT_ROUNDOFF = float(np.finfo(float).eps) / 2.0
"""u, half the spacing of doubles at 1 (2^-53)."""


def tolerance(terms: int) -> float:
    """gamma_w = w u / (1 - w u): the relative round-off of a sum of ``terms`` products."""
    w = max(int(terms), 1) * UNIT_ROUNDOFF
    return w / (1.0 - w)


@kernel
def one_negative(pivot: float, scale: float, gamma: float) -> int:
    """1 if the 1 x 1 pivot is negative beyond its round-off gamma * scale, else 0."""
    return 1 if pivot < -gamma * scale else 0


@kernel
def pair_negative(
    p: float, q: float, r: float, scale_p: float, scale_r: float, gamma: float
) -> int:
    """Negative eigenvalues of the 2 x 2 pivot block [[p, q], [q, r]] beyond round-off.

    ``scale_p`` and ``scale_r`` are the round-off scales (sigma) of its two
    diagonal entries; see the module for the rule.
    """
    determinant = p * r - q * q
    bound = 2.0 * gamma * (scale_p * scale_r + q * q)
    if determinant < -bound:
        return 1
    if determinant > bound:
        return 2 if p < 0.0 else 0
    return max(one_negative(p, scale_p, gamma), one_negative(r, scale_r, gamma))


def count_pivots(pivots: np.ndarray, scales: np.ndarray, gamma: float) -> int:
    """The 1 x 1 pivots negative beyond round-off (vectorised :func:`one_negative`)."""
    return int(np.count_nonzero(pivots < -gamma * scales))


@kernel
def band_negative(band: np.ndarray, pairs: np.ndarray, first: int, stop: int) -> int:
    """Negative eigenvalues of a symmetric band matrix by the rule (-1: a pivot not judged).

    An LDL^T without interchanges of columns ``first`` .. ``stop - 1`` of
    ``band`` (LAPACK's upper band form (b + 1, n): ``band[b + i - j, j]`` is
    K[i, j]; entries outside those columns are ignored: a diagonal block of a
    block-diagonal matrix), with a 2 x 2 pivot on rows k, k + 1 where
    ``pairs[k]`` (a multiplier paired with an unknown it constrains, see
    :func:`paired_band`; the band keeps its width) and 1 x 1 pivots
    elsewhere. Each pivot's round-off scale sigma (the module's rule) is
    summed as the factorisation goes, with gamma_(b+2). Not judged (-1) when
    a 1 x 1 pivot is exactly zero with entries beside it (a saddle point
    not paired) or an entry is not finite. O(n b^2), the banded Cholesky's
    cost.
    """
    b = band.shape[0] - 1
    n = stop - first
    gamma = (b + 2) * UNIT_ROUNDOFF / (1.0 - (b + 2) * UNIT_ROUNDOFF)
    work = np.zeros((n + 1, b + 2))  # work[i, t] = K[i, i + t] (rows of the upper band)
    scales = np.empty(n)
    for j in range(n):
        for t in range(min(b, j) + 1):
            value = band[b - t, first + j]  # K[j - t, j]
            if not np.isfinite(value):
                return -1
            work[j - t, t] = value
        scales[j] = abs(work[j, 0])
    negative = 0
    k = 0
    while k < n:
        if pairs[first + k] and k + 1 < n:  # a 2 x 2 pivot on rows k, k + 1
            p, q, r = work[k, 0], work[k, 1], work[k + 1, 0]
            negative += pair_negative(p, q, r, scales[k], scales[k + 1], gamma)
            determinant = p * r - q * q
            if determinant == 0.0:
                return -1
            i00, i01, i11 = r / determinant, -q / determinant, p / determinant
            for tj in range(2, b + 2):  # rows j = k + tj that rows k, k + 1 reach
                j = k + tj
                if j >= n:
                    break
                vj0 = work[k, tj] if tj <= b else 0.0
                vj1 = work[k + 1, tj - 1]
                if vj0 == 0.0 and vj1 == 0.0:
                    continue
                wj0 = i00 * vj0 + i01 * vj1  # B^-1 v_j
                wj1 = i01 * vj0 + i11 * vj1
                scales[j] += (
                    abs(i00) * vj0 * vj0 + 2.0 * abs(i01 * vj0 * vj1) + abs(i11) * vj1 * vj1
                )
                for ti in range(tj, b + 2):  # K[j, i] -= v_j^T B^-1 v_i, i >= j
                    i = k + ti
                    if i >= n:
                        break
                    vi0 = work[k, ti] if ti <= b else 0.0
                    vi1 = work[k + 1, ti - 1]
                    work[j, ti - tj] -= wj0 * vi0 + wj1 * vi1
            k += 2
            continue
        d = work[k, 0]
        negative += one_negative(d, scales[k], gamma)
        if d == 0.0:
            for t in range(1, b + 1):
                if work[k, t] != 0.0:
                    return -1
            k += 1
            continue
        for t in range(1, b + 1):  # rank-one update of the rows below
            j = k + t
            if j >= n:
                break
            a = work[k, t]
            if a == 0.0:
                continue
            scales[j] += a * a / abs(d)
            factor = a / d
            for s in range(t, b + 1):
                i = k + s
                if i >= n:
                    break
                work[j, s - t] -= factor * work[k, s]
        k += 1
    return negative


def paired_band(band: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A band whose rows with a zero diagonal follow an unknown they couple to, and the pairs.

    A Lagrange multiplier's row has a zero diagonal: eliminated alone it is a
    zero pivot. Each such row is paired with the coupled row of largest
    |K_zj| / sqrt|K_jj| (unchanged by the units of either) not yet taken and
    moved right after it, so that the two are one 2 x 2 pivot of
    :func:`band_negative`, whose determinant -K_zj^2 < 0 is the multiplier's
    own negative eigenvalue. Returns (the reordered band in the same form,
    ``pairs``: True at the first row of each pair); the band as it is and no
    pairs when no diagonal is zero or a zero row couples to nothing free.
    """
    b = band.shape[0] - 1
    n = band.shape[1]
    diagonal = band[b]
    zero = np.flatnonzero(diagonal == 0.0)
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
        strength = np.abs(values[near]) / np.sqrt(np.abs(diagonal[others]) + 0.0)
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
