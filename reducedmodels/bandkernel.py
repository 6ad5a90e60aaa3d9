"""Compiled banded Cholesky factorisation and solve for narrow bands (numba, cached on disk).

LAPACK's banded Cholesky (``dpbtrf``) treats a band narrower than its block
size column by column with one BLAS call each (``dscal``, ``dsyr``); on the
chains of beam elements (half-bandwidth 5, about a thousand columns) those
calls' overhead was the largest single cost of a Newton iteration, some 80 %
of the factorisation time. These loops do the same arithmetic in the same
order without the calls. :class:`reducedmodels.tangent.BandedTangent` uses
them up to ``NARROW_BAND`` and LAPACK above, where its vectorised BLAS wins.

Storage is LAPACK's upper band form: the entry K[i, j], i <= j <= i + b, of
a symmetric K is ``band[b + i - j, j]``.

Units: whatever the matrix's (N/mm, N, N mm for a tangent).
"""

from __future__ import annotations

import math

import numba
import numpy as np

_compiled = numba.njit(cache=True, error_model="numpy", nogil=True)


@_compiled
def band_cholesky(band: np.ndarray, b: int) -> tuple[np.ndarray, int]:
    """Upper Cholesky factor U (K = U^T U) of a positive definite band matrix; and a status.

    ``band`` (at least b + 1 rows, n) holds K in upper band form (rows 0..b);
    it is not modified. Returns the factor as ``factor[j, b + i - j] =
    U[i, j]`` (each column contiguous) and 0, or, when a pivot is not
    positive (K is not positive definite), the partial factor and the
    1-based column where it failed (LAPACK's ``info``).
    """
    n = band.shape[1]
    factor = np.empty((n, b + 1))
    for j in range(n):
        for r in range(b + 1):
            factor[j, r] = band[r, j]
    for j in range(n):
        pivot = factor[j, b]
        if not pivot > 0.0:
            return factor, j + 1
        pivot = math.sqrt(pivot)
        factor[j, b] = pivot
        width = min(b, n - 1 - j)
        scale = 1.0 / pivot
        for p in range(1, width + 1):
            factor[j + p, b - p] *= scale
        for q in range(1, width + 1):          # rank-one update of the trailing block
            x_q = factor[j + q, b - q]
            for p in range(1, q + 1):
                factor[j + q, b - q + p] -= factor[j + p, b - p] * x_q
    return factor, 0


@_compiled
def band_cholesky_solve(factor: np.ndarray, rhs: np.ndarray, perm: np.ndarray) -> np.ndarray:
    """x with K x = rhs, K = P^T U^T U P (``factor`` of :func:`band_cholesky`, ``perm`` P).

    The band holds K's rows and columns in the order ``perm``: the solution
    comes back in the original order. ``rhs`` is (n,) or (n, k).
    """
    n, width = factor.shape
    b = width - 1
    flat = rhs.reshape(n, -1)
    out = np.empty_like(flat)
    y = np.empty(n)
    for column in range(flat.shape[1]):
        for j in range(n):                     # U^T y = P rhs
            total = flat[perm[j], column]
            for i in range(max(0, j - b), j):
                total -= factor[j, b + i - j] * y[i]
            y[j] = total / factor[j, b]
        for j in range(n - 1, -1, -1):         # U (P x) = y
            total = y[j]
            for k in range(j + 1, min(n, j + b + 1)):
                total -= factor[k, b + j - k] * y[k]
            y[j] = total / factor[j, b]
        for j in range(n):
            out[perm[j], column] = y[j]
    return out.reshape(rhs.shape)


def warm_up() -> None:
    """Compile, or load from the on-disk cache, the kernels for the argument types flexval uses.

    A band as :class:`reducedmodels.tangent.BandedTangent` holds it (a
    Fortran-ordered (b + 1, n) array) and one or several right-hand sides;
    see :func:`reducedmodels.beamkernel.warm_up` for why.
    """
    band = np.zeros((2, 2), order="F")
    band[1] = 1.0
    factor, _ = band_cholesky(band, 1)
    perm = np.arange(2, dtype=np.int64)
    band_cholesky_solve(factor, np.ones(2), perm)
    band_cholesky_solve(factor, np.ones((2, 2)), perm)
