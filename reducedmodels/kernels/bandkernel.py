"""Compiled banded Cholesky and LU factorisations and solves of narrow bands (numba, on-disk cache).

LAPACK's banded Cholesky (``dpbtrf``) treats a band narrower than its block
size column by column with one BLAS call each (``dscal``, ``dsyr``); on the
chains of beam elements (half-bandwidth 5, about a thousand columns) those
calls' overhead was the largest single cost of a Newton iteration, some 80 %
of the factorisation time. These loops do the same arithmetic in the same
order without the calls. :class:`flexval.reducedmodels.core.tangent.BandedTangent` uses
them up to ``NARROW_BAND`` and LAPACK above, where its vectorised BLAS wins.

The half-bandwidth b is given as the length of a tuple (:func:`band_token`):
numba compiles one machine code per b, in which the loops over the band have
a known trip count and are unrolled, which on a beam chain makes the
factorisation markedly faster than the same loops with b a run-time value.

Storage is LAPACK's upper band form: the entry K[i, j], i <= j <= i + b, of
a symmetric K is ``band[b + i - j, j]``.

Units: whatever the matrix's (N/mm, N, N mm for a tangent).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .jit import kernel


@functools.cache
def band_token(b: int) -> tuple[int, ...]:
    """The argument that selects the kernels compiled for half-bandwidth b: b + 1 zeros."""
    return (0,) * (b + 1)


@kernel
def band_cholesky(band: np.ndarray, token: tuple) -> tuple[np.ndarray, int]:
    """Upper Cholesky factor U (K = U^T U) of a positive definite band matrix; and a status.

    ``band`` (b + 1, n) holds K in upper band form, b = ``len(token) - 1``
    (:func:`band_token`); it is not modified. Returns the factor as
    ``factor[j, b + i - j] = U[i, j]`` for i < j (each column contiguous)
    with the reciprocals ``factor[j, b] = 1 / U[j, j]`` on the diagonal, and
    0; or, when a pivot is not positive (K is not positive definite), the
    partial factor and the 1-based column where it failed (LAPACK's ``info``).
    See :func:`factor_columns`.
    """
    no_rhs = np.empty(0)
    return factor_columns(band, token, no_rhs, np.empty(0, np.int64), no_rhs)


@kernel
def factor_columns(
    band: np.ndarray, token: tuple, rhs: np.ndarray, perm: np.ndarray, y: np.ndarray
) -> tuple[np.ndarray, int]:
    """:func:`band_cholesky`, and with a right-hand side (``rhs.size`` > 0) U^T y = P rhs too.

    Column by column (the "up-looking" order): U[i, j] = (K[i, j] -
    sum_k U[k, i] U[k, j]) / U[i, i], k ascending, the division done as a
    product with 1 / U[i, i]; the same operations in the same order as the
    right-looking rank-one updates of ``dpbtf2``, so the same rounding, but
    each entry summed in a register. Column j of U is all the forward
    substitution's unknown j needs (:func:`forward_unknown`): taken there,
    its chain of dependent operations overlaps the factorisation's instead
    of following it in a second pass (the same operations, the same numbers).
    """
    b = len(token) - 1
    n = band.shape[1]
    forward = rhs.size > 0
    factor = np.zeros((n, b + 1))
    for c in range(n):
        if c >= b:  # a full column: trip counts known, unrolled
            for r in range(b):  # U[c - b + r, c]
                total = band[r, c]
                i = c - b + r
                for s in range(r):  # k = c - b + s
                    total -= factor[i, b + s - r] * factor[c, s]
                factor[c, r] = total * factor[i, b]
            total = band[b, c]
            for s in range(b):
                total -= factor[c, s] * factor[c, s]
        else:  # the first b columns are shorter
            for i in range(c):
                total = band[b + i - c, c]
                for k in range(max(0, i - b), i):
                    total -= factor[i, b + k - i] * factor[c, b + k - c]
                factor[c, b + i - c] = total * factor[i, b]
            total = band[b, c]
            for k in range(c):
                total -= factor[c, b + k - c] * factor[c, b + k - c]
        if not total > 0.0:
            return factor, c + 1
        factor[c, b] = 1.0 / math.sqrt(total)
        if forward:
            forward_unknown(factor, rhs, perm, y, c, token)
    return factor, 0


@kernel
def forward_unknown(
    factor: np.ndarray, rhs: np.ndarray, perm: np.ndarray, y: np.ndarray, j: int, token: tuple
) -> None:
    """Unknown j of U^T y = P rhs, from column j of U and the unknowns before it (in place).

    Each unknown is a sum times a stored 1 / U[j, j]: a product, where a
    division would put its latency on the chain from one unknown to the
    next (the solve took 1.7 times as long).
    """
    b = len(token) - 1
    total = rhs[perm[j]]
    if j >= b:  # a full row: unrolled
        for s in range(b):
            total -= factor[j, s] * y[j - b + s]
    else:  # the first b rows are shorter
        for i in range(j):
            total -= factor[j, b + i - j] * y[i]
    y[j] = total * factor[j, b]


@kernel
def band_cholesky_solve(
    factor: np.ndarray, rhs: np.ndarray, perm: np.ndarray, token: tuple, out: np.ndarray
) -> None:
    """x with K x = rhs into ``out``, K = P^T U^T U P (:func:`band_cholesky`'s factor, P ``perm``).

    The band holds K's rows and columns in the order ``perm``: the solution
    comes back in the original order. ``rhs`` and ``out`` are contiguous
    (n,) (several right-hand sides: one call per column).
    """
    n = factor.shape[0]
    y = np.empty(n)
    for j in range(n):  # U^T y = P rhs
        forward_unknown(factor, rhs, perm, y, j, token)
    backward_solve(factor, y, perm, token, out)


@kernel
def backward_solve(
    factor: np.ndarray, y: np.ndarray, perm: np.ndarray, token: tuple, out: np.ndarray
) -> None:
    """x with U P x = y into ``out`` (``y`` overwritten): the second half of a Cholesky solve."""
    b = len(token) - 1
    n = factor.shape[0]
    head = min(b, n)
    for j in range(n - 1, n - 1 - head, -1):  # the short rows first
        total = y[j]
        for k in range(j + 1, n):
            total -= factor[k, b + j - k] * y[k]
        y[j] = total * factor[j, b]
    for j in range(n - 1 - head, -1, -1):
        total = y[j]
        for s in range(1, b + 1):
            total -= factor[j + s, b - s] * y[j + s]
        y[j] = total * factor[j, b]
    for j in range(n):
        out[perm[j]] = y[j]


@kernel
def band_factor_solve(
    band: np.ndarray, rhs: np.ndarray, perm: np.ndarray, token: tuple
) -> tuple[np.ndarray, int, np.ndarray]:
    """:func:`band_cholesky` of K, then K x = rhs (:func:`band_cholesky_solve`), in one call.

    Returns the factor, the status and x (``rhs`` (n,) contiguous; x is
    undefined when the status is not 0). A Newton correction is the first
    solve with each tangent: one call instead of two saves a dispatch and
    its Python around it, which on a short chain (90 unknowns) cost more
    than the arithmetic; and the forward substitution runs inside the
    factorisation (:func:`factor_columns`).
    """
    n = band.shape[1]
    y = np.empty(n)
    factor, info = factor_columns(band, token, rhs, perm, y)
    out = np.empty(n)
    if info == 0:
        backward_solve(factor, y, perm, token, out)
    return factor, info, out


@kernel
def band_lu(band: np.ndarray, token: tuple) -> tuple[np.ndarray, np.ndarray, int]:
    """LU factors with partial pivoting of a symmetric band matrix (``dgbtf2``'s algorithm).

    For the tangents whose Cholesky meets a non-positive pivot (an iterate
    where K is indefinite). ``band`` (b + 1, n) holds K in upper band form,
    b = ``len(token) - 1``. Returns the factors with column j contiguous,
    ``lu[j, 2 b + i - j]`` for i - j in [-2 b, b] (U, with the fill-in of
    the row interchanges, above and on the diagonal; the multipliers of L
    below), the row interchanges (row j was swapped with ``pivots[j]``) and
    0, or the 1-based column of the first zero pivot (LAPACK's ``info``).
    Right-looking: scale the column below the pivot by 1 / pivot, rank-one
    update of the columns the pivot row reaches.
    """
    b = len(token) - 1
    n = band.shape[1]
    d = 2 * b  # the diagonal's row
    lu = np.zeros((n, 3 * b + 1))
    for j in range(n):  # K[i, j] for |i - j| <= b, K symmetric
        if b <= j < n - b:  # trip counts known, unrolled
            for r in range(b + 1):  # i = j - b + r
                lu[j, b + r] = band[r, j]
            for p in range(1, b + 1):  # i = j + p
                lu[j, d + p] = band[b - p, j + p]
            continue
        for i in range(max(0, j - b), j + 1):
            lu[j, d + i - j] = band[b + i - j, j]
        for i in range(j + 1, min(n, j + b + 1)):
            lu[j, d + i - j] = band[b + j - i, i]
    pivots = np.empty(n, np.int64)
    info = 0
    reach = 0  # last column the pivot rows reach so far
    for j in range(n):
        below = min(b, n - 1 - j)
        jp, largest = 0, abs(lu[j, d])  # the first largest |entry| on and below the diagonal
        for p in range(1, below + 1):
            if abs(lu[j, d + p]) > largest:
                jp, largest = p, abs(lu[j, d + p])
        pivots[j] = j + jp
        if lu[j, d + jp] == 0.0:
            if info == 0:
                info = j + 1
            continue
        reach = max(reach, min(j + b + jp, n - 1))
        if jp != 0:
            for c in range(j, reach + 1):
                upper, lower = d + j - c, d + j + jp - c
                lu[c, upper], lu[c, lower] = lu[c, lower], lu[c, upper]
        if below == b:  # a full column: trip counts known, unrolled
            scale = 1.0 / lu[j, d]
            for p in range(1, b + 1):
                lu[j, d + p] *= scale
            for c in range(j + 1, reach + 1):
                y = lu[c, d + j - c]
                if y != 0.0:
                    for p in range(1, b + 1):
                        lu[c, d + j + p - c] -= lu[j, d + p] * y
        elif below > 0:  # the last b columns: the same, shorter
            scale = 1.0 / lu[j, d]
            for p in range(1, below + 1):
                lu[j, d + p] *= scale
            for c in range(j + 1, reach + 1):
                y = lu[c, d + j - c]
                if y != 0.0:
                    for p in range(1, below + 1):
                        lu[c, d + j + p - c] -= lu[j, d + p] * y
    return lu, pivots, info


@kernel
def band_lu_solve(
    lu: np.ndarray,
    pivots: np.ndarray,
    rhs: np.ndarray,
    perm: np.ndarray,
    token: tuple,
    out: np.ndarray,
) -> None:
    """x with K x = rhs into ``out``, from :func:`band_lu`'s factors of K ordered by ``perm``.

    ``rhs`` and ``out`` are contiguous (n,); L's row interchanges and
    multipliers, then U column by column (``dgbtrs``).
    """
    b = len(token) - 1
    n = lu.shape[0]
    d = 2 * b
    y = np.empty(n)
    for j in range(n):
        y[j] = rhs[perm[j]]
    for j in range(n - 1):
        swap = pivots[j]
        if swap != j:
            y[j], y[swap] = y[swap], y[j]
        for p in range(1, min(b, n - 1 - j) + 1):
            y[j + p] -= lu[j, d + p] * y[j]
    for j in range(n - 1, -1, -1):
        if y[j] != 0.0:
            y[j] = y[j] / lu[j, d]
            for i in range(max(0, j - d), j):
                y[i] -= y[j] * lu[j, d + i - j]
    for j in range(n):
        out[perm[j]] = y[j]


def warm_up(b: int) -> None:
    """Compile, or load from the on-disk cache, the kernels of half-bandwidth b.

    A band as :class:`flexval.reducedmodels.core.tangent.BandedTangent` holds it (a
    Fortran-ordered (b + 1, n) array) and contiguous right-hand sides; see
    :func:`flexval.reducedmodels.kernels.beamkernel.warm_up` for who calls it.
    """
    n = b + 2
    band = np.zeros((b + 1, n), order="F")
    band[b] = 1.0
    token = band_token(b)
    perm = np.arange(n, dtype=np.int64)
    band_factor_solve(band, np.ones(n), perm, token)
    factor, _ = band_cholesky(band, token)
    band_cholesky_solve(factor, np.ones(n), perm, token, np.empty(n))
    lu, pivots, _ = band_lu(band, token)
    band_lu_solve(lu, pivots, np.ones(n), perm, token, np.empty(n))
