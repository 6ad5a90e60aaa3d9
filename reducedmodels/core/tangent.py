"""Storage, solution and inertia of the assembled tangent stiffness.

A System's tangent has the same sparsity pattern at every Newton iteration,
so where each connector's Hessian entry lands is worked out once
(:class:`TangentLayout`); each assembly adds the entry values into the
chosen storage at those slots (one ``bincount``, or a compiled kernel that
adds them as it computes them):

* ``dense``  -- small systems (at most ``DENSE_LIMIT`` unknowns; see ``NARROW_MIN``), LAPACK;
* ``banded`` -- chains of beams and bodies: after a reverse Cuthill-McKee
  ordering (scipy's, or for a compiled system the same one computed by
  :mod:`flexval.reducedmodels.kernels.orderkernel`) their bandwidth is small
  whatever the number of elements, so a banded LU (LAPACK ``dgbtrf``) costs
  O(n b^2), and so does the inertia (a banded Cholesky, or banded bisection
  when that fails, saddle points included);
* ``sparse`` -- wide bands (2D continuum meshes from level 3, 3D meshes): a
  sparse LDL^T under a fill-reducing ordering, analysed once per pattern
  (QDLDL's, or SuperLU's in symmetric mode where the factor fills in too
  much for QDLDL's column-by-column arithmetic), whose D gives the inertia.

Every :class:`Tangent` solves K x = b and counts its negative eigenvalues
(Sylvester's inertia, the stability check of the load stepping) by the one
rule of :mod:`flexval.reducedmodels.core.stability`: each pivot of an LDL^T judged
against its own round-off.

Units: the tangent is in N/mm, N and N mm like the coordinates it pairs.
"""

from __future__ import annotations

import functools
from types import ModuleType
from typing import Protocol

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack

from . import stability
from .threads import limit_threads

DENSE_LIMIT = 96  # above ~100 unknowns, multithreaded dense LAPACK stalls on shared cores
BAND_LIMIT = 64  # band storage beats the sparse LDL^T up to at least this half-bandwidth:
# per Newton iteration (assembly, factorisation, solve, inertia) of a plane-strain strip,
# L/h = 78, banded is faster at b = 61 (level 2, 11,200 unknowns) and slower at b = 125
# (level 3, 42,400), measured by benchmarks/bench_sparse.py; the continuum's level 2 is
# b = 61 on both scenes
NARROW_BAND = 8  # compiled banded Cholesky up to this half-bandwidth, LAPACK's above: at b = 5
# (beam chains) the loop takes half of dpbtrf's time, at b = 29 three times it
NARROW_MIN = 48  # a system that already runs compiled kernels takes a narrow band instead of
# dense storage from this many unknowns, where its factor and solve at b = 5 (beam chains)
# take a fraction of dense LAPACK's time
LDL_FILL_LIMIT = 200  # QDLDL's column-by-column LDL^T up to this many factor entries per
# column, SuperLU's supernodes (dense blocks, BLAS 3) above. QDLDL's time over symmetric-mode
# SuperLU's, scikit-fem elasticity matrices: 2D quad9, 28-44 per column at 6,000-23,000
# unknowns, 0.36-0.61 (0.58 and 0.72 at 45,000 and 177,000); 3D hex27 at 98 per column 0.71,
# 173: 0.94, 277: 0.95, 550 (13,900 unknowns): 4
BACKWARD_ERROR = 1e-14  # a sparse LDL^T's solve is refined while |K x - b| > BACKWARD_ERROR
# (|K| |x| + |b|) (infinity norms; 45 eps): measured 4e-17 to 5e-16 on the strips and the
# hex27 matrix of benchmarks/bench_sparse.py, up to 23 eps on random indefinite matrices
REFINEMENTS = 2  # refinement steps before a pivoting LU redoes the solve


@functools.cache
def narrow_kernels(b: int) -> tuple[ModuleType, tuple[int, ...]]:
    """:func:`band_kernels` (b) and the token that selects its kernels of half-bandwidth b.

    One cached call per tangent (:class:`BandedTangent` asks at every Newton iteration).
    """
    kernels = band_kernels(b)
    return kernels, kernels.band_token(b)


