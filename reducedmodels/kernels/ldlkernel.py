"""Compiled Bunch-Kaufman LDL^T of many small symmetric blocks: solves and inertia (numba).

A batch of copies whose own tangents are small dense saddle points
(``prbm``'s 21 x 21 on the open chain: Lagrange multipliers, so no
Cholesky factor) is factorised block by block as each copy's own System
factorises it (:class:`flexval.reducedmodels.core.tangent.DenseTangent`): the
symmetric indefinite factorisation P K P^T = U D U^T with Bunch and
Kaufman's partial pivoting, whose block-diagonal D (1 x 1 and 2 x 2
blocks) has K's inertia (Sylvester's law), so that one factorisation
serves the Newton solves and the stability check
(:class:`flexval.reducedmodels.core.blocktangent.BlockTangent`). Through SciPy's
LAPACK wrappers (``dsytrf``, ``dsytrs``) a block's cost is almost all the
call; here one compiled loop runs over every block of the batch.

The factorisation and the solve are LAPACK's unblocked upper ones
(``dsytf2``, which ``dsytrf`` runs on any matrix smaller than its block
size of 64, and ``dsytrs``): the same pivot choices with alpha =
(1 + sqrt(17)) / 8, the same updates in the same order, so D and the
solutions are LAPACK's to round-off; the count of D's negative
eigenvalues (:func:`ldl_negative`, the rule of
:mod:`flexval.reducedmodels.core.stability`) is made by the same kernel for a
copy alone (:class:`flexval.reducedmodels.core.tangent.DenseTangent`), so a batch
and its copies alone judge stability bit for bit alike.

Units: whatever the matrix's (N/mm, N, N mm for a tangent).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.roundoff import UNIT_ROUNDOFF
from .jit import kernel
from .stabilitykernel import one_negative, pair_negative

ALPHA = (1.0 + math.sqrt(17.0)) / 8.0
"""Bunch and Kaufman's pivot threshold: the growth bound of a 1 x 1 against a 2 x 2 pivot."""


def packed_size(m: int) -> int:
    """The entries of an m x m matrix's upper triangle: the length of its packed storage."""
    return m * (m + 1) // 2


