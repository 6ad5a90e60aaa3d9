"""The body graph of a mechanism: bodies are vertices, flexures and pins are edges.

One union-find serves both questions asked of it: which bodies a set of
links welds into one rigid cluster (:mod:`flexval.geometry.mobility` welds bodies
along flexures), and how many independent closed loops the mechanism has
(its cycle rank: an open chain has none, the paper's closed chain one).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .mechanism import Mechanism


def connected_roots(vertices: Iterable[str], edges: Iterable[tuple[str, str]]) -> dict[str, str]:
    """Representative vertex of each vertex's connected component (union-find, path halving)."""
    parent = {v: v for v in vertices}

    def root(v: str) -> str:
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v

    for a, b in edges:
        parent[root(a)] = root(b)
    return {v: root(v) for v in parent}


def independent_loops(mechanism: Mechanism) -> int:
    """Number of independent closed loops of the body graph (its cycle rank).

    Bodies (the ground included) are vertices, flexures and pins edges:
    loops = edges - vertices + connected components. 0 for an open chain.
    """
    edges = [link.bodies for link in (*mechanism.flexures, *mechanism.pins)]
    roots = connected_roots(mechanism.bodies, edges)
    return len(edges) - len(roots) + len(set(roots.values()))
