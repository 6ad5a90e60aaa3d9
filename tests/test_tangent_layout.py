"""TangentLayout's storage of further matrices: where their entries go, and products with it.

The dynamic step sums the mass matrix into the tangent's storage and multiplies
the stored matrices by velocities and accelerations (flexval.reducedmodels.analyses.dynamics);
checked here against the dense matrix built by scipy from the same entries,
for each storage kind the layout chooses (dense, banded under a reverse
Cuthill-McKee permutation, sparse).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from flexval.reducedmodels.core.tangent import TangentLayout


def symmetric_pattern(
    n: int, reach: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of a symmetric pattern: each unknown coupled to a few within ``reach``
    in a shuffled numbering (so the band exists only after reordering), diagonal included."""
    label = rng.permutation(n)
    i = np.repeat(np.arange(n), 3)
    j = np.clip(i + rng.integers(1, reach + 1, i.size), 0, n - 1)
    rows = np.concatenate([label[i], label[j], label])
    cols = np.concatenate([label[j], label[i], label])
    return rows, cols


def stored(layout: TangentLayout, rows, cols, values) -> np.ndarray:
    """The layout's storage of the matrix with these entries (duplicates summed)."""
    slots = layout.slots_of(rows, cols)
    kept = slots >= 0
    return np.bincount(slots[kept], weights=values[kept], minlength=layout.size)


@pytest.mark.parametrize(
    "n, reach, kind", [(40, 5, "dense"), (300, 3, "banded"), (300, 150, "sparse")]
)
def test_stored_matrix_and_its_product_match_the_dense_matrix(n, reach, kind):
    rng = np.random.default_rng(7)
    rows, cols = symmetric_pattern(n, reach, rng)
    layout = TangentLayout(n, rows, cols)
    assert layout.kind == kind
    half = rng.standard_normal(rows.size)
    # a symmetric matrix on the pattern: each entry's value also given to its mirror
    values = np.concatenate([half, half])
    rows2, cols2 = np.concatenate([rows, cols]), np.concatenate([cols, rows])
    dense = sp.coo_matrix((values, (rows2, cols2)), shape=(n, n)).toarray()
    storage = stored(layout, rows2, cols2, values)
    np.testing.assert_allclose(layout.tangent(storage).toarray(), dense, rtol=0, atol=1e-12)
    x = rng.standard_normal(n)
    np.testing.assert_allclose(layout.product(storage, x), dense @ x, rtol=0, atol=1e-11)


def test_entries_without_a_place_in_the_storage_are_refused():
    """Outside the band (banded) or the pattern (sparse): None, never a wrong slot."""
    rng = np.random.default_rng(3)
    for reach, kind in ((3, "banded"), (150, "sparse")):
        rows, cols = symmetric_pattern(300, reach, rng)
        layout = TangentLayout(300, rows, cols)
        assert layout.kind == kind
        assert layout.slots_of(rows, cols) is not None
        if kind == "banded":  # the first and the last unknown of the reordering
            pair = (np.array([layout.perm[0]]), np.array([layout.perm[-1]]))
        else:  # an entry the pattern does not have
            taken = set(zip(rows.tolist(), cols.tolist()))
            free = next((r, c) for r in range(300) for c in range(300) if (r, c) not in taken)
            pair = (np.array([free[0]]), np.array([free[1]]))
        assert layout.slots_of(*pair) is None
