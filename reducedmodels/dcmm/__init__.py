"""The ``dcmm:N`` and ``ee`` families: compliance matrices of a flexure's sub-arcs.

:mod:`.subarcs` gives each of a flexure's equal parts its ellipse of elasticity
and diagonal compliance; :mod:`.connector` displaces them (DCMM_n) or keeps them
at rest (the ellipse of elasticity); :mod:`.stacks` lays a connector's chain
out, alone and stacked with others. Units: mm, N, N mm, rad.
"""

__all__ = [
    "connector",
    "stacks",
    "subarcs",
]
"""The modules of this package (import the names from them)."""
