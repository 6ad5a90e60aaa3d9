"""What the reduced models keep of a flexure's centre line, per process.

The copies of a study over sections or materials (a tolerance study, a sweep of
thicknesses) share their centre lines, and much of a connector's construction
depends on the centre line alone: DCMM's parts and their ellipses' geometry, its
sample points, PRBM's chain at rest. :func:`per_centre_line` keeps such a
function's results, so that each copy computes only what its section and material
change. The kept arrays are made read-only by the functions that make them, so no
copy can change another's.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TypeVar

GEOMETRY_CACHE = 1024
"""Results kept per function (least recently used first out): a sweep block's copies share a
handful of centre lines, a study over shapes has as many as it has points."""

F = TypeVar("F", bound=Callable)


def per_centre_line(function: F) -> F:
    """``function`` of a centre line (and numbers), its results kept where its arguments are
    hashable (the built-in arcs and segments are) and computed anew where they are not."""
    cached = functools.lru_cache(maxsize=GEOMETRY_CACHE)(function)

    @functools.wraps(function)
    def kept(*args):
        try:
            return cached(*args)
        except TypeError:  # a centre line that cannot key the cache
            return function(*args)

    return kept  # type: ignore[return-value]
