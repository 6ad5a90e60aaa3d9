"""The plate stiffening a straight leaf gets from its clamps: the width effect of ``[width]``.

A straight uniform leaf bent by a small curvature is a narrow beam in the
linear strip theory (:mod:`flexval.geometry.anticlastic`: r = 1 whatever its
depth b), because its section is free to curl anticlastically. A clamp holds
the whole end face flat, so next to it the section cannot curl and bends as a
plate, E I / (1 - nu²); the curl is back a distance of the order of the depth
away (the decay of a self-equilibrated edge disturbance across a strip of
width b). A deep leaf clamped at both ends is therefore stiffer than E I, by a
share of the plate's 1 / (1 - nu²) that grows with b / L.

The model: the bending stiffness along the leaf is E I (1 + p s(x)),
p = nu² / (1 - nu²), with s(x) = exp(-x / (c b)) + exp(-(L - x) / (c b)) (at
most 1) from the two clamps, and the leaf's ratio r keeps its compliance as a
guided leaf bends (the moment linear along it, through zero at mid-length:
the sway of a parallel guide's leaves),

    1 / r = ∫ (1 - 2 x / L)² / (1 + p s(x)) dx / ∫ (1 - 2 x / L)² dx.

The one constant c (:data:`CLAMP_DECAY`) is fitted to the 3D solid
(``continuum:1[3d]``) of parallel leaf guides over b / h from 1 to 40 and
L / h from 40 to 160 (``benchmarks/straight_leaf_width.py``, its points in
``reports/threed/straight_leaves.json``): every point within 0.8 %, where
plain E I is up to 10 % too soft. A leaf bent otherwise (a pivot's leaves
turn under a nearly uniform moment, whose energy gathers less near the
clamps) takes the same ratio: an estimate there, not a fit. Units: mm; the
ratio is dimensionless.
"""

from __future__ import annotations

import functools
import math

import numpy as np

CLAMP_DECAY = 0.419
"""c: the distance over which the plate stiffening at a clamp fades, in leaf depths b;
fitted to ``continuum:1[3d]`` on parallel leaf guides (see the module docstring)."""

SAMPLES = 2049
"""Points of the quadrature over the leaf, spaced as the cosines of equal angles so that
the two boundary layers are resolved: r - 1 within 0.2 % of its converged value down to
b / L = 1e-4 (where r - 1 is 3e-5), within 2e-5 of it from b / L = 0.01 on."""


@functools.lru_cache(maxsize=1024)
def clamped_leaf_ratio(depth: float, length: float, poisson_ratio: float) -> float:
    """The bending stiffness ratio r of a straight uniform leaf clamped at both ends.

    Parameters
    ----------
    depth, length : float
        b (out of plane) and L of the leaf, mm.
    poisson_ratio : float
        nu of its material, in (-1, 0.5].

    Returns
    -------
    float
        From 1 (b / L -> 0: a narrow leaf) towards 1 / (1 - nu²) (b / L -> inf: a plate).
    """
    if not (depth > 0.0 and length > 0.0):
        raise ValueError(f"a leaf's depth and length must be positive, got {depth}, {length}")
    if not -1.0 < poisson_ratio <= 0.5:
        raise ValueError(f"Poisson's ratio must lie in (-1, 0.5], got {poisson_ratio}")
    plate = poisson_ratio**2 / (1.0 - poisson_ratio**2)
    t = np.linspace(0.0, 1.0, SAMPLES)
    x = 0.5 * (1.0 - np.cos(math.pi * t))  # along the leaf, 0..1
    dx = 0.5 * math.pi * np.sin(math.pi * t)  # dx / dt
    decay = CLAMP_DECAY * depth / length
    held = np.minimum(np.exp(-x / decay) + np.exp(-(1.0 - x) / decay), 1.0)
    weight = (1.0 - 2.0 * x) ** 2 * dx
    return float(np.trapezoid(weight, t) / np.trapezoid(weight / (1.0 + plate * held), t))
