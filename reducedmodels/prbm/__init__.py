"""The ``prbm`` family: pseudo-rigid-body models of a flexure.

:mod:`.connector` is the symmetric 3R chain with its fitted parameters (read
from the table :mod:`.parameters` reads, through :mod:`.spline`), :mod:`.pivot`
the one-pivot model of a notch hinge.
Units: mm, N, N mm, rad.
"""

__all__ = [
    "connector",
    "parameters",
    "pivot",
    "spline",
]
"""The modules of this package (import the names from them)."""
