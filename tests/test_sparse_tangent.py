"""The sparse tangent's LDL^T: one factorisation for the solve and the inertia.

Every check is against an independent dense computation: ``numpy.linalg.solve``
for the solution and ``numpy.linalg.eigvalsh``'s count of negative eigenvalues
for the inertia, on random positive definite, indefinite and saddle-point
matrices and on a real continuum tangent past its buckling load. The
pattern's first tangent is factorised by SuperLU in symmetric mode, its later
tangents by QDLDL reusing one symbolic analysis; both are checked.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
import scipy.sparse as sp
from test_continuum import E_MOD, cantilever

from flexval.geometry import Force, LoadCase, Segment
from flexval.reducedmodels.core.tangent import (
    SparseAnalysis,
    SparseTangent,
    TangentLayout,
)
from flexval.validation.continuum.run import build_system

EPS = np.finfo(float).eps


def grid_laplacian(m: int) -> sp.csc_matrix:
    """The 5-point Laplacian of an m x m grid (eigenvalues known: 4 - 2 cos - 2 cos)."""
    one = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(m, m))
    return sp.csc_matrix(sp.kron(one, sp.eye(m)) + sp.kron(sp.eye(m), one))


def random_symmetric(n: int, rng: np.random.Generator, negative: int) -> sp.csc_matrix:
    """A sparse symmetric matrix with ``negative`` negative eigenvalues, gapped from zero.

    A grid Laplacian with random symmetric perturbations of its pattern, shifted
    to lie halfway between two eigenvalues so that the count is unambiguous.
    """
    m = int(round(math.sqrt(n)))
    lap = grid_laplacian(m)
    noise = sp.random(m * m, m * m, density=0.02, random_state=rng) * 0.5
    matrix = (lap + noise + noise.T).tocsc()
    ev = np.linalg.eigvalsh(matrix.toarray())
    shift = 0.5 * (ev[negative - 1] + ev[negative]) if negative else ev[0] - 1.0
    return sp.csc_matrix(matrix - shift * sp.eye(m * m))


def tangents(matrix: sp.csc_matrix, n_multipliers: int = 0):
    """Two tangents of one pattern: the first (SuperLU, chooses) and a later one (the choice)."""
    analysis = SparseAnalysis()
    first = SparseTangent(matrix, n_multipliers, analysis)
    first.solve(np.ones(matrix.shape[0]))
    second = SparseTangent(matrix.copy(), n_multipliers, analysis)
    return first, second


def assert_solves(tangent: SparseTangent, rhs: np.ndarray) -> None:
    """The solve agrees with numpy's dense LU to round-off: the forward error within
    100 eps cond(K) and the backward error within 100 eps (measured on every matrix
    here: at most 3.1 eps cond(K) and 23 eps)."""
    dense = tangent.toarray()
    reference = np.linalg.solve(dense, rhs)
    x = tangent.solve(rhs)
    cond = np.linalg.cond(dense)
    scale = np.abs(reference).max()
    assert np.abs(x - reference).max() <= 100 * EPS * cond * scale
    backward = np.abs(dense @ x - rhs).max() / (
        np.abs(dense).sum(axis=1).max() * np.abs(x).max() + np.abs(rhs).max()
    )
    assert backward <= 100 * EPS


@pytest.mark.parametrize("negative", [0, 1, 3, 7])
@pytest.mark.parametrize("seed", range(2))
def test_ldl_solves_and_counts_the_inertia_of_symmetric_matrices(negative, seed):
    rng = np.random.default_rng(seed)
    matrix = random_symmetric(196, rng, negative)
    first, second = tangents(matrix)
    assert first._method == "superlu" and second._analysis.method == "ldl"
    rhs = rng.normal(size=matrix.shape[0])
    for tangent in (first, second):
        assert_solves(tangent, rhs)
        assert tangent.negative_eigenvalues() == negative
    assert second._method == "ldl"
    several = rng.normal(size=(matrix.shape[0], 3))
    assert np.allclose(second.solve(several)[:, 1], second.solve(several[:, 1]), rtol=1e-14)


def test_the_symbolic_analysis_is_made_once_per_pattern():
    """Later tangents refactorise numerically into the pattern's one QDLDL solver, and a
    tangent whose factor a later one overwrote refactorises before it solves again."""
    rng = np.random.default_rng(5)
    matrix = random_symmetric(225, rng, 2)
    analysis = SparseAnalysis()
    SparseTangent(matrix, 0, analysis).negative_eigenvalues()  # the first: SuperLU, chooses
    a = SparseTangent(matrix, 0, analysis)
    shifted = matrix.copy()
    shifted.data = shifted.data * 3.0  # same pattern, other values (same inertia)
    b = SparseTangent(shifted, 0, analysis)
    rhs = rng.normal(size=matrix.shape[0])
    x_a = a.solve(rhs)
    solver = analysis.solver
    x_b = b.solve(rhs)  # overwrites the solver's factor with b's
    assert analysis.solver is solver
    assert np.allclose(x_b, x_a / 3.0, rtol=1e-10, atol=0.0)
    assert np.array_equal(a.solve(rhs), x_a)  # a's own factor again
    assert a.negative_eigenvalues() == b.negative_eigenvalues() == 2


def test_the_layout_shares_one_analysis_between_its_tangents():
    lap = grid_laplacian(20).tocoo()  # 400 unknowns, half-bandwidth 20 after RCM: banded
    rows, cols = np.concatenate([lap.row, lap.col]), np.concatenate([lap.col, lap.row])
    values = np.concatenate([lap.data, lap.data]) / 2
    # a random permutation of the unknowns' numbers keeps the Laplacian's bandwidth 20 after
    # reverse Cuthill-McKee: make it wide with one row coupled to every other unknown
    extra = np.arange(400)
    rows = np.concatenate([rows, np.zeros(400, int), extra])
    cols = np.concatenate([cols, extra, np.zeros(400, int)])
    values = np.concatenate([values, np.full(800, 1e-3)])
    layout = TangentLayout(400, rows, cols)
    assert layout.kind == "sparse"
    storage = np.bincount(layout.slots, values, minlength=layout.size)
    first, second = layout.tangent(storage), layout.tangent(storage.copy())
    dense = first.toarray()
    assert second._analysis is first._analysis
    rhs = np.arange(400.0)
    for tangent in (first, second):
        assert np.allclose(tangent.solve(rhs), np.linalg.solve(dense, rhs), rtol=1e-12, atol=0)
        assert tangent.negative_eigenvalues() == np.sum(np.linalg.eigvalsh(dense) < 0) == 0
    assert (first._method, second._method) == ("superlu", "ldl")
    copied = pickle.loads(pickle.dumps(layout))  # a copy analyses afresh: its own solver
    third = copied.tangent(storage)
    assert np.allclose(third.solve(rhs), np.linalg.solve(dense, rhs), rtol=1e-12, atol=0)
    assert third._method == "ldl" and copied._analysis.solver is not first._analysis.solver


def saddle_point(rng: np.random.Generator, n: int, m: int, negative: int) -> np.ndarray:
    """[[H, B^T], [B, 0]] with H sparse symmetric (``negative`` negative eigenvalues) and
    each multiplier constraining two unknowns, so it has the fewest neighbours and a
    minimum-degree ordering eliminates it first: a zero pivot without pivoting."""
    H = random_symmetric(n, rng, negative).toarray()
    B = np.zeros((m, n))
    for k in range(m):
        B[k, rng.choice(n, 2, replace=False)] = rng.uniform(1.0, 2.0, 2)
    return np.block([[H, B.T], [B, np.zeros((m, m))]])


@pytest.mark.parametrize("seed", range(3))
def test_a_saddle_point_falls_back_to_the_pivoting_lu(seed):
    """The symmetric factorisation meets the multipliers' zero pivots: the tangent solves
    by SuperLU's pivoting LU, its inertia is not judged (None, as for any saddle point on
    that path) and the pattern's later tangents go straight to the LU."""
    rng = np.random.default_rng(seed)
    K = saddle_point(rng, 144, 3, seed)
    ev = np.linalg.eigvalsh(K)
    assert np.abs(ev).min() > 1e-6
    first, second = tangents(sp.csc_matrix(K), n_multipliers=3)
    assert first._analysis.method == "lu"
    rhs = rng.normal(size=K.shape[0])
    for tangent in (first, second):
        assert_solves(tangent, rhs)
        assert tangent._method == "lu"
        assert tangent.negative_eigenvalues() is None
    # the same matrix without multipliers declared: the fallback's separate symmetric-mode
    # SuperLU meets the zero pivot too, so the inertia is not judged either
    assert SparseTangent(sp.csc_matrix(K), 0).negative_eigenvalues() is None


