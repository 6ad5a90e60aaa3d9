"""Benchmark of the sparse tangent: one LDL^T for solve and inertia against two SuperLUs.

Per Newton iteration of a wide-band System the tangent is assembled, factorised,
solved with and its inertia counted (the load stepping's stability check). This
compares, on the same matrices and interleaved in one process (median of the
repeats):

* ``superlu x2`` -- a pivoting SuperLU for the solve and a second, symmetric-mode
  SuperLU for the inertia (what the sparse storage's fallback path does,
  written out here);
* ``ldl`` -- :class:`flexval.reducedmodels.core.tangent.SparseTangent`: one LDL^T
  (QDLDL with the pattern's analysis reused, or one symmetric-mode SuperLU
  where the factor fills in beyond ``LDL_FILL_LIMIT`` entries per column).

Matrices: the continuum tangent of a clamped plane-strain strip (h = 1 mm, mesh
level 3: 8 x 8 L/h 9-node quadrilaterals, about 543 unknowns per unit of L/h)
of about 10,900 and 42,400 unknowns, assembled by flexval at rest under a tip
force; and a 3D linear elasticity matrix of 27-node hexahedra (scikit-fem's
element, one element matrix repeated over a uniform n x n x 4n grid, one end
clamped).

Where FElupe is installed (the ``peers`` extra), its Newton iteration on the
same strip (the same grid of 9-node elements, plane strain, neo-Hookean; vector and matrix
assembly and its SuperLU solve, no inertia) is timed in the same repeats.

A second table times the banded storage against the sparse one on the same
strip (L/h = 78) at mesh levels 2 and 3 (half-bandwidths about 60 and 120 after
reverse Cuthill-McKee): per iteration, assembly into each storage, factorisation,
solve and inertia; it is the measurement behind ``BAND_LIMIT``.

Usage: ``python benchmarks/bench_sparse.py [--repeats 5] [--hex 6]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexval.geometry import Force, LoadCase, Material, Section, Segment
from flexval.geometry.mechanism import FlexureSpec, assemble
from flexval.reducedmodels.core import tangent as storage
from flexval.reducedmodels.core.tangent import SparseAnalysis, SparseTangent
from flexval.validation.continuum.run import build_system


def superlu_twice(matrix: sp.csc_matrix, rhs: np.ndarray) -> tuple[np.ndarray, int | None]:
    """The solve by a pivoting SuperLU and the inertia by a symmetric-mode SuperLU."""
    x = spla.splu(matrix).solve(rhs)
    lu = storage._symmetric_superlu(matrix)  # the inertia by the sparse path's own factorisation
    if lu is None:
        return x, None
    d = lu.U.diagonal()
    return x, int(np.sum(d < -1e-12 * np.abs(d).max(initial=0.0)))


def strip_system(slenderness: float, level: int = 3):
    """A clamped strip (h = 1 mm, L = slenderness mm) as a continuum System, and a tip load."""
    shape = Segment((0.0, 0.0), (slenderness, 0.0))
    spec = FlexureSpec("e", shape, ("1", "2"), Section(1.0, 1.0))
    mech = assemble(
        [spec], "1", shape.end_points[0:1], Material(2100.0, 0.35), "2", shape.end_points[1]
    )
    system = build_system(mech, level, plane="strain")
    tip = np.array([slenderness, 0.0])
    loads = system.loads(LoadCase("f", (Force("2", tip, np.pi / 2, 0.1),)))
    return system, loads


def hex27_matrix(n: int) -> sp.csc_matrix:
    """3D elasticity (E = 2100 MPa, nu = 0.35) on n x n x 4n 27-node hexahedra, x = 0 clamped."""
    import skfem
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    element = skfem.ElementVector(skfem.ElementHex2())
    h = 1.0 / n
    one = skfem.MeshHex.init_tensor(*([0.0, h],) * 3)
    form = linear_elasticity(*lame_parameters(2100.0, 0.35))
    local = form.assemble(skfem.Basis(one, element)).toarray()  # every element's matrix
    grid = np.linspace(0.0, 1.0, n + 1)
    mesh = skfem.MeshHex.init_tensor(np.linspace(0.0, 4.0, 4 * n + 1), grid, grid)
    basis = skfem.Basis(mesh, element, intorder=1)  # only its numbering is used
    dofs = basis.element_dofs  # (81, elements)
    rows = np.repeat(dofs, dofs.shape[0], axis=0).T.ravel()
    cols = np.tile(dofs, (dofs.shape[0], 1)).T.ravel()
    values = np.tile(local.ravel(), dofs.shape[1])
    matrix = sp.csc_matrix((values, (rows, cols)), shape=(basis.N, basis.N))
    free = basis.complement_dofs(basis.get_dofs(lambda x: x[0] < 1e-9).all())
    return sp.csc_matrix(matrix[free][:, free])


def felupe_iteration(slenderness: float, n_t: int = 8):
    """One FElupe Newton iteration's work on the strip's mesh (None: FElupe not installed)."""
    try:
        import felupe as fem
    except ImportError:
        return None
    n_l = int(round(n_t * slenderness))  # level 3's divisions: 8 through h, 8 per h along
    mesh = fem.Rectangle(a=(0.0, 0.0), b=(slenderness, 1.0), n=(n_l + 1, n_t + 1))
    region = fem.RegionBiQuadraticQuad(fem.mesh.convert(mesh, order=2, calc_midfaces=True))
    field = fem.FieldContainer([fem.FieldPlaneStrain(region, dim=2)])
    dof0, dof1 = fem.dof.partition(field, {"clamped": fem.Boundary(field[0], fx=0.0)})
    solid = fem.SolidBody(fem.NeoHooke(mu=2100.0 / 2.7, bulk=2100.0 / 0.9), field)

    def iteration() -> int:
        residual = solid.assemble.vector()
        matrix = solid.assemble.matrix()
        fem.solve.solve(*fem.solve.partition(field, matrix, dof1, dof0, residual))
        return dof1.size

    return iteration


def compare(label: str, produce, repeats: int, peer=None) -> dict:
    """Interleaved repeats of (assembly, LDL^T path, SuperLU x2 path, the peer's iteration)
    on the same tangents."""
    analysis = SparseAnalysis()
    matrix, rhs, assembly = produce()
    start = time.perf_counter()
    SparseTangent(matrix, 0, analysis).solve(rhs)  # the pattern's first: chooses the method
    first = time.perf_counter() - start
    times = {"assemble": [], "ldl": [], "superlu x2": [], "felupe": []}
    peer_unknowns = 0
    for _ in range(repeats):
        matrix, rhs, assembly = produce()
        times["assemble"].append(assembly)
        start = time.perf_counter()
        tangent = SparseTangent(matrix, 0, analysis)
        x_new = tangent.solve(rhs)
        negative_new = tangent.negative_eigenvalues()
        times["ldl"].append(time.perf_counter() - start)
        start = time.perf_counter()
        x_old, negative_old = superlu_twice(matrix, rhs)
        times["superlu x2"].append(time.perf_counter() - start)
        if peer is not None:
            start = time.perf_counter()
            peer_unknowns = peer()
            times["felupe"].append(time.perf_counter() - start)

    def backward(x: np.ndarray) -> float:  # |K x - b| / (|K| |x| + |b|), infinity norms
        norm = np.abs(matrix).sum(axis=1).max()
        return float(np.abs(matrix @ x - rhs).max() / (norm * np.abs(x).max() + np.abs(rhs).max()))

    row = {
        "case": label,
        "unknowns": matrix.shape[0],
        "method": tangent._method,
        "first_s": first,
        **{key: statistics.median(value) if value else None for key, value in times.items()},
        "felupe_unknowns": peer_unknowns,
        "negative": (negative_new, negative_old),
        "backward": (backward(x_new), backward(x_old)),
    }
    return row


def strip_case(slenderness: float):
    system, loads = strip_system(slenderness)
    q = system.initial_state()

    def produce():
        start = time.perf_counter()
        _, g, tangent = system.assemble(q, loads, 1.0)
        return tangent.matrix, -g, time.perf_counter() - start

    if system.layout.kind != "sparse":
        raise SystemExit(f"L/h = {slenderness}: {system.layout.kind} storage, not sparse")
    return produce


def band_against_sparse(level: int, slenderness: float, repeats: int) -> dict:
    """Per-iteration seconds of the banded and the sparse storage of one strip's tangent."""
    limit = storage.BAND_LIMIT
    systems = {}
    try:
        for kind, band_limit in (("banded", 10**6), ("sparse", -1)):
            storage.BAND_LIMIT = band_limit
            systems[kind] = strip_system(slenderness, level)
    finally:
        storage.BAND_LIMIT = limit
    times = {kind: [] for kind in systems}
    for repeat in range(repeats + 1):  # the first: the sparse pattern's choice, not timed
        for kind, (system, loads) in systems.items():
            start = time.perf_counter()
            _, g, tangent = system.assemble(system.initial_state(), loads, 1.0)
            tangent.solve(-g)
            tangent.negative_eigenvalues()
            if repeat:
                times[kind].append(time.perf_counter() - start)
    banded = systems["banded"][0].layout
    return {
        "level": level,
        "unknowns": banded.n,
        "b": banded.b,
        **{kind: statistics.median(value) for kind, value in times.items()},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="repeats (median reported)")
    parser.add_argument("--hex", type=int, default=6, help="3D grid: n x n x 4n hexahedra")
    args = parser.parse_args()
    rows = []
    for slenderness in (20.0, 78.0):
        rows.append(
            compare(
                f"strip L/h={slenderness:g}",
                strip_case(slenderness),
                args.repeats,
                felupe_iteration(slenderness),
            )
        )
    matrix = hex27_matrix(args.hex)
    rhs = np.ones(matrix.shape[0])
    rows.append(
        compare(
            f"hex27 {args.hex}x{args.hex}x{4 * args.hex}", lambda: (matrix, rhs, 0.0), args.repeats
        )
    )
    print(f"median of {args.repeats} repeats, seconds per Newton iteration")
    print(
        f"{'case':<18}{'unknowns':>9}{'method':>9}{'assemble':>9}{'ldl':>7}{'superlu x2':>11}"
        f"{'iter. new':>10}{'iter. old':>10}{'new/old':>8}{'felupe':>8}{'first':>7}"
        f"  negative  backward error new, old"
    )
    for r in rows:
        new, old = r["assemble"] + r["ldl"], r["assemble"] + r["superlu x2"]
        felupe = "-" if r["felupe"] is None else f"{r['felupe']:.3f}"
        print(
            f"{r['case']:<18}{r['unknowns']:>9}{r['method']:>9}{r['assemble']:>9.3f}"
            f"{r['ldl']:>7.3f}{r['superlu x2']:>11.3f}{new:>10.3f}{old:>10.3f}{new / old:>8.2f}"
            f"{felupe:>8}{r['first_s']:>7.3f}  {r['negative']!s:>8}  "
            f"{r['backward'][0]:.1e}, {r['backward'][1]:.1e}"
        )
    if any(r["felupe_unknowns"] for r in rows):
        print("FElupe's unknowns:", ", ".join(str(r["felupe_unknowns"]) for r in rows[:2]))
    print(f"load average {os.getloadavg()[0]:.1f} (1 min)")
    print("\nbanded against sparse storage, strip L/h = 78, per iteration (s)")
    print(f"{'level':>5}{'unknowns':>9}{'b':>5}{'banded':>8}{'sparse':>8}")
    for level in (2, 3):
        r = band_against_sparse(level, 78.0, args.repeats)
        print(f"{r['level']:>5}{r['unknowns']:>9}{r['b']:>5}{r['banded']:>8.3f}{r['sparse']:>8.3f}")
    print(f"load average {os.getloadavg()[0]:.1f} (1 min)")


if __name__ == "__main__":
    main()
