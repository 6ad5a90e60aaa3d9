"""The compiled narrow-band Cholesky and LU kernels against LAPACK and dense linear algebra.

Every half-bandwidth has its own machine code (the band's width is a
compile-time constant); the smallest, the beam chains' and the largest
compiled ones are checked (each costs a compilation on a cold cache): the
Cholesky factor against LAPACK's ``dpbtrf`` (the same operations in the
same order: equal to round-off; the diagonal is stored as reciprocals), the
solves against dense solves of the permuted system, the failure column of
an indefinite matrix against ``dpbtrf``'s ``info``, and the LU of an
indefinite band against ``dgbtrf`` (same pivots, factors to round-off).
"""

import numpy as np
import pytest
from scipy.linalg import lapack

from flexval.reducedmodels.beam.elements import CHAIN_HALF_BANDWIDTH
from flexval.reducedmodels.core.tangent import NARROW_BAND, BandedTangent, band_kernels

N = 23  # more columns than any band is wide: full and short columns both occur
WIDTHS = sorted({1, 2, CHAIN_HALF_BANDWIDTH, NARROW_BAND})


def random_band(b: int, rng: np.random.Generator, shift: float) -> np.ndarray:
    """A symmetric band matrix (N, N) of half-bandwidth b with ``shift`` added to the diagonal."""
    dense = rng.normal(size=(N, N))
    dense = dense + dense.T
    rows, cols = np.indices((N, N))
    dense[np.abs(rows - cols) > b] = 0.0
    return dense + shift * np.eye(N)


def band_token_of(b: int) -> tuple:
    """The kernels' selector of half-bandwidth b."""
    return band_kernels(b).band_token(b)


def upper_band(dense: np.ndarray, b: int) -> np.ndarray:
    """LAPACK's upper band form (b + 1, N), Fortran order, of a symmetric matrix."""
    band = np.zeros((b + 1, N), order="F")
    for k in range(b + 1):
        j = np.arange(k, N)
        band[b - k, j] = dense[j - k, j]
    return band


@pytest.mark.parametrize("b", [0, *WIDTHS])
def test_factor_and_solve_agree_with_lapack_and_a_dense_solve(b):
    rng = np.random.default_rng(b)
    dense = random_band(b, rng, 4.0 * (b + 1))  # diagonally dominant: positive definite
    band = upper_band(dense, b)
    kernels = band_kernels(b)
    factor, info = kernels.band_cholesky(band, kernels.band_token(b))
    reference, ref_info = lapack.dpbtrf(band, lower=0)
    assert info == ref_info == 0
    for j in range(N):  # factor[j, b + i - j] = U[i, j], factor[j, b] = 1 / U[j, j]
        rows = slice(max(0, b - j), b)
        np.testing.assert_allclose(factor[j, rows], reference[rows, j], rtol=1e-14, atol=1e-14)
        assert factor[j, b] == pytest.approx(1.0 / reference[b, j], rel=1e-14)
    perm = rng.permutation(N)
    matrix = np.empty((N, N))
    matrix[np.ix_(perm, perm)] = dense  # the band holds K[perm][:, perm]
    rhs = rng.normal(size=(N, 2))
    tangent = BandedTangent(band, perm.astype(np.int64), b)
    np.testing.assert_allclose(tangent.solve(rhs), np.linalg.solve(matrix, rhs), rtol=1e-12)
    np.testing.assert_allclose(
        tangent.solve(rhs[:, 0]), np.linalg.solve(matrix, rhs[:, 0]), rtol=1e-12
    )
    assert tangent.negative_eigenvalues() == 0
    first = BandedTangent(band, perm.astype(np.int64), b)  # factorised by its first solve
    np.testing.assert_allclose(
        first.solve(rhs[:, 0]), np.linalg.solve(matrix, rhs[:, 0]), rtol=1e-12
    )
    assert first.negative_eigenvalues() == 0


@pytest.mark.parametrize("b", WIDTHS)
def test_factor_and_solve_in_one_call_equal_the_two_calls(b):
    """band_factor_solve is band_cholesky then band_cholesky_solve: the same numbers, bit for bit;
    on an indefinite band it reports dpbtrf's failure column."""
    rng = np.random.default_rng(300 + b)
    dense = random_band(b, rng, 4.0 * (b + 1))
    kernels, token = band_kernels(b), band_token_of(b)
    perm = rng.permutation(N).astype(np.int64)
    rhs = rng.normal(size=N)
    band = upper_band(dense, b)
    factor, info, x = kernels.band_factor_solve(band, rhs, perm, token)
    reference, ref_info = kernels.band_cholesky(band, token)
    expected = np.empty(N)
    kernels.band_cholesky_solve(reference, rhs, perm, token, expected)
    assert info == ref_info == 0
    np.testing.assert_array_equal(factor, reference)
    np.testing.assert_array_equal(x, expected)
    dense[N // 2, N // 2] = -1.0
    band = upper_band(dense, b)
    assert (
        kernels.band_factor_solve(band, rhs, perm, token)[1] == lapack.dpbtrf(band, lower=0)[1] > 0
    )


@pytest.mark.parametrize("b", WIDTHS)
def test_an_indefinite_band_fails_at_lapacks_column_and_is_solved_by_lu(b):
    rng = np.random.default_rng(100 + b)
    dense = random_band(b, rng, 4.0 * (b + 1))
    dense[N // 2, N // 2] = -1.0  # one negative pivot half way
    band = upper_band(dense, b)
    kernels = band_kernels(b)
    _, info = kernels.band_cholesky(band, kernels.band_token(b))
    assert info == lapack.dpbtrf(band, lower=0)[1] > 0
    perm = np.arange(N, dtype=np.int64)
    rhs = rng.normal(size=N)
    tangent = BandedTangent(band, perm, b)
    np.testing.assert_allclose(tangent.solve(rhs), np.linalg.solve(dense, rhs), rtol=1e-10)
    assert tangent.negative_eigenvalues() == np.sum(np.linalg.eigvalsh(dense) < 0.0)


@pytest.mark.parametrize("b", WIDTHS)
def test_the_banded_lu_agrees_with_lapacks_dgbtrf(b):
    """dgbtf2's algorithm (partial pivoting, right-looking): same pivots, factors to round-off."""
    rng = np.random.default_rng(200 + b)
    dense = random_band(b, rng, 0.0)  # indefinite: row interchanges happen
    band = upper_band(dense, b)
    kernels = band_kernels(b)
    lu, pivots, info = kernels.band_lu(band, kernels.band_token(b))
    general = np.zeros((3 * b + 1, N), order="F")  # LAPACK general band: A[i, j] at 2b + i - j
    for i in range(N):
        for j in range(max(0, i - b), min(N, i + b + 1)):
            general[2 * b + i - j, j] = dense[i, j]
    reference, ref_pivots, ref_info = lapack.dgbtrf(general, b, b)
    assert info == ref_info == 0
    np.testing.assert_array_equal(pivots, ref_pivots)
    for j in range(N):
        np.testing.assert_allclose(lu[j], reference[:, j], rtol=1e-12, atol=1e-12)
