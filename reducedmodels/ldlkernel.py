"""Compiled inertia of many small symmetric blocks: Bunch-Kaufman LDL^T (numba, on-disk cache).

A batch of copies whose own tangents are small and dense (``prbm``'s 21 x
21 saddle points on the open chain) judges each copy's stability on its
diagonal block, as the copy's own System judges it
(:meth:`flexval.reducedmodels.tangent.DenseTangent.negative_eigenvalues`):
the symmetric indefinite factorisation P K P^T = U D U^T with Bunch and
Kaufman's partial pivoting, whose block-diagonal D (1 x 1 and 2 x 2
blocks) has K's inertia (Sylvester's law). Called once per block through
SciPy's LAPACK wrapper (``dsytrf``) that cost 17 us a block, almost all of
it the call; here one compiled loop runs over every block of the batch.

The factorisation is LAPACK's unblocked upper one (``dsytf2``, which
``dsytrf`` runs on any matrix smaller than its block size of 64): the same
pivot choices with alpha = (1 + sqrt(17)) / 8, the same updates in the same
order, so D is LAPACK's to round-off and the count of its negative
eigenvalues, with the same margin, is the count the copy alone makes.

Units: whatever the matrix's (N/mm, N, N mm for a tangent).
"""

from __future__ import annotations

import math

import numpy as np

from .jit import kernel

ALPHA = (1.0 + math.sqrt(17.0)) / 8.0
"""Bunch and Kaufman's pivot threshold: the growth bound of a 1 x 1 against a 2 x 2 pivot."""


@kernel
def ldl_pivot_eigenvalues(a: np.ndarray) -> np.ndarray:
    """The eigenvalues of D in P A P^T = U D U^T (Bunch-Kaufman, LAPACK's ``dsytf2``, upper).

    Parameters
    ----------
    a : ndarray (m, m)
        A symmetric matrix; its upper triangle is read and overwritten by the
        factorisation.

    Returns
    -------
    ndarray (m,)
        D's 1 x 1 pivots and the two eigenvalues of each 2 x 2 pivot block
        (smaller first), in the order the factorisation leaves them. A zero
        column (a singular matrix) gives a zero pivot, as LAPACK's ``info`` > 0.
    """
    m = a.shape[0]
    eigenvalues = np.zeros(m)
    k = m - 1
    while k >= 0:
        step = 1
        diagonal = abs(a[k, k])
        row_max_of_k, column = 0, 0.0
        for i in range(k):  # the largest off-diagonal entry of column k (first of equals)
            if abs(a[i, k]) > column:
                column, row_max_of_k = abs(a[i, k]), i
        if max(diagonal, column) == 0.0 or math.isnan(diagonal):
            eigenvalues[k] = a[k, k]
            k -= 1
            continue
        pivot = k
        if diagonal < ALPHA * column:
            r = row_max_of_k
            row = 0.0  # the largest off-diagonal entry of row/column r within 0..k
            for j in range(r + 1, k + 1):
                if abs(a[r, j]) > row:
                    row = abs(a[r, j])
            for i in range(r):
                if abs(a[i, r]) > row:
                    row = abs(a[i, r])
            if diagonal >= ALPHA * column * (column / row):
                pivot = k
            elif abs(a[r, r]) >= ALPHA * row:
                pivot = r
            else:
                pivot, step = r, 2
        kk = k - step + 1
        if pivot != kk:  # interchange rows and columns kk and pivot of A(0:k, 0:k)
            for i in range(pivot):
                a[i, kk], a[i, pivot] = a[i, pivot], a[i, kk]
            for j in range(pivot + 1, kk):
                a[j, kk], a[pivot, j] = a[pivot, j], a[j, kk]
            a[kk, kk], a[pivot, pivot] = a[pivot, pivot], a[kk, kk]
            if step == 2:
                a[k - 1, k], a[pivot, k] = a[pivot, k], a[k - 1, k]
        if step == 1:
            r1 = 1.0 / a[k, k]
            for j in range(k):  # A(0:k-1, 0:k-1) -= r1 x x^T, x = A(0:k-1, k): dsyr's order
                if a[j, k] != 0.0:
                    t = -r1 * a[j, k]
                    for i in range(j + 1):
                        a[i, j] += a[i, k] * t
            for i in range(k):
                a[i, k] *= r1
            eigenvalues[k] = a[k, k]
        else:
            if k > 1:
                d12 = a[k - 1, k]
                d22 = a[k - 1, k - 1] / d12
                d11 = a[k, k] / d12
                t = 1.0 / (d11 * d22 - 1.0)
                d12 = t / d12
                for j in range(k - 2, -1, -1):
                    wkm1 = d12 * (d11 * a[j, k - 1] - a[j, k])
                    wk = d12 * (d22 * a[j, k] - a[j, k - 1])
                    for i in range(j, -1, -1):
                        a[i, j] = a[i, j] - a[i, k] * wk - a[i, k - 1] * wkm1
                    a[j, k] = wk
                    a[j, k - 1] = wkm1
            p, q, r = a[k - 1, k - 1], a[k - 1, k], a[k, k]
            mid, radius = 0.5 * (p + r), math.hypot(0.5 * (p - r), q)
            eigenvalues[k - 1], eigenvalues[k] = mid - radius, mid + radius
        k -= step
    return eigenvalues


@kernel
def negative_counts(
    storage: np.ndarray,
    b: int,
    m: int,
    copies: np.ndarray,
    own: np.ndarray,
    round_off: float,
) -> np.ndarray:
    """The negative eigenvalues of each copy's diagonal block of a banded tangent.

    Parameters
    ----------
    storage : ndarray (b + 1, n)
        The batch's tangent in LAPACK's upper band form: K[i, j], i <= j <=
        i + b, is ``storage[b + i - j, j]``.
    b, m : int
        The half-bandwidth, and the unknowns of one copy (copy c's block is
        K[c m : c m + m, c m : c m + m]).
    copies : ndarray of int
        The copies to judge.
    own : ndarray of int (m,)
        The block's rows in the copy's own numbering: entry (p, q) of the
        judged matrix is the block's (own[p], own[q]).
    round_off : float
        Eigenvalues of D below -round_off times the largest in size count.

    Returns
    -------
    ndarray of int (len(copies),)
        Per copy, the count; -1 where its block is not finite.
    """
    counts = np.zeros(copies.size, np.int64)
    block = np.empty((m, m))
    for c in range(copies.size):
        first = copies[c] * m
        finite = True
        for p in range(m):
            for q in range(p, m):
                i, j = own[p], own[q]
                if i > j:
                    i, j = j, i
                value = storage[b + i - j, first + j] if j - i <= b else 0.0
                finite = finite and math.isfinite(value)
                block[p, q] = value
                block[q, p] = value
        if not finite:
            counts[c] = -1
            continue
        eigenvalues = ldl_pivot_eigenvalues(block)
        largest = 0.0
        for value in eigenvalues:
            largest = max(largest, abs(value))
        for value in eigenvalues:
            if value < -round_off * largest:
                counts[c] += 1
    return counts