@functools.cache
def band_kernels(b: int) -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.bandkernel`, whose kernels of half-bandwidth b
    are compiled, or loaded from the on-disk cache, where they are first called, off the
    path's clock (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import bandkernel

    return bandkernel


@functools.cache
def ldl_kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.ldlkernel`: the compiled Bunch-Kaufman LDL^T that
    counts a dense tangent's inertia (and a batch's blocks'), each kernel compiled or loaded
    where it is first called, off the path's clock (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import ldlkernel

    return ldlkernel


@functools.cache
def order_kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.orderkernel` (a compiled system's ordering), each
    kernel compiled or loaded where it is first called, off the path's clock
    (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import orderkernel

    return orderkernel


class Tangent(Protocol):
    """An assembled symmetric tangent of n unknowns."""

    n: int

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """K x = rhs for one (n,) or several (n, k) right-hand sides.

        Raises ``np.linalg.LinAlgError`` or ``RuntimeError`` when K is singular.
        """
        ...

    def negative_eigenvalues(self) -> int | None:
        """Number of negative eigenvalues (None: could not be judged).

        Counted by the one rule of :mod:`flexval.reducedmodels.core.stability`:
        a pivot of the factorisation counts when it is negative beyond its
        own round-off, whatever the units or the resolution.
        """
        ...

    def positive_definite(self) -> bool:
        """True when the factorisation the solves use proves K positive definite (a Cholesky
        that succeeds, or an LDL^T whose pivots are all positive)."""
        ...

    def toarray(self) -> np.ndarray:
        """The matrix as a dense (n, n) array (for tests and small-system inspection)."""
        ...

    def tosparse(self) -> sp.csc_matrix:
        """The matrix as a sparse (n, n) CSC matrix (for eigensolvers of large systems)."""
        ...


class DenseTangent:
    """A tangent held as a dense array.

    As for band storage, one factorisation serves the solves and the
    inertia: LAPACK's Cholesky (``dpotrf``, called directly: numpy's
    ``solve`` spends 20 times longer in its checks than in the arithmetic of
    a 9 x 9 system) and, when K is not positive definite, a symmetric
    indefinite LDL^T (Bunch-Kaufman, ``dsytrf``), whose block-diagonal D has
    K's inertia (Sylvester). A saddle-point tangent (Lagrange multipliers:
    ``indefinite``) goes straight to the LDL^T.
    """

    def __init__(self, matrix: np.ndarray, indefinite: bool = False):
        self.matrix, self.n = matrix, matrix.shape[0]
        self._cholesky = None  # upper Cholesky factor, when K is positive definite
        self._ldl = None  # (ldu, ipiv, info) of dsytrf, when it is not
        self._positive = False if indefinite else None  # dpotrf succeeded (None: not tried)
        self._negative: int | None = None  # the inertia's count, once made

    def _factorise(self) -> None:
        if self._positive is None:
            factor, info = lapack.dpotrf(self.matrix)
            self._positive = info == 0
            self._cholesky = factor if self._positive else None
        if not self._positive and self._ldl is None:
            self._ldl = lapack.dsytrf(self.matrix)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        self._factorise()
        if self._positive:
            return lapack.dpotrs(self._cholesky, rhs)[0]
        ldu, ipiv, info = self._ldl
        if info > 0:
            raise np.linalg.LinAlgError(f"singular tangent (zero pivot {info})")
        return lapack.dsytrs(ldu, ipiv, rhs)[0]

    def negative_eigenvalues(self) -> int | None:
        """Zero when the Cholesky succeeded, else the negative eigenvalues of an LDL^T's D.

        The LDL^T is the compiled Bunch-Kaufman of
        :func:`flexval.reducedmodels.kernels.ldlkernel.ldl_factor` (LAPACK's
        ``dsytf2``), whose every pivot comes with its round-off scale, its
        count made by :func:`~flexval.reducedmodels.kernels.ldlkernel.ldl_negative`:
        the same kernel a batch of copies counts each block with.
        """
        if not np.isfinite(self.matrix).all():
            return None
        self._factorise()
        if self._positive:
            return 0
        if self._negative is None:
            kernels = ldl_kernels()
            work = np.ascontiguousarray(self.matrix.T)  # as a batch's block: upper read,
            factor = work.T  # U's columns contiguous
            pivots, eigenvalues = np.empty(self.n, np.int64), np.empty(self.n)
            scales = np.empty(self.n)
            kernels.ldl_factor(factor, pivots, eigenvalues, scales)
            self._negative = int(kernels.ldl_negative(factor, pivots, scales))
        return self._negative

    def positive_definite(self) -> bool:
        """True when LAPACK's Cholesky succeeds (the factorisation the solves use)."""
        self._factorise()
        return bool(self._positive)

    def toarray(self) -> np.ndarray:
        return self.matrix

    def tosparse(self) -> sp.csc_matrix:
        return sp.csc_matrix(self.matrix)


class BandedTangent:
    """A symmetric tangent held in LAPACK's upper band form under a bandwidth-reducing permutation.

    ``storage`` is Fortran-ordered (b + 1, n) with
    ``storage[b + i - j, j] = K[perm[i], perm[j]]`` for 0 <= j - i <= b (the
    diagonal is the last row): the form ``dpbtrf`` and ``eigvals_banded``
    read, and half the entries of a general band, so an assembly writes
    half as much. LAPACK is called directly: the wrappers' copies and checks
    cost more than the factorisation of a narrow band.

    One factorisation serves both the solves and the inertia: a banded
    Cholesky first (the usual, stable case: about a third of a banded LU's
    work, and it proves there is no negative eigenvalue), a banded LU with
    pivoting (on the general band storage, mirrored from the upper band)
    only when the Cholesky meets a non-positive pivot, and straight away for
    a saddle point (Lagrange multipliers: ``indefinite``), which has no
    Cholesky factor. Up to ``NARROW_BAND`` both are the compiled loops of
    :mod:`flexval.reducedmodels.kernels.bandkernel` (numba), above it LAPACK's.
    """

    def __init__(
        self, storage: np.ndarray, perm: np.ndarray, half_bandwidth: int, indefinite: bool = False
    ):
        self.storage, self.perm, self.b = storage, perm, half_bandwidth
        self.n = storage.shape[1]
        self._cholesky = None  # upper Cholesky factor in band form, when K is positive definite
        self._lu = None  # (lu, pivots, info) of a banded LU, when it is not
        self._indefinite = indefinite  # a saddle point: no Cholesky to try
        # the compiled kernels and their token for a narrow band (None: LAPACK's)
        self._narrow = narrow_kernels(half_bandwidth) if half_bandwidth <= NARROW_BAND else None

    def _factorise(self) -> None:
        if self._cholesky is None and self._lu is None:
            b = self.b
            if self._narrow is not None:
                kernels, token = self._narrow
                factor, info = (
                    (None, 1) if self._indefinite else kernels.band_cholesky(self.storage, token)
                )
                if info:
                    self._lu = kernels.band_lu(self.storage, token)
            else:
                factor, info = (
                    (None, 1) if self._indefinite else lapack.dpbtrf(self.storage, lower=0)
                )
                if info:
                    self._lu = lapack.dgbtrf(self._general_band(), b, b)
            if info == 0:
                self._cholesky = factor

    def _general_band(self) -> np.ndarray:
        """K in LAPACK general band storage (3b + 1, n), with the b rows dgbtrf works in."""
        b, n = self.b, self.n
        general = np.zeros((3 * b + 1, n), order="F")
        general[b : 2 * b + 1] = self.storage
        for k in range(1, b + 1):  # K[j + k, j] = K[j, j + k]
            general[2 * b + k, : n - k] = self.storage[b - k, k:]
        return general

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        narrow = self._narrow
        if (
            narrow is not None
            and not self._indefinite
            and self._cholesky is None
            and self._lu is None
            and rhs.ndim == 1
            and rhs.flags.c_contiguous
            and rhs.dtype == np.float64
        ):
            kernels, token = narrow  # the first solve: factorise and solve at once
            factor, info, x = kernels.band_factor_solve(self.storage, rhs, self.perm, token)
            if info == 0:
                self._cholesky = factor
                return x
            self._lu = kernels.band_lu(self.storage, token)
        self._factorise()
        if self._lu is not None and self._lu[2] > 0:
            raise np.linalg.LinAlgError(f"singular tangent (zero pivot {self._lu[2]})")
        if self._narrow is not None:
            return self._narrow_solve(rhs)
        if self._cholesky is not None:
            x_perm, _ = lapack.dpbtrs(self._cholesky, rhs[self.perm], lower=0)
        else:
            lu, piv, _ = self._lu
            x_perm, _ = lapack.dgbtrs(lu, self.b, self.b, rhs[self.perm], piv)
        x = np.empty_like(x_perm)
        x[self.perm] = x_perm
        return x

    def _narrow_solve(self, rhs: np.ndarray) -> np.ndarray:
        """:meth:`solve` with the compiled kernels' factors (one call per right-hand side)."""
        kernels, token = self._narrow
        if self._cholesky is not None:
            solve = functools.partial(kernels.band_cholesky_solve, self._cholesky)
        else:
            lu, pivots, _ = self._lu
            solve = functools.partial(kernels.band_lu_solve, lu, pivots)
        rhs = np.asfortranarray(rhs, float)
        x = np.empty_like(rhs, order="F")
        if rhs.ndim == 1:
            solve(rhs, self.perm, token, x)
            return x
        for k in range(rhs.shape[1]):  # each column contiguous
            solve(rhs[:, k], self.perm, token, x[:, k])
        return x

    def positive_definite(self) -> bool:
        """True when the banded Cholesky succeeds (the factorisation the solves use)."""
        self._factorise()
        return self._cholesky is not None

    def negative_eigenvalues(self) -> int | None:
        """Zero when the banded Cholesky of the solves succeeded (O(n b^2), no extra work).

        Otherwise a banded LDL^T without interchanges counts them
        (:func:`flexval.reducedmodels.kernels.stabilitykernel.band_negative`, O(n b^2)),
        each Lagrange multiplier's row paired with an unknown it constrains
        (:func:`~flexval.reducedmodels.core.stability.paired_band`); None when a
        pivot cannot be judged.
        """
        upper = self.storage
        if not np.isfinite(upper).all():
            return None
        self._factorise()
        if self._cholesky is not None:
            return 0
        return stability.band_count(np.asarray(upper))

    def tosparse(self) -> sp.csc_matrix:
        rows, cols, values = [], [], []
        for k in range(self.b + 1):  # k = j - i: the k-th super-diagonal and its mirror
            j = np.arange(k, self.n)
            value = self.storage[self.b - k, j]
            rows += [self.perm[j - k]] + ([self.perm[j]] if k else [])
            cols += [self.perm[j]] + ([self.perm[j - k]] if k else [])
            values += [value] + ([value] if k else [])
        return sp.csc_matrix(
            (np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.n, self.n),
        )

    def toarray(self) -> np.ndarray:
        dense = np.zeros((self.n, self.n))
        for k in range(self.b + 1):  # k = j - i
            j = np.arange(k, self.n)
            dense[self.perm[j - k], self.perm[j]] = self.storage[self.b - k, j]
            dense[self.perm[j], self.perm[j - k]] = self.storage[self.b - k, j]
        return dense


class SparseAnalysis:
    """What one sparsity pattern's tangents share: the factorisation chosen and its analysis.

    A System's pattern is fixed, so its layout keeps one of these for every
    tangent it wraps. ``method`` is chosen by the first tangent's
    factorisation (a symmetric-mode SuperLU, see :class:`SparseTangent`):
    ``"ldl"`` (QDLDL's LDL^T: its AMD ordering and elimination tree are
    computed once, by the first ``qdldl.Solver``, and each later tangent
    refactorises numerically into the same solver) when that factor's fill
    is at most ``LDL_FILL_LIMIT`` entries per column, ``"superlu"`` (one
    symmetric-mode SuperLU per tangent) above it, ``"lu"`` (a pivoting
    SuperLU per tangent, no inertia for saddle points) once a zero pivot
    stopped an LDL^T of this pattern (a multiplier ordered before the
    unknowns it constrains: the same at every iteration).
    """

    def __init__(self) -> None:
        self.method: str | None = None
        self.solver = None  # the qdldl.Solver, holding the factor of tangent ``owner``
        self.owner = 0  # the token of the SparseTangent whose factor the solver holds
        self.issued = 0  # tokens issued so far

    def token(self) -> int:
        """A new tangent's token (which factor the shared solver holds)."""
        self.issued += 1
        return self.issued

    def __getstate__(self) -> dict:
        """A copy (pickle, deepcopy) makes its own solver: the compiled one cannot be copied."""
        return {**self.__dict__, "solver": None, "owner": 0}


class SparseTangent:
    """A tangent held as a CSC matrix: one symmetric factorisation gives solves and inertia.

    The factorisation is an LDL^T without numerical pivoting under a
    fill-reducing symmetric ordering (QDLDL with AMD, or SuperLU in
    symmetric mode with diagonal pivots): by Sylvester's law the signs of
    D are K's inertia, so the stability check costs nothing beyond the
    solve. The factor is made on the first solve (or inertia) and kept: one
    tangent may be solved with more than once (the Newton correction, then
    the load stepping's linearised prediction K^-1 f), as the dense and
    banded tangents do with their factors. Tangents of one System share a
    :class:`SparseAnalysis` (the symbolic analysis of their common pattern).

    Without pivoting an LDL^T can meet a zero pivot (a saddle point whose
    multiplier is ordered before the unknowns it constrains) or lose
    accuracy on an indefinite K (growth of the factors); every solve's
    backward error is checked and, above ``BACKWARD_ERROR``, refined with
    the same factor (at most ``REFINEMENTS`` times). A zero pivot, or a
    solve still inaccurate, sends the tangent to a pivoting SuperLU LU for
    its solves, its inertia then counted by a separate symmetric-mode
    SuperLU (not judged, None, for saddle points); after a zero pivot the
    pattern's later tangents go straight to that path.
    """

    def __init__(
        self, matrix: sp.csc_matrix, n_multipliers: int, analysis: SparseAnalysis | None = None
    ):
        self.matrix, self.n, self.n_multipliers = matrix, matrix.shape[0], n_multipliers
        self._analysis = analysis if analysis is not None else SparseAnalysis()
        self._token = self._analysis.token()
        self._method = None  # "ldl", "superlu" or "lu": how this tangent is factorised
        self._symmetric = None  # a symmetric-mode SuperLU with diagonal pivots
        self._lu = None  # a pivoting SuperLU (the fallback)
        self._pivots = None  # D of the LDL^T (None: no LDL^T of this tangent)
        self._norm = None  # |K|_inf, for the solves' backward error

    def _factorise(self) -> None:
        if self._method is not None:
            return
        if not np.isfinite(self.matrix.data).all():  # a refused iterate, not the pattern's fault
            self._fall_back(pattern=False)
            return
        analysis = self._analysis
        if analysis.method == "ldl" and self._ldl():
            self._method = "ldl"
            return
        if analysis.method in (None, "superlu"):
            symmetric = _symmetric_superlu(self.matrix)
            if symmetric is not None:
                self._symmetric, self._pivots = symmetric, symmetric.U.diagonal()
                self._method = "superlu"
                if analysis.method is None:  # the pattern's first tangent chooses
                    fill = symmetric.L.nnz / max(self.n, 1)
                    analysis.method = "ldl" if fill <= LDL_FILL_LIMIT else "superlu"
                return
        self._fall_back()

    def _fall_back(self, pattern: bool = True) -> None:
        """A pivoting LU for this tangent's solves (``pattern``: and the pattern's later ones)."""
        import scipy.sparse.linalg as spla

        if pattern:
            self._analysis.method = "lu"
        self._method = "lu"
        self._pivots, self._symmetric = None, None
        self._lu = spla.splu(self.matrix)

    def _ldl(self) -> bool:
        """Factorise into the pattern's QDLDL solver; False at a zero or non-finite pivot."""
        import qdldl  # only wide bands

        analysis = self._analysis
        if analysis.solver is None:
            analysis.solver = qdldl.Solver(self.matrix)  # AMD ordering and elimination tree
        else:
            analysis.solver.update(self.matrix)  # numeric only, the analysis reused
        analysis.owner = self._token
        pivots = analysis.solver.factors()[1]
        if not (np.isfinite(pivots).all() and pivots.all()):  # QDLDL divides by a zero pivot
            analysis.owner = 0
            return False
        self._pivots = pivots
        return True

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """K x = rhs by the LDL^T, refined until its backward error is ``BACKWARD_ERROR``."""
        self._factorise()
        if self._method == "lu":
            return self._lu.solve(rhs)
        x = self._factor_solve(rhs)
        for refinement in range(REFINEMENTS + 1):
            residual = rhs - self.matrix @ x
            if self._backward_error(x, rhs, residual) <= BACKWARD_ERROR:
                return x
            if refinement < REFINEMENTS:  # a step of iterative refinement with the same factor
                x = x + self._factor_solve(residual)
        self._fall_back(pattern=False)  # near-singular values, not the pattern: this tangent
        return self._lu.solve(rhs)

    def _factor_solve(self, rhs: np.ndarray) -> np.ndarray:
        """K x = rhs with this tangent's LDL^T (QDLDL's or the symmetric SuperLU's)."""
        if self._method == "superlu":
            return self._symmetric.solve(rhs)
        if self._analysis.owner != self._token:  # a later tangent refactorised the solver
            self._ldl()
        solver = self._analysis.solver
        if rhs.ndim == 1:
            return solver.solve(rhs)
        return np.column_stack([solver.solve(np.ascontiguousarray(column)) for column in rhs.T])

    def _backward_error(self, x: np.ndarray, rhs: np.ndarray, residual: np.ndarray) -> float:
        """|rhs - K x| / (|K| |x| + |rhs|) in infinity norms (over all columns)."""
        if self._norm is None:
            self._norm = _norm_inf(self.matrix)
        size = self._norm * np.abs(x).max(initial=0.0) + np.abs(rhs).max(initial=0.0)
        return float(np.abs(residual).max(initial=0.0) / size) if size > 0.0 else 0.0

    def negative_eigenvalues(self) -> int | None:
        """Pivots of the LDL^T negative beyond their own round-off (Sylvester's inertia).

        Each pivot's scale is the diagonal of |L| |D| |L^T| of the factor the
        solves use (QDLDL's or the symmetric SuperLU's), its tolerance
        gamma_(c+2) for the longest row c of L
        (:mod:`flexval.reducedmodels.core.stability`). Not judged (None) when K
        has non-finite entries, or when it fell back to the pivoting LU and
        is a saddle point or meets a zero pivot in a symmetric-mode SuperLU
        too.
        """
        if not np.isfinite(self.matrix.data).all():
            return None
        self._factorise()
        if self._pivots is None:  # the fallback: a separate symmetric-mode factorisation
            if self.n_multipliers:
                return None
            symmetric = _symmetric_superlu(self.matrix)
            if symmetric is None:
                return None
            return _superlu_negative(symmetric)
        if self._method == "superlu":
            return _superlu_negative(self._symmetric)
        if self._analysis.owner != self._token:  # a later tangent refactorised the solver
            self._ldl()
        lower, pivots = self._analysis.solver.factors()[:2]
        return _pivots_negative(sp.csr_matrix(lower), pivots)

    def positive_definite(self) -> bool:
        """True when the LDL^T's pivots are all positive (after the pivoting LU's fallback,
        those of the separate symmetric-mode factorisation its inertia is counted by; a
        tangent whose inertia cannot be judged counts as positive definite)."""
        self._factorise()
        if self._pivots is not None:
            return bool((self._pivots > 0.0).all())
        return not self.negative_eigenvalues()

    def toarray(self) -> np.ndarray:
        return self.matrix.toarray()

    def tosparse(self) -> sp.csc_matrix:
        return self.matrix


def _symmetric_superlu(matrix: sp.csc_matrix):
    """SuperLU in symmetric mode with diagonal pivots (an LDL^T whose D is U's diagonal).

    None when it meets a zero pivot, takes an off-diagonal one (then U's
    diagonal is no longer D) or gives a non-finite pivot.
    """
    import scipy.sparse.linalg as spla  # SuperLU: only wide bands (a start-up cost)

    try:
        lu = spla.splu(
            matrix,
            permc_spec="MMD_AT_PLUS_A",
            diag_pivot_thresh=0.0,
            options={"SymmetricMode": True},
        )
    except RuntimeError:
        return None
    pivots = lu.U.diagonal()
    if not np.array_equal(lu.perm_r, lu.perm_c) or not np.isfinite(pivots).all():
        return None
    return lu


def _pivots_negative(lower: sp.csr_matrix, pivots: np.ndarray) -> int:
    """D's pivots negative beyond round-off, for K = L D L^T (L unit lower, strictly below
    its diagonal in ``lower``); scales |D_k| + sum_j L_kj^2 |D_j| (stability's rule)."""
    magnitudes = np.abs(pivots)
    squares = lower.multiply(lower).tocsr()
    scales = magnitudes + squares @ magnitudes
    longest = int(np.diff(squares.indptr).max(initial=0))
    return stability.count_pivots(pivots, scales, stability.tolerance(longest + 2))


def _superlu_negative(lu) -> int:
    """:func:`_pivots_negative` of a symmetric-mode SuperLU (U = D L^T: L_kj U_jk = D_j L_kj^2)."""
    pivots = lu.U.diagonal()
    lower = sp.csr_matrix(lu.L)
    lower.setdiag(0.0)
    lower.eliminate_zeros()
    with np.errstate(divide="ignore", invalid="ignore"):
        return _pivots_negative(lower, pivots)


def _norm_inf(matrix: sp.csc_matrix) -> float:
    """The largest absolute row sum of a sparse matrix (its infinity norm)."""
    row_sums = np.bincount(matrix.indices, np.abs(matrix.data), minlength=matrix.shape[0])
    return float(row_sums.max(initial=0.0))


class TangentLayout:
    """Where each value slot of the assembled tangent goes, for a fixed sparsity pattern.

    Parameters
    ----------
    n : int
        Number of unknowns.
    rows, cols : array (k,)
        Global row and column of every value slot (duplicates are summed).
    n_multipliers : int
        Lagrange multipliers among the unknowns (they make K a saddle point).
    ordering : int array (n,), optional
        The unknowns' order for band storage (default: reverse Cuthill-McKee),
        which it then takes whatever the size (unless the band is wider than
        ``BAND_LIMIT``): a batch gives each copy's own order, so that each
        block is factorised by the same arithmetic in a batch of any size.
    compiled : bool
        The system already runs compiled kernels (numba is loaded), so a
        narrow band may take the compiled Cholesky below ``DENSE_LIMIT``,
        and the ordering is computed by :mod:`flexval.reducedmodels.kernels.orderkernel`
        (scipy's reverse Cuthill-McKee, the same permutation, without the
        sparse matrix scipy needs, whose construction costs more than the ordering).

    Attributes
    ----------
    slots : int array (k,)
        Where the value of each (row, col) entry is added in the storage
        (-1: nowhere; a symmetric band stores the upper triangle only).
    size : int
        Length of the flat storage array :meth:`tangent` wraps.

    The storage is dense up to ``DENSE_LIMIT`` unknowns (for a compiled
    system from ``NARROW_MIN`` on only if the band is wider than
    ``NARROW_BAND``), else banded if the reordered half-bandwidth is at most
    ``BAND_LIMIT``, else sparse.
    """

    def __init__(
        self,
        n: int,
        rows: np.ndarray,
        cols: np.ndarray,
        n_multipliers: int = 0,
        compiled: bool = False,
        ordering: np.ndarray | None = None,
    ):
        limit_threads()  # once per process: small banded systems want 1 BLAS thread
        self.n, self.n_multipliers = n, n_multipliers
        rows, cols = np.asarray(rows, np.int64), np.asarray(cols, np.int64)
        # a caller's ordering asks for band storage (a batch: each copy's block factorised
        # by the same arithmetic whatever the batch's size)
        small = n <= DENSE_LIMIT and ordering is None
        if small and not (compiled and n >= NARROW_MIN):
            self.kind, self.slots, self.size = "dense", rows * n + cols, n * n
            return
        if ordering is not None:  # the caller's: a batch's copies, each in its own order
            perm = np.asarray(ordering, np.int64)
            position = np.empty(n, np.int64)
            position[perm] = np.arange(n)
            j = position[cols]
            offset = j - position[rows]
            b = int(max(offset.max(initial=0), -offset.min(initial=0)))
            band_slots = None
        elif compiled:  # scipy's ordering, without building a sparse matrix
            kernels = order_kernels()
            perm = kernels.ordering(n, rows, cols)
            position, b, band_slots = kernels.band_slots(perm, rows, cols)
        else:
            from scipy.sparse.csgraph import reverse_cuthill_mckee  # not for dense: start-up

            graph = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
            perm = reverse_cuthill_mckee(graph, symmetric_mode=True).astype(np.int64)
            position = np.empty(n, np.int64)
            position[perm] = np.arange(n)
            j = position[cols]
            offset = j - position[rows]  # j - i >= 0: an upper-band entry
            b = int(max(offset.max(initial=0), -offset.min(initial=0)))
            band_slots = None
        if small and b > NARROW_BAND:
            self.kind, self.slots, self.size = "dense", rows * n + cols, n * n
            return
        if b <= BAND_LIMIT:  # the upper band only: the lower entries mirror it (slot -1)
            self.kind, self.perm, self.b, self._position = "banded", perm, b, position
            if b <= NARROW_BAND:
                band_kernels(b)
            self.slots = (
                np.where(offset >= 0, j * (b + 1) + (b - offset), -1)
                if band_slots is None
                else band_slots
            )
            self.size = (b + 1) * n
            return
        self.kind = "sparse"
        uniq, inverse = np.unique(cols * n + rows, return_inverse=True)
        self.slots, self.size = inverse.ravel().astype(np.int64), uniq.size
        self._keys = uniq
        self._analysis = SparseAnalysis()  # shared by the pattern's tangents
        self._indices = (uniq % n).astype(np.int32)
        self._indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)

    def slots_of(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray | None:
        """Where entries (rows, cols) of the matrix add in the storage, as :attr:`slots` says.

        For a further matrix on the same unknowns (a mass matrix) to be
        summed into the tangent's storage. A symmetric band stores the upper
        triangle, so lower entries get -1 (their mirror carries the value);
        None when some entry has no place (outside the band, or not in the
        sparse pattern).
        """
        rows, cols = np.asarray(rows, np.int64), np.asarray(cols, np.int64)
        if self.kind == "dense":
            return rows * self.n + cols
        if self.kind == "banded":
            i, j = self._position[rows], self._position[cols]
            if np.any(np.abs(i - j) > self.b):
                return None
            return np.where(i <= j, j * (self.b + 1) + (self.b + i - j), -1)
        keys = cols * self.n + rows
        slots = np.minimum(np.searchsorted(self._keys, keys), self._keys.size - 1)
        return slots if np.array_equal(self._keys[slots], keys) else None

    def product(self, storage: np.ndarray, x: np.ndarray) -> np.ndarray:
        """K x for the matrix held in ``storage`` (units of K times those of x)."""
        if self.kind == "dense":
            return storage.reshape(self.n, self.n) @ x
        if self.kind == "sparse":
            return sp.csc_matrix((storage, self._indices, self._indptr), shape=(self.n, self.n)) @ x
        b, perm = self.b, self.perm
        band = storage.reshape(self.n, b + 1)  # band[j, b + i - j] = K[perm i, perm j]
        xp = x[perm]
        yp = band[:, b] * xp
        for k in range(1, b + 1):  # the k-th super- and sub-diagonal
            upper = band[k:, b - k]  # K[perm (j - k), perm j], j >= k
            yp[:-k] += upper * xp[k:]
            yp[k:] += upper * xp[:-k]
        y = np.empty_like(yp)
        y[perm] = yp
        return y

    def tangent(self, storage: np.ndarray) -> Tangent:
        """The tangent held in ``storage`` (:attr:`size` values, summed at :attr:`slots`)."""
        if self.kind == "dense":
            return DenseTangent(storage.reshape(self.n, self.n), self.n_multipliers > 0)
        if self.kind == "banded":  # column j contiguous: Fortran order, as LAPACK wants it
            return BandedTangent(
                storage.reshape(self.n, self.b + 1).T, self.perm, self.b, self.n_multipliers > 0
            )
        matrix = sp.csc_matrix((storage, self._indices, self._indptr), shape=(self.n, self.n))
        return SparseTangent(matrix, self.n_multipliers, self._analysis)
