"""What a continuum load path will take, estimated from the mechanism and the mesh level
without meshing (the catalogue's :class:`~flexval.reducedmodels.catalogue.Cost`).

Unknowns: every flexure's mesh is a structured band of ``n_t`` elements across
and ``n_l`` along (:func:`flexval.geometry.mesh.divisions` for a uniform arc or
segment, :func:`flexval.geometry.outline.stations` and
:func:`~flexval.geometry.outline.across` for any other flexure), so it has
``w (2 n_l + 1)`` quad9 nodes with ``w = 2 n_t + 1`` nodes across; the nodes of
its two end faces follow the bodies, the others carry two coordinates each.
With three per moving body and two multipliers per pin this is exactly the
System's number of unknowns (checked in the tests).

Memory: the element arrays (quadrature-point gradients, element Hessians and
their assembly slots, the recorded path) grow with the unknowns n; the
factor of the tangent (a band of half-width about 7 w after reverse
Cuthill-McKee, or SuperLU's fill, alike for a strip) with n w. The model

    peak = BASE_BYTES + BYTES_PER_UNKNOWN n + BYTES_PER_FILL n w

is fitted to the peak resident memory of ``flexval run`` (``/usr/bin/time -v``)
on open_chain m+ (levels 0-4) and notch_fourbar f+ (levels 0-4); see
:data:`BYTES_PER_UNKNOWN` for the fit's spread.

Time: each Newton iteration factorises a tangent of bandwidth ~ w, a cost
growing like n w^TIME_EXPONENT; a load step takes at most
:data:`ITERATIONS_PER_STEP` iterations on the built-in scenes.

The 3D model (option ``3d``, :mod:`.connector3d`) extrudes each flexure's
mesh over ``n_z`` layers (:func:`flexval.geometry.extrude.layers`) into
``2 n_z + 1`` node layers: every node off the end faces carries x and y,
and z unless it lies on the mid-plane (:func:`size_3d`). Its memory and time
grow with the element-matrix entries (81 x 81 per element, each expanded
into the Hessian values the core scatters), its time also with SuperLU's
factorisations, about n w (:data:`BYTES_PER_ENTRY_3D`,
:data:`SECONDS_PER_FACTOR_3D`).

Units: bytes, s.
"""

from __future__ import annotations

import math

from flexval.geometry import Mechanism
from flexval.geometry.loads import DEFAULT_LEVELS
from flexval.geometry.mesh import ASPECT_RATIO, MAX_LEVEL
from flexval.geometry.shapes import Arc, Segment
from flexval.reducedmodels.catalogue import Cost, ModelSpec

from .level import DEFAULT_LEVEL

BASE_BYTES = 70e6
"""Resident memory of a process that has imported the solver (numpy, scipy, scikit-fem)."""
BYTES_PER_UNKNOWN = 8.06e3
"""Peak memory per unknown (element arrays and path). Fitted with :data:`BYTES_PER_FILL` and
:data:`BASE_BYTES` (least squares of the relative error) to the peak resident memory of
``flexval run`` on open_chain m+ levels 0-3 and notch_fourbar f+ levels 0-4: estimate over
measured 0.81-1.12 (open_chain level 2: 0.53 GB for 0.65 GB; notch_fourbar level 4: 3.45 GB
for 3.50 GB); on closed_chain f+ (not fitted) 0.90 and 1.03 at levels 2 and 3."""
BYTES_PER_FILL = 161.0
"""Peak memory per unknown and node across the band (the tangent's factor)."""
SECONDS_PER_UNIT = 1.18e-7
"""Seconds of one Newton iteration per unknown and per w^TIME_EXPONENT, fitted (log least
squares) to the path times of the runs above at levels 1-4 (a path's time as
``benchmarks/bench_continuum.py --level N`` measures it): with
:data:`ITERATIONS_PER_STEP` the estimate is 0.8-1.3 times the time on open_chain and
closed_chain, 1.4-2.7 times on notch_fourbar (which takes 1.5 iterations a step)."""
TIME_EXPONENT = 1.32
ITERATIONS_PER_STEP = 3.2
"""Newton iterations per load step (open_chain m+: 2.9-3.4 at levels 0-3, closed_chain f+:
3.6; notch_fourbar f+: 1.3-1.7)."""
BYTES_PER_ENTRY_3D = 190.0
"""3D model: peak memory per element-matrix entry (the element matrices, the Hessian values
with their pattern and storage slots, the sparse tangent; SuperLU's factor, about 10 n w
values, is folded in), above :data:`BASE_BYTES`. Fitted to the peak resident memory of
``flexval run open_chain`` at levels 0 and 1 (35.3 million entries at level 1): estimate
over measured 0.88-1.14 (level 1: 6.78 GB for m+ 6.30, m- 6.14, f+ 7.71 GB, SuperLU's fill
depending on its pivots; level 0: 0.91 GB for 0.80-0.85); closed_chain f+ level 0 (not
fitted) 0.36 GB for 0.33."""
SECONDS_PER_ENTRY_3D = 1.0e-7
"""3D model: seconds per element-matrix entry and assembly (element kernels, scatter):
open_chain 0.36 s at level 0 (4.4 million entries), 4.1 s at level 1 (35 million). With
the constants below the estimate of an open_chain path is 34 s at level 0 and 420 s at
level 1; measured (``benchmarks/bench_continuum3d.py table``): 24-74 s (m+, m-, f+) and
246 s (f-, 155 Newton iterations) at level 0, 537-1021 s (m+, m-, f+; m+ 193 s of CPU) at
level 1."""
SETUP_SECONDS_PER_ENTRY_3D = 7.0e-7
"""3D model: set-up seconds per element-matrix entry (meshes, gradients, index maps):
open_chain 1.6-2.4 s at level 0, 25 s at level 1."""
SECONDS_PER_FACTOR_3D = 7.5e-7
"""3D model: seconds of one SuperLU factorisation per unknown and node across the section
(open_chain: 0.31 s at level 0, n w = 0.42 million; 6.0 s at level 1, 7.9 million)."""
ASSEMBLIES_PER_STEP_3D = 3.6
FACTORS_PER_STEP_3D = 4.6
"""Assemblies and factorisations per load step of the 3D model (open_chain m+ level 0: 36
Newton iterations and 46 factorisations, the stability checks' included, in 10 steps)."""


