"""Structured quad9 meshes of a flexure's true outline: any centre line, any thickness law.

A flexure whose section varies (a taper or a notch, :mod:`flexval.geometry.profiles`)
or whose centre line is free-form (:class:`flexval.geometry.shapes.Spline`)
is the region

    X(s, eta) = c(s) + eta h(s) / 2 n(s),    0 <= s <= L,  -1 <= eta <= 1,

with c(s) the centre line at arc length s, n(s) its unit normal (the
tangent turned by +90 deg) and h(s) the thickness. It is meshed by this map:
``2 n_l + 1`` stations s_k along the centre line, ``2 n_t + 1`` positions
eta_m uniform across, every node placed exactly on the map, so the outline
and the end faces (the normals at s = 0 and L) are those of the flexure.

Grading: the elements along the flexure are as long as the local thickness
(times :data:`flexval.geometry.mesh.ASPECT_RATIO`), and short enough that the
thickness changes by at most :data:`THICKNESS_CHANGE` of itself across one,
so that a steep flank (a notch's ends) is followed; each stretch between the
profile's breakpoints is graded on its own, and across the thickness there
are ``2**level`` elements, twice as many on a notch hinge (:data:`NOTCH_ACROSS`).
For a uniform thickness this is the division of
:func:`flexval.geometry.mesh.divisions`. The grading's density and its
measured effect are in ARCHITECTURE.md, "Geometry".

Meshes are cached like :mod:`flexval.geometry.mesh`'s (same folder, checksum
and atomic writes) under a hash of the exact values of the shape and the
thickness law. Units: mm.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math

import numpy as np

from .mesh import (
    ASPECT_RATIO,
    CACHE_FORMAT,
    ELEMENT_ORDER,
    MAX_LEVEL,
    FlexureMesh,
    cached_mesh,
    counterclockwise,
    mesh_flexure,
)
from .shapes import Arc, Segment

OUTLINE_VERSION = 2
"""Bumped whenever the outline meshing changes what it produces (invalidates the cache)."""

THICKNESS_CHANGE = 0.5
"""Largest relative change of the thickness across one element of mesh level 0 (per unit of
its length over the local thickness: elements are shortened where |h'| exceeds it)."""

NOTCH_ACROSS = 2
"""Elements across the thickness of a notch hinge at level 0 (one for any other flexure).

A notch's root is a two-dimensional stress state: its stress concentration is the part of
the stress across the root that is not linear, which one quadratic element across cannot
carry, and it stiffens. Measured on a circular notch under a pure moment (t/R = 0.05, 0.2,
0.5), the tip rotation's error against its Richardson value at levels 0, 1, 2: with one
element across 2.2, 0.15, 0.010 %; 7.1, 0.61, 0.050 %; 12, 1.4, 0.13 %; with two 0.34,
0.023, 0.0015 %; 0.98, 0.073, 0.0050 %; 1.6, 0.16, 0.012 %, for 1.6 to 1.8 times the
unknowns (observed order 3.4 to 4 either way). The elements stay as long as the local
thickness, twice their own thickness, which on a straight axis costs no locking."""

GRADING_SAMPLES = 2048
"""Points per stretch of the table of tau(s) = int ds / h from which stations are placed."""


def stations(length: float, section, level: int) -> np.ndarray:
    """Arc lengths (2 n_l + 1,) of the mesh's stations along the flexure, mm.

    Parameters
    ----------
    length : float
        Centre-line length L, mm.
    section : Section
        Thickness h(s) (uniform or with a profile).
    level : int
        Mesh level, 0 .. MAX_LEVEL.
    """
    if not 0 <= level <= MAX_LEVEL:
        raise ValueError(f"mesh level must be between 0 and {MAX_LEVEL}, got {level}")
    profile = section.profile
    breaks = () if profile is None else profile.breakpoints
    cuts = [0.0, *sorted(b for b in breaks if 0.0 < b < length), length]
    vertices = [np.zeros(1)]
    for a, b in zip(cuts[:-1], cuts[1:]):
        # a table of tau on points clustered at the stretch's ends (where h' may be singular)
        s = a + 0.5 * (b - a) * (1.0 - np.cos(np.linspace(0.0, math.pi, GRADING_SAMPLES + 1)))
        h = np.asarray(section.thickness_at(s), float)
        density = np.maximum(1.0, np.abs(np.gradient(h, s)) / THICKNESS_CHANGE) / h
        tau = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(s))])
        n = max(1, math.ceil(tau[-1] / ASPECT_RATIO - 1e-9)) * 2**level
        inner = np.interp(tau[-1] * np.arange(1, n) / n, tau, s)
        vertices.append(np.concatenate([inner, [b]]))
    vertex = np.concatenate(vertices)
    out = np.empty(2 * vertex.size - 1)
    out[0::2] = vertex
    out[1::2] = 0.5 * (vertex[:-1] + vertex[1:])
    return out


def across(section) -> int:
    """Elements across the thickness at level 0: :data:`NOTCH_ACROSS` for a notch hinge, else 1."""
    profile = section.profile
    return NOTCH_ACROSS if profile is not None and profile.kind == "notch" else 1


