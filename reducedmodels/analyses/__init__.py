"""What a System gives besides a load path.

Natural frequencies and mode shapes, implicit dynamics, linearised buckling and
the stiffness condensed onto the target point. Units: mm, N, N mm, rad, s, t.
"""

__all__ = [
    "buckling",
    "dynamics",
    "modes",
    "targetstiffness",
]
"""The modules of this package (import the names from them)."""
