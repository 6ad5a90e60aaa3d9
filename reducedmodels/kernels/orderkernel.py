"""Compiled reverse Cuthill-McKee ordering and band slots of a tangent's pattern
(numba, on-disk cache).

:class:`flexval.reducedmodels.core.tangent.TangentLayout` orders the unknowns of a
banded tangent by reverse Cuthill-McKee (RCM). For a system that already
runs compiled kernels these loops do what scipy does there
(``scipy.sparse.csgraph.reverse_cuthill_mckee`` of the CSR graph of the
entries): on a beam chain, building the CSR matrix, ordering and placing
the entries took a large share of a System's build, most of it the sparse
matrix's construction (sorting and summing duplicate entries) and call
overhead, for little graph work.

The ordering is scipy's exactly (``tests/test_orderkernel.py`` compares
the permutations on chains, closed loops, disconnected and random graphs),
so a system's tangent and every number computed from it are unchanged:

* the graph of row i is the set of distinct columns of the entries in row
  i (the pattern is taken as given: a symmetric pattern gives a symmetric
  graph), and a node's degree is the number of those columns, plus one
  when the diagonal is among them (scipy counts the diagonal twice);
* each connected component starts from the first unvisited node in
  ``numpy.argsort(degree)`` (the caller computes that order with numpy,
  so that ties fall as they do in scipy);
* breadth first, each node's unvisited neighbours are appended in
  increasing number, then stably sorted by degree (an insertion sort);
* the order is reversed.

Units: none (unknown numbers and storage positions).
"""

from __future__ import annotations

import numpy as np

from .jit import kernel


@kernel
def pattern_graph(
    n: int, rows: np.ndarray, cols: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The graph of the entries (rows, cols) of an n x n pattern: (indptr, indices, degree).

    Row i's neighbours are ``indices[indptr[i]:indptr[i + 1]]``, its
    distinct columns in increasing order (a CSR matrix's canonical form);
    ``degree`` (int32, as scipy's for these sizes) counts them, the
    diagonal twice.
    """
    count = np.zeros(n + 1, np.int64)
    for k in range(rows.size):
        count[rows[k] + 1] += 1
    for i in range(n):
        count[i + 1] += count[i]
    bucket = np.empty(rows.size, np.int64)
    fill = count[:n].copy()
    for k in range(rows.size):
        bucket[fill[rows[k]]] = cols[k]
        fill[rows[k]] += 1
    indptr = np.zeros(n + 1, np.int64)
    indices = np.empty(rows.size, np.int64)
    degree = np.zeros(n, np.int32)
    seen = np.full(n, -1, np.int64)  # the last row that listed each column
    m = 0
    for i in range(n):
        start = m
        for k in range(count[i], count[i + 1]):
            col = bucket[k]
            if seen[col] == i:
                continue
            seen[col] = i
            a = m  # insertion sort: a row has a few columns
            while a > start and indices[a - 1] > col:
                indices[a] = indices[a - 1]
                a -= 1
            indices[a] = col
            m += 1
            degree[i] += 2 if col == i else 1
        indptr[i + 1] = m
    return indptr, indices[:m], degree


@kernel
def reverse_cuthill_mckee(
    indptr: np.ndarray, indices: np.ndarray, degree: np.ndarray, seeds: np.ndarray
) -> np.ndarray:
    """The RCM permutation of a :func:`pattern_graph` (``perm[k]``: the unknown placed k-th).

    ``seeds`` is ``numpy.argsort(degree)``: each connected component
    starts from its first node not yet placed.
    """
    n = degree.size
    placed = np.zeros(n, np.bool_)
    order = np.empty(n, np.int64)
    count = 0
    for seed in seeds:
        if placed[seed]:
            continue
        placed[seed] = True
        order[count] = seed
        count += 1
        level_start, level_end = count - 1, count
        while level_start < level_end:
            for k in range(level_start, level_end):
                node = order[k]
                first = count
                for p in range(indptr[node], indptr[node + 1]):
                    neighbour = indices[p]
                    if not placed[neighbour]:
                        placed[neighbour] = True
                        order[count] = neighbour
                        count += 1
                for a in range(first + 1, count):  # stable insertion sort by degree
                    moving = order[a]
                    b = a
                    while b > first and degree[moving] < degree[order[b - 1]]:
                        order[b] = order[b - 1]
                        b -= 1
                    order[b] = moving
            level_start, level_end = level_end, count
        if count == n:
            break
    return order[::-1].copy()


@kernel
def band_slots(
    perm: np.ndarray, rows: np.ndarray, cols: np.ndarray
) -> tuple[np.ndarray, int, np.ndarray]:
    """Each unknown's place under ``perm``, the half-bandwidth and the entries' band slots.

    Returns (position, b, slots): ``position[perm[k]] = k``; b the largest
    |position[row] - position[col]| of an entry; ``slots`` where each entry
    goes in the upper band storage of :class:`flexval.reducedmodels.core.tangent.BandedTangent`
    laid out flat (column j's b + 1 values contiguous, the diagonal last:
    ``j (b + 1) + b - (j - i)`` for i = position[row] <= j = position[col]),
    -1 for an entry below the diagonal (its mirror carries the value).
    """
    n = perm.size
    position = np.empty(n, np.int64)
    for k in range(n):
        position[perm[k]] = k
    b = 0
    for k in range(rows.size):
        b = max(b, abs(position[cols[k]] - position[rows[k]]))
    slots = np.empty(rows.size, np.int64)
    for k in range(rows.size):
        i, j = position[rows[k]], position[cols[k]]
        slots[k] = j * (b + 1) + (b - (j - i)) if j >= i else -1
    return position, b, slots


def ordering(n: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """The RCM permutation of the pattern (rows, cols) of an n x n matrix (int64 arrays)."""
    indptr, indices, degree = pattern_graph(n, rows, cols)
    return reverse_cuthill_mckee(indptr, indices, degree, np.argsort(degree))


def warm_up() -> None:
    """Compile, or load from the on-disk cache, the kernels for the int64 arrays of a layout.

    See :func:`flexval.reducedmodels.kernels.beamkernel.warm_up` for who calls it.
    """
    rows = np.array([0, 1, 0, 1], np.int64)
    cols = np.array([0, 1, 1, 0], np.int64)
    band_slots(ordering(2, rows, cols), rows, cols)