def _describe(value):
    """A JSON form of a shape or profile with every float exact (``float.hex``)."""
    if dataclasses.is_dataclass(value):
        return {
            "type": type(value).__name__,
            **{f.name: _describe(getattr(value, f.name)) for f in dataclasses.fields(value)},
        }
    if isinstance(value, (float, np.floating)):
        return float(value).hex()
    if isinstance(value, (tuple, list, np.ndarray)):
        return [_describe(v) for v in value]
    return value


def _key(shape, section, level: int) -> str:
    desc = {
        "kind": "outline",
        "shape": _describe(shape),
        "thickness": float(section.thickness).hex(),
        "profile": _describe(section.profile),
        "level": level,
        "order": ELEMENT_ORDER,
        "aspect": ASPECT_RATIO,
        "grading": [GRADING_SAMPLES, THICKNESS_CHANGE, NOTCH_ACROSS],
        "version": OUTLINE_VERSION,
        "cache_format": CACHE_FORMAT,
    }
    return hashlib.sha256(json.dumps(desc, sort_keys=True).encode()).hexdigest()[:24]


def mesh_outline(shape, section, level: int, use_cache: bool = True) -> FlexureMesh:
    """Structured quad9 mesh of the true outline of a flexure (cached on disk).

    Parameters
    ----------
    shape : Shape
        Centre line (any shape with ``point``, ``tangent``, ``curvature_at``
        and ``length``), mm.
    section : Section
        Its thickness law h(s), mm (s from the shape's start).
    level : int
        Mesh level, 0 .. MAX_LEVEL.
    use_cache : bool
        Read and write the on-disk cache.

    Returns
    -------
    FlexureMesh
        Faces and sections ordered from the right-hand side of the centre
        line (looking along it, eta = -1) to the left.

    Raises
    ------
    ValueError
        If the level is out of range, the thickness is not positive, or the
        outline folds over (h(s)/2 at least the radius of curvature).
    """
    s = stations(shape.length, section, level)
    n_t, n_l = across(section) * 2**level, (s.size - 1) // 2
    h = np.asarray(section.thickness_at(s), float)
    if not np.all(h > 0.0):
        raise ValueError(f"thickness must be positive, got {float(h.min())} mm")
    folds = 0.5 * h * np.abs(np.asarray(shape.curvature_at(s), float))
    if np.any(folds >= 1.0):
        k = int(np.argmax(folds))
        raise ValueError(
            f"thickness {h[k]:.6g} mm at arc length {s[k]:.6g} mm is not smaller than the "
            f"diameter of curvature there ({2.0 * h[k] / (2.0 * folds[k]):.6g} mm): "
            "the outline folds over"
        )
    return cached_mesh(
        _key(shape, section, level),
        level,
        n_t,
        n_l,
        lambda: _build(shape, s, h, n_t, n_l, level),
        use_cache,
    )


def _build(shape, s: np.ndarray, h: np.ndarray, n_t: int, n_l: int, level: int) -> FlexureMesh:
    """The mesh of the map X(s_k, eta_m); node k (2 n_t + 1) + m."""
    width = 2 * n_t + 1
    eta = np.linspace(-1.0, 1.0, width)
    centre = np.asarray(shape.point(s), float)
    tangent = np.asarray(shape.tangent(s), float)
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    nodes = centre[:, None, :] + (0.5 * h[:, None, None] * eta[None, :, None]) * normal[:, None]
    nodes = np.ascontiguousarray(nodes.reshape(-1, 2))
    i, j = np.meshgrid(np.arange(n_l), np.arange(n_t), indexing="ij")
    k0, m0 = 2 * i.ravel(), 2 * j.ravel()
    # quad9 order: corners counterclockwise in (s, eta), then mid-edges, then the centre
    dk = np.array([0, 2, 2, 0, 1, 2, 1, 0, 1])
    dm = np.array([0, 0, 2, 2, 0, 1, 2, 1, 1])
    elements = (k0[:, None] + dk) * width + (m0[:, None] + dm)
    elements = counterclockwise(nodes, elements)
    index = np.arange(s.size)[:, None] * width + np.arange(width)
    return FlexureMesh(
        nodes,
        elements.astype(np.int64),
        index[0].astype(np.int64),
        index[-1].astype(np.int64),
        index[:, n_t].astype(np.int64),
        level,
        n_t,
        n_l,
    )


def flexure_mesh(shape, section, level: int, use_cache: bool = True) -> FlexureMesh:
    """The quad9 mesh of a flexure of any shape and section (cached on disk).

    A uniform arc or segment is meshed by :func:`mesh_flexure` (Gmsh); a
    varying section (``section.profile``: a taper or a notch) or any other
    centre line (a spline) by its true outline,
    :func:`mesh_outline`.

    Parameters
    ----------
    shape : Shape
        Centre line, mm.
    section : Section
        Thickness, uniform or h(s), mm.
    level : int
        Mesh level, 0 .. MAX_LEVEL.
    use_cache : bool
        Read and write the on-disk cache.
    """
    if section.profile is None and isinstance(shape, (Arc, Segment)):
        return mesh_flexure(shape, section.thickness, level, use_cache)
    return mesh_outline(shape, section, level, use_cache)
