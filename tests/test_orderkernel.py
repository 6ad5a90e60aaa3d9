"""The compiled reverse Cuthill-McKee ordering against scipy's, and the layouts built with it.

A compiled System's TangentLayout orders its unknowns with
flexval.reducedmodels.kernels.orderkernel instead of scipy.sparse.csgraph.reverse_cuthill_mckee;
the permutation must be scipy's exactly (the same tangent storage, so the
same numbers in every result). Checked on chains and closed loops in a
shuffled numbering, disconnected graphs, patterns with duplicates, missing
diagonals and asymmetric entries; and on the built-in scenes' systems, whose
layouts must equal the ones scipy's ordering gives.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.tangent import NARROW_BAND, NARROW_MIN, TangentLayout
from flexval.reducedmodels.kernels import orderkernel
from flexval.reducedmodels.models import build_system


def scipy_ordering(n: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """scipy's RCM of the CSR graph of the entries, as TangentLayout built it before."""
    graph = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    return reverse_cuthill_mckee(graph, symmetric_mode=True).astype(np.int64)


def half_bandwidth(perm: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> int:
    position = np.empty(perm.size, np.int64)
    position[perm] = np.arange(perm.size)
    return int(np.abs(position[rows] - position[cols]).max(initial=0))


def block_chain(
    n_blocks: int, block: int, closed: bool, rng: np.random.Generator
) -> tuple[int, np.ndarray, np.ndarray]:
    """Entries of a chain of elements each coupling two consecutive blocks of unknowns fully
    (beam elements: block 3), closed into a loop or not, in a shuffled numbering."""
    n = n_blocks * block
    label = rng.permutation(n)
    links = n_blocks if closed else n_blocks - 1
    rows, cols = [], []
    for e in range(links):
        dofs = np.concatenate(
            [np.arange(block) + block * e, np.arange(block) + block * ((e + 1) % n_blocks)]
        )
        rows.append(np.repeat(dofs, dofs.size)), cols.append(np.tile(dofs, dofs.size))
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    return n, label[rows], label[cols]


@pytest.mark.parametrize("closed", [False, True])
@pytest.mark.parametrize("n_blocks, block", [(2, 3), (30, 3), (301, 3), (50, 1), (40, 7)])
def test_chains_and_loops_take_scipys_ordering_and_band(n_blocks, block, closed):
    rng = np.random.default_rng(n_blocks + 7 * block + closed)
    n, rows, cols = block_chain(n_blocks, block, closed, rng)
    reference = scipy_ordering(n, rows, cols)
    perm = orderkernel.ordering(n, rows, cols)
    np.testing.assert_array_equal(perm, reference)
    position, b, slots = orderkernel.band_slots(perm, rows, cols)
    assert b == half_bandwidth(reference, rows, cols)
    if not closed:  # an open chain's band: the two blocks of an element
        assert b == 2 * block - 1
    np.testing.assert_array_equal(position[perm], np.arange(n))


@pytest.mark.parametrize("seed", range(40))
def test_random_patterns_take_scipys_ordering(seed):
    """Random entries (several components, duplicates, degree ties), symmetric or not,
    with or without the diagonal: the permutation is scipy's."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 300))
    m = int(rng.integers(0, 5 * n))
    r, c = rng.integers(0, n, m), rng.integers(0, n, m)
    if seed % 2:
        rows, cols = np.concatenate([r, c, np.arange(n)]), np.concatenate([c, r, np.arange(n)])
    else:
        rows, cols = r, c
    rows, cols = rows.astype(np.int64), cols.astype(np.int64)
    np.testing.assert_array_equal(
        orderkernel.ordering(n, rows, cols), scipy_ordering(n, rows, cols)
    )


def test_band_slots_are_the_upper_band_storage():
    """Each entry's slot is where K[row, col] lives in the band storage BandedTangent reads
    (upper triangle; lower entries -1): summed there, the values give back the matrix."""
    rng = np.random.default_rng(5)
    n, rows, cols = block_chain(20, 3, True, rng)
    perm = orderkernel.ordering(n, rows, cols)
    position, b, slots = orderkernel.band_slots(perm, rows, cols)
    full = rng.standard_normal((n, n))
    values = (full + full.T)[rows, cols]  # a symmetric matrix on the (symmetric) pattern
    dense = sp.coo_matrix((values, (rows, cols)), shape=(n, n)).toarray()
    kept = slots >= 0
    band = np.bincount(slots[kept], weights=values[kept], minlength=(b + 1) * n).reshape(n, b + 1)
    i, j = position[rows], position[cols]
    upper = i <= j
    np.testing.assert_array_equal(kept, upper)
    np.testing.assert_array_equal(
        band[j[upper], b + i[upper] - j[upper]], dense[rows[upper], cols[upper]]
    )


SYSTEMS = [
    (scene, model)
    for scene in ("open_chain", "closed_chain")
    for model in ("beam:10", "beam:20", "beam:100", "prbm", *(f"dcmm:{k}" for k in range(1, 9)))
]


@pytest.mark.parametrize("scene, model", SYSTEMS)
def test_built_in_systems_keep_the_layout_scipys_ordering_gives(scene, model):
    """Storage kind, half-bandwidth, permutation and slots as with scipy's ordering."""
    captured = {}
    original = TangentLayout.__init__

    def capture(self, n, rows, cols, n_multipliers=0, compiled=False, ordering=None):
        captured.update(
            n=n, rows=np.asarray(rows), cols=np.asarray(cols), n_multipliers=n_multipliers
        )
        original(self, n, rows, cols, n_multipliers, compiled, ordering)

    TangentLayout.__init__ = capture
    try:
        layout = build_system(load_scene(scene).mechanism, parse_model(model)).layout
    finally:
        TangentLayout.__init__ = original
    n, rows, cols = captured["n"], captured["rows"], captured["cols"]
    if layout.kind == "dense" and n < NARROW_MIN:
        return  # no ordering computed
    reference = scipy_ordering(n, rows, cols)
    b = half_bandwidth(reference, rows, cols)
    if layout.kind == "banded":
        np.testing.assert_array_equal(layout.perm, reference)
        assert layout.b == b
        position = np.empty(n, np.int64)
        position[reference] = np.arange(n)
        i, j = position[rows], position[cols]
        np.testing.assert_array_equal(layout.slots, np.where(i <= j, j * (b + 1) + b - (j - i), -1))
    else:
        assert layout.kind == "dense" and b > NARROW_BAND