def test_an_inaccurate_solve_is_refined_or_redone_by_the_pivoting_lu(monkeypatch):
    """Blocks [[d, 1], [1, d]] (d = 1e-15): any diagonal pivot is d, the factors grow like
    1/d and SuperLU's symmetric solve is 11 % off (measured); refinement with the same
    factor recovers round-off. Without refinement the backward error check sends the
    tangent to the pivoting LU, which solves to round-off. Either way the inertia is
    Sylvester's: each block has the eigenvalues d - 1 < 0 < d + 1."""
    from flexval.reducedmodels.core import tangent as module

    d = 1e-15
    K = sp.csc_matrix(sp.block_diag([np.array([[d, 1.0], [1.0, d]])] * 50))
    rhs = np.random.default_rng(1).normal(size=100)
    reference = np.linalg.solve(K.toarray(), rhs)
    refined = SparseTangent(K, 0)
    assert np.allclose(refined.solve(rhs), reference, rtol=1e-13, atol=0)
    assert refined._method == "superlu"
    assert np.abs(refined._symmetric.solve(rhs) - reference).max() > 1e-2  # unrefined
    monkeypatch.setattr(module, "REFINEMENTS", 0)
    for tangent in tangents(K):
        assert np.allclose(tangent.solve(rhs), reference, rtol=1e-14, atol=0)
        assert tangent._method == "lu"
        assert tangent.negative_eigenvalues() == 50
    assert refined.negative_eigenvalues() == 50