def pack_upper(matrix: np.ndarray) -> np.ndarray:
    """A square matrix's upper triangle packed column by column (LAPACK's ``'U'`` packed
    storage: entry (i, j), i <= j, at i + j (j + 1) / 2), as :func:`ldl_solve` takes a
    factor."""
    m = matrix.shape[0]
    rows, cols = np.triu_indices(m)
    packed = np.empty(packed_size(m))
    packed[rows + cols * (cols + 1) // 2] = matrix[rows, cols]
    return packed


@kernel
def ldl_factor(
    a: np.ndarray, pivots: np.ndarray, eigenvalues: np.ndarray, scales: np.ndarray
) -> int:
    """P A P^T = U D U^T in place (Bunch-Kaufman, LAPACK's ``dsytf2``, upper), and D's eigenvalues.

    Parameters
    ----------
    a : ndarray (m, m)
        A symmetric matrix; its upper triangle is read and overwritten by
        U and D as ``dsytf2`` leaves them.
    pivots : ndarray of int (m,)
        Filled with the interchanges, as LAPACK's ``ipiv`` but from 0: row k
        of a 1 x 1 pivot was swapped with row ``pivots[k]``; the rows k - 1, k
        of a 2 x 2 pivot block both hold -1 - (the row swapped with k - 1).
    eigenvalues : ndarray (m,)
        Filled with D's 1 x 1 pivots and the two eigenvalues of each 2 x 2
        pivot block (smaller first), in the order of the factorisation.
    scales : ndarray (m,)
        Filled with each pivot's round-off scale, the diagonal of
        |U| |D| |U^T| (the magnitudes summed into it), row k's at k as the
        pivots lie in ``a``: what :func:`ldl_negative` judges each pivot
        against (:mod:`flexval.reducedmodels.core.stability`). Bookkeeping only:
        the factor is the same without it.

    Returns
    -------
    int
        0, or k + 1 for the first zero pivot k met (a singular matrix, as
        LAPACK's ``info``; the factorisation goes on past it).
    """
    m = a.shape[0]
    info = 0
    for i in range(m):
        scales[i] = abs(a[i, i])
    k = m - 1
    while k >= 0:
        step = 1
        diagonal = abs(a[k, k])
        row_max_of_k, column = 0, 0.0
        for i in range(k):  # the largest off-diagonal entry of column k (NaN passed over) ...
            column = max(column, abs(a[i, k]))
        if column > 0.0:
            for i in range(k):  # ... and its first row: a max, then a search, without the
                if abs(a[i, k]) == column:  # branch of a running argmax (8 % of a prbm block)
                    row_max_of_k = i
                    break
        if max(diagonal, column) == 0.0 or math.isnan(diagonal):
            if info == 0:
                info = k + 1
            pivots[k] = k
            eigenvalues[k] = a[k, k]
            k -= 1
            continue
        pivot = k
        if diagonal < ALPHA * column:
            r = row_max_of_k
            row = 0.0  # the largest off-diagonal entry of row/column r within 0..k
            for j in range(r + 1, k + 1):
                row = max(row, abs(a[r, j]))
            for i in range(r):
                row = max(row, abs(a[i, r]))
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
            scales[kk], scales[pivot] = scales[pivot], scales[kk]
            if step == 2:
                a[k - 1, k], a[pivot, k] = a[pivot, k], a[k - 1, k]
        if step == 1:
            r1 = 1.0 / a[k, k]
            for j in range(k):  # A(0:k-1, 0:k-1) -= r1 x x^T, x = A(0:k-1, k): dsyr's order
                if a[j, k] != 0.0:
                    t = -r1 * a[j, k]
                    scales[j] += abs(a[j, k] * t)
                    for i in range(j + 1):
                        a[i, j] += a[i, k] * t
            for i in range(k):
                a[i, k] *= r1
            pivots[k] = pivot
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
                    scales[j] += abs(a[j, k] * wk) + abs(a[j, k - 1] * wkm1)
                    for i in range(j, -1, -1):
                        a[i, j] = a[i, j] - a[i, k] * wk - a[i, k - 1] * wkm1
                    a[j, k] = wk
                    a[j, k - 1] = wkm1
            pivots[k] = pivots[k - 1] = -1 - pivot
            p, q, r = a[k - 1, k - 1], a[k - 1, k], a[k, k]
            mid, radius = 0.5 * (p + r), math.hypot(0.5 * (p - r), q)
            eigenvalues[k - 1], eigenvalues[k] = mid - radius, mid + radius
        k -= step
    return info


@kernel
def ldl_negative(a: np.ndarray, pivots: np.ndarray, scales: np.ndarray) -> int:
    """D's negative eigenvalues after :func:`ldl_factor` (``a`` its factor, square), by the one
    rule of :mod:`flexval.reducedmodels.core.stability`: each 1 x 1 pivot and 2 x 2 block judged
    against its own round-off scale, with gamma_(m+1) (a pivot sums at most m terms)."""
    m = pivots.size
    gamma = (m + 1) * UNIT_ROUNDOFF / (1.0 - (m + 1) * UNIT_ROUNDOFF)
    negative = 0
    k = m - 1
    while k >= 0:
        if pivots[k] >= 0:
            negative += one_negative(a[k, k], scales[k], gamma)
            k -= 1
        else:
            p, q, r = a[k - 1, k - 1], a[k - 1, k], a[k, k]
            negative += pair_negative(p, q, r, scales[k - 1], scales[k], gamma)
            k -= 2
    return negative


@kernel
def ldl_solve(a: np.ndarray, pivots: np.ndarray, x: np.ndarray) -> None:
    """Solve A x = b in place (``x`` holds b) with :func:`ldl_factor`'s U, D and pivots, the
    factor packed (:func:`pack_upper`: its columns contiguous, half the square's memory);
    LAPACK's ``dsytrs``, upper, one right-hand side."""
    m = pivots.size
    k = m - 1
    while k >= 0:  # U D y = b, from the last row up
        ck = k * (k + 1) // 2
        if pivots[k] >= 0:
            p = pivots[k]
            x[k], x[p] = x[p], x[k]
            for i in range(k):
                x[i] -= a[ck + i] * x[k]
            x[k] *= 1.0 / a[ck + k]
            k -= 1
        else:
            cm = (k - 1) * k // 2
            p = -1 - pivots[k]
            x[k - 1], x[p] = x[p], x[k - 1]
            for i in range(k - 1):
                x[i] -= a[ck + i] * x[k]
            for i in range(k - 1):
                x[i] -= a[cm + i] * x[k - 1]
            akm1k = a[ck + k - 1]
            akm1 = a[cm + k - 1] / akm1k
            ak = a[ck + k] / akm1k
            denominator = akm1 * ak - 1.0
            bkm1 = x[k - 1] / akm1k
            bk = x[k] / akm1k
            x[k - 1] = (ak * bkm1 - bk) / denominator
            x[k] = (akm1 * bk - bkm1) / denominator
            k -= 2
    k = 0
    while k < m:  # U^T x = y, from the first row down
        ck = k * (k + 1) // 2
        if pivots[k] >= 0:
            total = 0.0
            for i in range(k):
                total += a[ck + i] * x[i]
            x[k] -= total
            p = pivots[k]
            x[k], x[p] = x[p], x[k]
            k += 1
        else:
            cn = (k + 1) * (k + 2) // 2  # where column k + 1 starts
            total = 0.0
            for i in range(k):
                total += a[ck + i] * x[i]
            x[k] -= total
            total = 0.0
            for i in range(k):
                total += a[cn + i] * x[i]
            x[k + 1] -= total
            p = -1 - pivots[k]
            x[k], x[p] = x[p], x[k]
            k += 2


@kernel
def block_factor(
    storage: np.ndarray,
    places: np.ndarray,
    stride: int,
    factors: np.ndarray,
    pivots: np.ndarray,
    eigenvalues: np.ndarray,
    info: np.ndarray,
    negative: np.ndarray,
) -> None:
    """:func:`ldl_factor` of every copy's diagonal block of a block-diagonal matrix.

    Parameters
    ----------
    storage : ndarray (n_values,)
        The matrix's values, flat (a band's storage, say).
    places : ndarray of int (m, m)
        Where entry (p, q), p <= q, of copy 0's block lies in ``storage``
        (-1: a structural zero); copy c's is ``c * stride`` further on. Only
        the upper triangle is read.
    stride : int
        The values between one copy's block and the next's.
    factors, pivots, eigenvalues, info, negative : ndarray
        (copies, m (m + 1) / 2), (copies, m), (copies, m), (copies,) and
        (copies,): filled with each copy's :func:`ldl_factor` results and
        its negative eigenvalues (:func:`ldl_negative`; -1 when not finite), ``factors[c]``
        holding the factorised block packed (:func:`pack_upper`; half the
        square's memory: a 1000-copy ``prbm`` batch's factors stay in a
        core's 2 MB cache for the solves, which then cost half as much); a
        copy whose block is not finite is not factorised: info -1,
        eigenvalues NaN.
    """
    m = places.shape[0]
    scales = np.empty(m)
    work = np.empty((m, m))  # one copy's block, transposed: U's columns contiguous (a quarter
    a = work.T  # less time than row by row on prbm's blocks), kept in cache between copies
    for c in range(info.size):
        first = c * stride
        total = 0.0  # not finite if any entry is not
        for p in range(m):
            for q in range(p, m):
                place = places[p, q]
                value = storage[first + place] if place >= 0 else 0.0
                total += value
                work[q, p] = value
        if not math.isfinite(total):
            info[c] = -1
            negative[c] = -1
            eigenvalues[c, :] = np.nan
            continue
        info[c] = ldl_factor(a, pivots[c], eigenvalues[c], scales)
        negative[c] = ldl_negative(a, pivots[c], scales)
        packed, at = factors[c], 0
        for q in range(m):  # the upper triangle, column after column
            for p in range(q + 1):
                packed[at] = work[q, p]
                at += 1


@kernel
def block_solve(
    factors: np.ndarray,
    pivots: np.ndarray,
    info: np.ndarray,
    index: np.ndarray,
    rhs: np.ndarray,
    x: np.ndarray,
) -> None:
    """x = K^-1 rhs for the block-diagonal K :func:`block_factor` factorised (packed).

    ``index[c, p]`` is the unknown (the place in ``rhs`` and ``x``) of copy
    c's own row p. A copy not factorised or singular (``info`` non-zero)
    gets NaN.
    """
    m = index.shape[1]
    work = np.empty(m)
    for c in range(info.size):
        if info[c] != 0:
            for p in range(m):
                x[index[c, p]] = np.nan
            continue
        for p in range(m):
            work[p] = rhs[index[c, p]]
        ldl_solve(factors[c], pivots[c], work)
        for p in range(m):
            x[index[c, p]] = work[p]


def warm_up() -> None:
    """Compile (or load from the on-disk cache) every kernel on a 3 x 3 saddle point."""
    matrix = np.array([[2.0, 0.0, 1.0], [0.0, 1.0, 1.0], [1.0, 1.0, 0.0]])
    places = np.arange(9, dtype=np.int64).reshape(3, 3)
    factors, pivots = np.empty((1, packed_size(3))), np.empty((1, 3), np.int64)
    eigenvalues, info = np.empty((1, 3)), np.empty(1, np.int64)
    negative = np.empty(1, np.int64)
    block_factor(matrix.ravel(), places, 9, factors, pivots, eigenvalues, info, negative)
    index = np.arange(3, dtype=np.int64)[None, :]
    block_solve(factors, pivots, info, index, np.ones(3), np.empty(3))
