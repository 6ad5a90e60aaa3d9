"""The compiled Bunch-Kaufman inertia of small blocks against LAPACK and against eigenvalues.

Its D is LAPACK's (``dsytrf``, which runs ``dsytf2`` below its block size)
to round-off, on positive definite, indefinite, saddle-point (zero diagonal
block: 2 x 2 pivots) and singular matrices, and its count of negative
eigenvalues is the dense tangent's and Sylvester's (the eigenvalues' signs).
"""

import numpy as np
import pytest
from scipy.linalg import lapack

from flexval.reducedmodels.ldlkernel import ldl_pivot_eigenvalues, negative_counts
from flexval.reducedmodels.tangent import ROUND_OFF, DenseTangent


def _lapack_d(matrix: np.ndarray) -> np.ndarray:
    """D's eigenvalues from dsytrf's factor, in the kernel's order."""
    ldu, ipiv, _ = lapack.dsytrf(matrix)
    d = ldu.diagonal().copy()
    off = ldu.diagonal(1)
    k = matrix.shape[0] - 1
    while k >= 0:
        if ipiv[k] < 0:  # a 2 x 2 block in rows k - 1, k
            p, q, r = d[k - 1], off[k - 1], d[k]
            mid, radius = 0.5 * (p + r), np.hypot(0.5 * (p - r), q)
            d[k - 1], d[k] = mid - radius, mid + radius
            k -= 2
        else:
            k -= 1
    return d


def _matrices(rng: np.random.Generator) -> list[np.ndarray]:
    out = []
    for m in (1, 2, 3, 9, 21, 40):
        a = rng.standard_normal((m, m))
        out.append(a @ a.T + m * np.eye(m))  # positive definite
        out.append(a + a.T)  # indefinite
        if m >= 3:  # a saddle point: stiffness, constraints, zero block
            n, c = m - m // 3, m // 3
            k = rng.standard_normal((n, n))
            s = np.zeros((m, m))
            s[:n, :n] = k @ k.T + np.eye(n)
            s[n:, :n] = rng.standard_normal((c, n))
            s[:n, n:] = s[n:, :n].T
            out.append(s)
            singular = a + a.T
            singular[:, 0] = singular[0, :] = 0.0  # a zero column: a zero pivot
            out.append(singular)
    return out


def test_d_is_lapacks_and_its_inertia_is_sylvesters():
    rng = np.random.default_rng(7)
    for matrix in _matrices(rng):
        d = ldl_pivot_eigenvalues(np.array(matrix))
        scale = np.abs(matrix).max()
        assert np.allclose(d, _lapack_d(matrix), rtol=1e-10, atol=1e-12 * scale)
        eigenvalues = np.linalg.eigvalsh(matrix)
        limit = 1e-9 * np.abs(eigenvalues).max()
        assert np.sum(d < -limit) == np.sum(eigenvalues < -limit)
        assert np.sum(d > limit) == np.sum(eigenvalues > limit)


@pytest.mark.parametrize("b", [2, 5, 30])
def test_counts_read_each_copy_block_from_the_band_as_the_dense_tangent_counts(b):
    rng = np.random.default_rng(b)
    blocks = [_matrices(rng)[k] for k in (8, 9, 10, 9, 8)]  # 9 x 9: definite, indefinite, saddle
    copies, m = len(blocks), blocks[0].shape[0]
    own = rng.permutation(m)  # the copy's own row p is the batch's row own[p]
    n = copies * m
    storage = np.zeros((b + 1, n))
    for c, block in enumerate(blocks):
        # the band holds the block in the batch's order: entry (own[p], own[q]) is (p, q)
        banded = np.zeros((m, m))
        banded[np.ix_(own, own)] = block
        for i in range(m):
            for j in range(i, min(m, i + b + 1)):
                storage[b + i - j, c * m + j] = banded[i, j]
    storage[b, 3 * m + 2] = np.nan  # copy 3 not finite: not judged
    counts = negative_counts(storage, b, m, np.arange(copies), own, ROUND_OFF)
    for c, block in enumerate(blocks):
        banded = np.zeros((m, m))
        banded[np.ix_(own, own)] = block
        seen = np.triu(np.tril(banded, b), -b)  # what a band of half-width b keeps
        want = -1 if c == 3 else DenseTangent(seen[np.ix_(own, own)], True).negative_eigenvalues()
        assert counts[c] == want