def test_non_finite_entries_are_not_judged():
    matrix = grid_laplacian(12)
    matrix.data[3] = np.nan
    assert SparseTangent(matrix, 0).negative_eigenvalues() is None


def test_a_continuum_tangent_past_buckling_has_numpys_inertia():
    """A straight clamped strip (L/h = 50, level 0: 597 unknowns) under an axial thrust of
    10 times its Euler load pi^2 EI / (4 L^2): Newton stays on the straight, unstable
    branch, past the bifurcations of the first two sway modes (at 1 and 9 times the
    load), so its tangent has two negative eigenvalues (numpy's count on the dense copy).
    The real tangent, factorised as a sparse one, gives that count and numpy's solve."""
    length, h = 50.0, 1.0
    mech = cantilever(Segment((0.0, 0.0), (length, 0.0)), h)
    EI = E_MOD * h**3 / 12
    thrust = 10 * math.pi**2 * EI / (4 * length**2)
    system = build_system(mech, 0)
    loads = system.loads(LoadCase("p", (Force("2", np.array([length, 0.0]), math.pi, thrust),)))
    q = system.initial_state()
    for _ in range(6):
        _, g, tangent = system.assemble(q, loads, 1.0)
        q = q - tangent.solve(g)
    _, g, tangent = system.assemble(q, loads, 1.0)
    assert np.abs(g).max() < 1e-8  # an equilibrium (residual 6e-11 N measured)
    dense = tangent.toarray()
    ev = np.linalg.eigvalsh(dense)
    assert np.sum(ev < 0) == 2
    first, second = tangents(sp.csc_matrix(dense))
    rhs = np.random.default_rng(0).normal(size=dense.shape[0])
    for sparse in (first, second):
        assert sparse.negative_eigenvalues() == 2
        assert_solves(sparse, rhs)
    assert second._method == "ldl"
    assert abs(ev[0]) > 1e-12 * np.abs(ev).max()  # far above round-off (u |K| ~ 1e-16 |K|)


def test_a_continuum_path_is_superlus_to_round_off():
    """A clamped strip (L/h = 20, mesh level 3: 10,849 unknowns, sparse storage) bent by a
    tip force to a 0.38 rad tip rotation: the path by the LDL^T and the path by the
    pivoting SuperLU with its separate inertia (the pattern's method set to "lu") agree to
    round-off at every level (measured: 5e-15 relative), with the same Newton counts."""
    from flexval.geometry import FlexureSpec, Material, Section
    from flexval.geometry.mechanism import assemble
    from flexval.reducedmodels import solve_path

    length = 20.0
    shape = Segment((0.0, 0.0), (length, 0.0))
    spec = FlexureSpec("e", shape, ("1", "2"), Section(1.0, 1.0))
    mech = assemble(
        [spec], "1", shape.end_points[0:1], Material(E_MOD, 0.3), "2", shape.end_points[1]
    )
    force = 0.8 * E_MOD / 12 / length**2  # F L^2 / (EI) = 0.8
    case = LoadCase("f", (Force("2", np.array([length, 0.0]), math.pi / 2, force),))
    paths = {}
    for method in ("ldl", "lu"):
        system = build_system(mech, 3)
        assert system.layout.kind == "sparse"
        if method == "lu":
            system.layout._analysis.method = "lu"
        paths[method] = solve_path(system, case, levels=4)
        assert system.layout._analysis.method == method
    ldl, lu = paths["ldl"], paths["lu"]
    assert ldl.stats["newton_iterations"] == lu.stats["newton_iterations"]
    for name in ("dx", "dy", "rotation"):
        a, b = np.asarray(getattr(ldl, name)), np.asarray(getattr(lu, name))
        assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max(), (name, a, b)
    assert abs(lu.rotation[-1]) > 0.3
