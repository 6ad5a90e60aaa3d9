"""Compiled kernels of the one stability rule (:mod:`flexval.reducedmodels.core.stability`, numba).

The judgement of a 1 x 1 pivot and of a 2 x 2 pivot block against their own
round-off, shared by every compiled factorisation that counts an inertia
(:mod:`flexval.reducedmodels.kernels.ldlkernel`'s Bunch-Kaufman), and the inertia of
a band by an LDL^T without interchanges.

Units: those of the matrix (N/mm, N, N mm for a tangent).
"""

from __future__ import annotations

import numpy as np

from ..core.roundoff import UNIT_ROUNDOFF
from .jit import kernel


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


def warm_up() -> None:
    """Compile (or load from the on-disk cache) the kernels on a 3 x 3 saddle point."""
    band = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [2.0, 1.0, 0.0]], order="F")
    band_negative(band, np.zeros(4, np.bool_), 0, 3)
