"""The compiled Bunch-Kaufman LDL^T of small blocks against LAPACK, eigenvalues and solves.

Its D is LAPACK's (``dsytrf``, which runs ``dsytf2`` below its block size)
to round-off, on positive definite, indefinite, saddle-point (zero diagonal
block: 2 x 2 pivots) and singular matrices; its count of negative
eigenvalues is Sylvester's (the eigenvalues' signs) and the dense tangent's;
its solves are LAPACK's (``dsytrs``) and satisfy K x = b. A batch's
:class:`BlockTangent` reads each copy's block from the band in the copy's
own numbering and solves and counts each copy as its own dense tangent does.
"""

import numpy as np
import pytest
from scipy.linalg import lapack

from flexval.reducedmodels.core.blocktangent import BlockTangent, block_maps
from flexval.reducedmodels.core.tangent import DenseTangent
from flexval.reducedmodels.kernels.ldlkernel import ldl_factor, ldl_negative, ldl_solve, pack_upper


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


def _saddle(rng: np.random.Generator, m: int) -> np.ndarray:
    """A stiffness block, constraints and a zero block: a saddle point of m unknowns."""
    n, c = m - m // 3, m // 3
    k = rng.standard_normal((n, n))
    s = np.zeros((m, m))
    s[:n, :n] = k @ k.T + np.eye(n)
    s[n:, :n] = rng.standard_normal((c, n))
    s[:n, n:] = s[n:, :n].T
    return s


def _matrices(rng: np.random.Generator) -> list[np.ndarray]:
    out = []
    for m in (1, 2, 3, 9, 21, 40):
        a = rng.standard_normal((m, m))
        out.append(a @ a.T + m * np.eye(m))  # positive definite
        out.append(a + a.T)  # indefinite
        if m >= 3:
            out.append(_saddle(rng, m))
            singular = a + a.T
            singular[:, 0] = singular[0, :] = 0.0  # a zero column: a zero pivot
            out.append(singular)
    return out


def test_d_is_lapacks_its_inertia_sylvesters_and_its_solves_lapacks():
    rng = np.random.default_rng(7)
    for matrix in _matrices(rng):
        m = matrix.shape[0]
        factor, pivots, d = np.array(matrix), np.empty(m, np.int64), np.empty(m)
        scales = np.empty(m)
        info = ldl_factor(factor, pivots, d, scales)
        scale = np.abs(matrix).max()
        # measured over 200 seeds of these matrices: D within 1.7e-13 of LAPACK's relative to
        # |D| + 0.01 |K| (OpenBLAS's dsyr fuses multiply-adds), the solutions within 1.6e-10
        # componentwise (the indefinite ones are ill-conditioned); the bounds keep a margin
        assert np.allclose(d, _lapack_d(matrix), rtol=1e-10, atol=1e-12 * scale)
        eigenvalues = np.linalg.eigvalsh(matrix)
        limit = 1e-9 * np.abs(eigenvalues).max()
        assert np.sum(d < -limit) == np.sum(eigenvalues < -limit)
        assert np.sum(d > limit) == np.sum(eigenvalues > limit)
        if np.abs(eigenvalues).min() > limit:  # the rule's count is Sylvester's
            assert ldl_negative(factor, pivots, scales) == np.sum(eigenvalues < 0.0)
        assert info == lapack.dsytrf(matrix)[2]
        if info:
            continue
        b = rng.standard_normal(m)
        x = b.copy()
        ldl_solve(pack_upper(factor), pivots, x)
        ldu, ipiv, _ = lapack.dsytrf(matrix)
        assert np.allclose(x, lapack.dsytrs(ldu, ipiv, b)[0], rtol=1e-9, atol=0.0)
        assert np.linalg.norm(matrix @ x - b) <= 1e-10 * np.linalg.norm(matrix, 1) * np.linalg.norm(
            x
        ) + 1e-12 * np.linalg.norm(b)


def _banded(blocks: list[np.ndarray], own: np.ndarray, b: int) -> np.ndarray:
    """The blocks in one upper band of half-width b (Fortran order), each in the band order
    that puts a copy's own row p at the block's row own[p]."""
    m = blocks[0].shape[0]
    storage = np.zeros((b + 1, m * len(blocks)), order="F")
    for c, block in enumerate(blocks):
        banded = np.zeros((m, m))
        banded[np.ix_(own, own)] = block
        for i in range(m):
            for j in range(i, min(m, i + b + 1)):
                storage[b + i - j, c * m + j] = banded[i, j]
    return storage


@pytest.mark.parametrize("b", [2, 5, 30])
def test_a_block_tangent_solves_and_counts_each_copy_as_its_own_dense_tangent(b):
    rng = np.random.default_rng(b)
    m = 9
    singular = _matrices(rng)[11]  # a zero column
    blocks = [_saddle(rng, m), _matrices(rng)[9], _saddle(rng, m), _saddle(rng, m), singular]
    copies = len(blocks)
    own = rng.permutation(m)  # copy c's own row p is the band's row c m + own[p]
    index = np.arange(copies * m).reshape(copies, m)  # the system numbers copy by copy
    perm = (np.arange(copies)[:, None] * m + np.argsort(own)[None, :]).ravel()
    assert np.array_equal(perm[np.arange(copies)[:, None] * m + own[None, :]], index)
    storage = _banded(blocks, own, b)
    storage[b, 3 * m + int(own[0])] = np.nan  # copy 3 not finite: not judged, not solved
    tangent = BlockTangent(storage.ravel(order="F"), perm, b, block_maps(own, b, index))
    rhs = rng.standard_normal(copies * m)
    x = tangent.solve(rhs)
    counts = tangent.copy_negative()
    for c, block in enumerate(blocks):
        banded = np.zeros((m, m))
        banded[np.ix_(own, own)] = block
        kept = np.triu(np.tril(banded, b), -b)[np.ix_(own, own)]  # what the band holds
        if c == 3:
            assert counts[c] == -1 and np.isnan(x[index[c]]).all()
            continue
        if c == 4:  # singular: its own copy gets no correction, the others theirs
            assert np.isnan(x[index[c]]).all()
            with pytest.raises(np.linalg.LinAlgError):
                DenseTangent(kept, indefinite=True).solve(rhs[index[c]])
            continue
        alone = DenseTangent(kept, indefinite=True)
        assert counts[c] == alone.negative_eigenvalues()
        assert np.allclose(x[index[c]], alone.solve(rhs[index[c]]), rtol=1e-9, atol=1e-12)
    assert tangent.negative_eigenvalues() is None
    assert not tangent.positive_definite()


def test_a_block_tangent_of_one_singular_copy_raises_as_the_copy_alone():
    rng = np.random.default_rng(3)
    singular = _matrices(rng)[11]
    m, own = singular.shape[0], np.arange(singular.shape[0])
    storage = _banded([singular], own, m - 1).ravel(order="F")
    index = np.arange(m)[None, :]
    tangent = BlockTangent(storage, np.arange(m), m - 1, block_maps(own, m - 1, index))
    with pytest.raises(np.linalg.LinAlgError, match="singular tangent"):
        tangent.solve(np.ones(m))
