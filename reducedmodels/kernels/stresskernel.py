"""Compiled peak stresses of a stack of flexures' section forces (numba).

A batch's copies have their flexures' section forces stacked, (g, k, m):
g flexures of uniform section, k levels, m stations shared by all
(:class:`flexval.reducedmodels.core.sections.ForceStack`). :func:`stack_peaks` finds
each flexure's outer-fibre stress, its peak at every level and where it lies,
and its profile at the last level in one pass, without the temporaries of
the same arithmetic in array operations
(:func:`flexval.reducedmodels.core.peaks.path_peaks`), whose numbers it gives:
each stress is |N|/A + |M| h/(2 I) in that order of operations, and a peak is
the first largest stress (a NaN, the first NaN), as numpy's ``max`` and
``argmax`` find them.

Units: N, N mm, mm, MPa.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import kernel


@kernel
def stack_peaks(
    at: np.ndarray,
    axial: np.ndarray,
    moment: np.ndarray,
    constants: np.ndarray,
    peaks: np.ndarray,
    places: np.ndarray,
    profile: np.ndarray,
) -> None:
    """Each flexure's peak outer-fibre stress at every level, its place and its last profile.

    Parameters
    ----------
    at : ndarray (m,)
        The stations' arc-length fractions from the flexures' first ends.
    axial, moment : ndarray (g, k, m)
        Normal force (N) and bending moment (N mm) of g flexures at k levels.
    constants : ndarray (g, 3)
        Each flexure's section thickness h (mm), area A (mm^2) and second
        moment I (mm^4).
    peaks, places : ndarray (g, k)
        Filled with each flexure's largest stress at each level (MPa) and its
        station's fraction.
    profile : ndarray (g, m)
        Filled with each flexure's stress at every station at the last level (MPa).
    """
    flexures, levels, stations = axial.shape
    for c in range(flexures):
        thickness, area, bending = constants[c, 0], constants[c, 1], 2.0 * constants[c, 2]
        for level in range(levels):
            best, where = 0.0, -1
            for j in range(stations):
                stress = (
                    abs(axial[c, level, j]) / area + abs(moment[c, level, j]) * thickness / bending
                )
                if level == levels - 1:
                    profile[c, j] = stress
                if where < 0 or (not math.isnan(best) and (stress > best or math.isnan(stress))):
                    best, where = stress, j
            peaks[c, level] = best
            places[c, level] = at[where] if where >= 0 else np.nan


def warm_up() -> None:
    """Compile (or load from the on-disk cache) the kernel on a stack of one flexure."""
    forces = np.ones((1, 1, 2))
    stack_peaks(
        np.array([0.0, 1.0]),
        forces,
        forces,
        np.ones((1, 3)),
        np.empty((1, 1)),
        np.empty((1, 1)),
        np.empty((1, 2)),
    )
