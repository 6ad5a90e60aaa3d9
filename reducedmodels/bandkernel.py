"""Compiled banded Cholesky factorisation and solve for narrow bands (numba, cached on disk).

LAPACK's banded Cholesky (``dpbtrf``) treats a band narrower than its block
size column by column with one BLAS call each (``dscal``, ``dsyr``); on the
chains of beam elements (half-bandwidth 5, about a thousand columns) those
calls' overhead was the largest single cost of a Newton iteration, some 80 %
of the factorisation time. These loops do the same arithmetic in the same
order without the calls. :class:`reducedmodels.tangent.BandedTangent` uses
them up to ``NARROW_BAND`` and LAPACK above, where its vectorised BLAS wins.

The half-bandwidth b is given as the length of a tuple (:func:`band_token`):
numba compiles one machine code per b, in which the loops over the band have
a known trip count and are unrolled. On a chain (b = 5, n = 1197) that made
the factorisation 2.7 times faster than the same loops with b a run-time
value (18 against 49 us, fastest of 3000 on a loaded machine).

Storage is LAPACK's upper band form: the entry K[i, j], i <= j <= i + b, of
a symmetric K is ``band[b + i - j, j]``.

Units: whatever the matrix's (N/mm, N, N mm for a tangent).
"""

from __future__ import annotations

import functools
import math

import numba
import numpy as np

_compiled = numba.njit(cache=True, error_model="numpy", nogil=True)


@functools.cache
def band_token(b: int) -> tuple[int, ...]:
    """The argument that selects the kernels compiled for half-bandwidth b: b + 1 zeros."""
    return (0,) * (b + 1)


@_compiled
def band_cholesky(band: np.ndarray, token: tuple) -> tuple[np.ndarray, int]:
    """Upper Cholesky factor U (K = U^T U) of a positive definite band matrix; and a status.

    ``band`` (b + 1, n) holds K in upper band form, b = ``len(token) - 1``
    (:func:`band_token`); it is not modified. Returns the factor as
    ``factor[j, b + i - j] = U[i, j]`` for i < j (each column contiguous)
    with the reciprocals ``factor[j, b] = 1 / U[j, j]`` on the diagonal, and
    0; or, when a pivot is not positive (K is not positive definite), the
    partial factor and the 1-based column where it failed (LAPACK's ``info``).

    Column by column (the "up-looking" order): U[i, j] = (K[i, j] -
    sum_k U[k, i] U[k, j]) / U[i, i], k ascending, the division done as a
    product with 1 / U[i, i]; the same operations in the same order as the
    right-looking rank-one updates of ``dpbtf2``, so the same rounding, but
    each entry summed in a register.
    """
    b = len(token) - 1
    n = band.shape[1]
    factor = np.zeros((n, b + 1))
    for c in range(n):
        if c >= b:                             # a full column: trip counts known, unrolled
            for r in range(b):                 # U[c - b + r, c]
                total = band[r, c]
                i = c - b + r
                for s in range(r):             # k = c - b + s
                    total -= factor[i, b + s - r] * factor[c, s]
                factor[c, r] = total * factor[i, b]
            total = band[b, c]
            for s in range(b):
                total -= factor[c, s] * factor[c, s]
        else:                                  # the first b columns are shorter
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
    return factor, 0


@_compiled
def band_cholesky_solve(factor: np.ndarray, rhs: np.ndarray, perm: np.ndarray, token: tuple,
                        out: np.ndarray) -> None:
    """x with K x = rhs into ``out``, K = P^T U^T U P (``factor`` of :func:`band_cholesky`, P ``perm``).

    The band holds K's rows and columns in the order ``perm``: the solution
    comes back in the original order. ``rhs`` and ``out`` are contiguous
    (n,) (several right-hand sides: one call per column). Each unknown is a
    sum times a stored 1 / U[j, j]: a product, where a division would put
    its latency on the chain from one unknown to the next (the solve took
    1.7 times as long).
    """
    b = len(token) - 1
    n = factor.shape[0]
    y = np.empty(n)
    head = min(b, n)
    for j in range(head):                      # U^T y = P rhs, the short rows first
        total = rhs[perm[j]]
        for i in range(j):
            total -= factor[j, b + i - j] * y[i]
        y[j] = total * factor[j, b]
    for j in range(head, n):
        total = rhs[perm[j]]
        for s in range(b):
            total -= factor[j, s] * y[j - b + s]
        y[j] = total * factor[j, b]
    for j in range(n - 1, n - 1 - head, -1):   # U (P x) = y, the short rows first
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


def warm_up(b: int) -> None:
    """Compile, or load from the on-disk cache, the kernels of half-bandwidth b.

    A band as :class:`reducedmodels.tangent.BandedTangent` holds it (a
    Fortran-ordered (b + 1, n) array) and contiguous right-hand sides; see
    :func:`reducedmodels.beamkernel.warm_up` for why.
    """
    n = b + 2
    band = np.zeros((b + 1, n), order="F")
    band[b] = 1.0
    token = band_token(b)
    factor, _ = band_cholesky(band, token)
    band_cholesky_solve(factor, np.ones(n), np.arange(n, dtype=np.int64), token, np.empty(n))
