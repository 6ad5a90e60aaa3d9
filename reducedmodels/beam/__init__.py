"""The ``beam:N`` family: geometrically exact corotational beam elements.

:mod:`.elements` is the connector of a flexure cut into N elements,
:mod:`.varying` its stations on a varying section. Units: mm, N, N mm, rad.
"""

__all__ = [
    "elements",
    "varying",
]
"""The modules of this package (import the names from them)."""