def divisions(flexure, level: int) -> tuple[int, int]:
    """Elements (across, along) of ``flexure``'s mesh at ``level``, as the mesher makes them.

    Parameters
    ----------
    flexure : Flexure
    level : int
        Mesh level, 0 .. MAX_LEVEL.
    """
    section, shape = flexure.section, flexure.shape
    if section.profile is None and isinstance(shape, (Arc, Segment)):
        n_l0 = max(1, math.ceil(shape.length / (ASPECT_RATIO * section.thickness) - 1e-9))
        return 2**level, n_l0 * 2**level
    from flexval.geometry.outline import across, stations

    # each level splits every element of level 0 in two both ways
    n_l0 = (stations(shape.length, section, 0).size - 1) // 2
    return across(section) * 2**level, n_l0 * 2**level


def size(mechanism: Mechanism, level: int) -> tuple[int, int]:
    """(unknowns, widest band in nodes w = 2 n_t + 1) of the continuum System at ``level``."""
    if not 0 <= level <= MAX_LEVEL:
        raise ValueError(f"mesh level must be between 0 and {MAX_LEVEL}, got {level}")
    n = 3 * len(mechanism.moving_bodies) + 2 * len(mechanism.pins)
    widest = 0
    for flexure in mechanism.flexures:
        n_t, n_l = divisions(flexure, level)
        w = 2 * n_t + 1
        n += 2 * w * (2 * n_l - 1)  # all nodes but the two end faces'
        widest = max(widest, w)
    return n, widest


def size_3d(mechanism: Mechanism, level: int) -> tuple[int, int, int]:
    """(unknowns, widest section in nodes, element-matrix entries) of the 3D continuum System
    at ``level`` (half-depth meshes, :mod:`.connector3d`)."""
    from flexval.geometry.extrude import layers

    if not 0 <= level <= MAX_LEVEL:
        raise ValueError(f"mesh level must be between 0 and {MAX_LEVEL}, got {level}")
    n_z = layers(level)
    n = 3 * len(mechanism.moving_bodies) + 2 * len(mechanism.pins)
    widest = entries = 0
    for flexure in mechanism.flexures:
        n_t, n_l = divisions(flexure, level)
        free = (2 * n_t + 1) * (2 * n_l - 1)  # in-plane nodes off the end faces
        n += 2 * free * (2 * n_z + 1) + free * 2 * n_z  # x, y everywhere; z off the mid-plane
        widest = max(widest, (2 * n_t + 1) * (2 * n_z + 1))
        entries += n_t * n_l * n_z * 81 * 81
    return n, widest, entries


def path_cost(mechanism: Mechanism, spec: ModelSpec, levels: int | None = None) -> Cost:
    """Peak memory and time of one continuum load path (``spec``'s mesh level).

    Parameters
    ----------
    mechanism : Mechanism
    spec : ModelSpec
        A continuum spec (its resolution is the mesh level).
    levels : int, optional
        Load levels of the path (default 11, the scenes' usual).
    """
    level = DEFAULT_LEVEL if spec.resolution is None else spec.resolution
    steps = max(1, (levels or DEFAULT_LEVELS) - 1)
    if spec.kwargs.get("three_d"):
        n, w, entries = size_3d(mechanism, level)
        peak = BASE_BYTES + BYTES_PER_ENTRY_3D * entries
        per_step = (
            ASSEMBLIES_PER_STEP_3D * SECONDS_PER_ENTRY_3D * entries
            + FACTORS_PER_STEP_3D * SECONDS_PER_FACTOR_3D * n * w
        )
        seconds = SETUP_SECONDS_PER_ENTRY_3D * entries + steps * per_step
        return Cost(peak, seconds, f"{n:,} unknowns, {w} nodes across a section (3D)")
    n, w = size(mechanism, level)
    peak = BASE_BYTES + BYTES_PER_UNKNOWN * n + BYTES_PER_FILL * n * w
    seconds = ITERATIONS_PER_STEP * steps * SECONDS_PER_UNIT * n * w**TIME_EXPONENT
    return Cost(peak, seconds, f"{n:,} unknowns, {w} nodes across")
