"""A flexure mesh's cross-sections in polar form: the load-stepping predictor of the continuum.

The structured quad9 mesh (:mod:`flexval.geometry.mesh`) is a stack of
cross-sections: the ``2 n_t + 1`` nodes on the normal to the centre line
through each centre-line node, the first and last being the end faces. A
deformed mesh is described section by section by

* the chords between consecutive section centres: length ``ell`` (mm) and
  direction ``alpha`` (rad);
* each section's rotation ``phi`` (rad): the direction of the vector across
  it, from its first node to its last;
* each node's offset from its section centre in the section's own frame
  (mm), which carries the section's stretch and warping.

Extrapolating these along the load path instead of the node positions keeps
a turning flexure from coming out stretched: a node position extrapolated
in Cartesian coordinates misses the arc it moves on by O(h^3) of the step h,
and the membrane stiffness of a slender flexure turns that miss into nodal
forces hundreds of times the load, which Newton then spends iterations
removing (measured on the built-in scenes: predicted residuals fall from
~1e3 to ~10 times the load, and whole paths take 20-30 % fewer
iterations). The same reason made the beam model extrapolate chord lengths
and angles (:meth:`flexval.reducedmodels.beam.elements.BeamConnector.predict_internal`).

The same description makes the Newton update of a turning flexure exact
(:func:`increment`): a correction is mapped to the first-order changes of
the chords, rotations and offsets, which are then applied as finite turns.

Units: mm, rad.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from flexval.geometry.mesh import FlexureMesh


class PolarShape(NamedTuple):
    """A deformed mesh section by section (see the module docstring)."""

    ell: np.ndarray  # (n_chords,) lengths of the chords between section centres, mm
    alpha: np.ndarray  # (n_chords,) their directions, rad
    phi: np.ndarray  # (n_sections,) section rotations, rad
    offset: np.ndarray  # (n_sections, 2 n_t + 1, 2) node offsets in the section frame, mm


def nearest(points: np.ndarray, candidates: np.ndarray, rows: int = 512) -> np.ndarray:
    """Index of the nearest of ``candidates`` (m, 2) to each of ``points`` (..., 2), mm.

    Squared distances as |c|^2 - 2 p.c (+ |p|^2, the same for every
    candidate): one matrix product instead of an (n, m, 2) array of
    differences; their round-off, ~1e-16 of the squared coordinates, is far
    below the squared spacing of mesh nodes. Taken ``rows`` points at a time,
    so the distance block stays in cache (a level-1 flexure's 2525 x 505
    block at once took 4.7 times as long, measured).
    """
    flat = points.reshape(-1, 2)
    c2 = np.einsum("ij,ij->i", candidates, candidates)
    index = np.empty(flat.shape[0], np.int64)
    for start in range(0, flat.shape[0], rows):
        block = flat[start : start + rows]
        index[start : start + rows] = np.argmin(c2 - 2.0 * block @ candidates.T, axis=1)
    return index.reshape(points.shape[:-1])


def cross_sections(mesh: FlexureMesh) -> np.ndarray:
    """Node indices of every cross-section (n_sections, 2 n_t + 1).

    Sections run from the start face to the end face; each from the right of
    the centre line (looking along it) to its left, its centre node in the
    middle.

    A node belongs to the centre-line node whose normal it lies on (radial
    lines of an arc, normals of a segment), which is also the nearest
    centre-line node. Every section must have 2 n_t + 1 nodes, its centre
    node in the middle, and the first and last must be the end faces.

    Raises
    ------
    RuntimeError
        If the mesh is not such a stack of sections.
    """
    nodes, line = mesh.nodes, mesh.centre_line
    centre = nodes[line]
    tangent = np.gradient(centre, axis=0)
    tangent /= np.hypot(tangent[:, 0], tangent[:, 1])[:, None]
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    station = nearest(nodes, centre)
    across = np.einsum("nk,nk->n", nodes - centre[station], normal[station])
    width = 2 * mesh.n_t + 1
    if np.any(np.bincount(station, minlength=line.size) != width):
        raise RuntimeError(f"mesh is not a stack of {line.size} sections of {width} nodes")
    sections = np.lexsort((across, station)).reshape(line.size, width)
    if not (
        np.array_equal(sections[:, mesh.n_t], line)
        and np.array_equal(np.sort(sections[0]), np.sort(mesh.start_face))
        and np.array_equal(np.sort(sections[-1]), np.sort(mesh.end_face))
    ):
        raise RuntimeError(
            "mesh sections do not run from the start face to the end face through the centre line"
        )
    return sections


class SectionStack(NamedTuple):
    """The cross-sections of one or several flexures whose nodes are numbered one after the other.

    Attributes
    ----------
    nodes : int array (n_sections, 2 n_t + 1)
        Node indices of every section (:func:`cross_sections`), flexure after flexure.
    first, last : int arrays (n_flexures,)
        Each flexure's first and last section (its end faces).
    starts : int array (n_chords,)
        The sections a chord starts from (all but the last of each flexure).
    chord_flexure, section_flexure : int arrays
        The flexure of each chord and of each section.
    interior : int array
        The sections that are not end faces.
    """

    nodes: np.ndarray
    first: np.ndarray
    last: np.ndarray
    starts: np.ndarray
    chord_flexure: np.ndarray
    section_flexure: np.ndarray
    interior: np.ndarray


def stack_sections(parts: Sequence[np.ndarray], node_offsets: Sequence[int]) -> SectionStack:
    """The :class:`SectionStack` of flexures with sections ``parts``, their nodes shifted by
    ``node_offsets``."""
    counts = np.array([p.shape[0] for p in parts])
    last = np.cumsum(counts) - 1
    first = last - counts + 1
    section_flexure = np.repeat(np.arange(counts.size), counts)
    is_end = np.zeros(counts.sum(), bool)
    is_end[first] = is_end[last] = True
    starts = np.setdiff1d(np.arange(counts.sum()), last)
    return SectionStack(
        np.vstack([p + o for p, o in zip(parts, node_offsets)]),
        first,
        last,
        starts,
        section_flexure[starts],
        section_flexure,
        np.flatnonzero(~is_end),
    )


class _Frames(NamedTuple):
    """The section geometry of node positions that the polar description and its change share."""

    xs: np.ndarray  # (n_sections, 2 n_t + 1, 2) node positions by section, mm
    chord: np.ndarray  # (n_chords, 2) chords between section centres, mm
    across: np.ndarray  # (n_sections, 2) first-to-last node of every section, mm
    phi: np.ndarray  # (n_sections,) section rotations, rad
    cos: np.ndarray  # (n_sections, 1) cos phi
    sin: np.ndarray  # (n_sections, 1) sin phi
    rel: np.ndarray  # (n_sections, 2 n_t + 1, 2) nodes relative to their section centre, mm


def _frames(x: np.ndarray, stack: SectionStack) -> _Frames:
    xs = x[stack.nodes]
    centre = xs[:, stack.nodes.shape[1] // 2]
    across = xs[:, -1] - xs[:, 0]
    phi = np.arctan2(across[:, 1], across[:, 0])
    return _Frames(
        xs,
        centre[stack.starts + 1] - centre[stack.starts],
        across,
        phi,
        np.cos(phi)[:, None],
        np.sin(phi)[:, None],
        xs - centre[:, None],
    )


def _polar(fr: _Frames) -> PolarShape:
    c, s, rel = fr.cos, fr.sin, fr.rel
    offset = np.stack([c * rel[..., 0] + s * rel[..., 1], c * rel[..., 1] - s * rel[..., 0]], -1)
    return PolarShape(
        np.hypot(fr.chord[:, 0], fr.chord[:, 1]),
        np.arctan2(fr.chord[:, 1], fr.chord[:, 0]),
        fr.phi,
        offset,
    )


def to_polar(x: np.ndarray, stack: SectionStack) -> PolarShape:
    """The polar description of node positions x (n_nodes, 2), mm."""
    return _polar(_frames(x, stack))


def advanced(x: np.ndarray, dx: np.ndarray, stack: SectionStack) -> PolarShape:
    """:func:`to_polar` of x (n_nodes, 2) plus its first-order change for node moves dx (mm).

    The section geometry is worked out once for both.
    """
    fr = _frames(x, stack)
    return PolarShape(*(a + d for a, d in zip(_polar(fr), _change(fr, dx, stack))))


def first_order_change(x: np.ndarray, dx: np.ndarray, stack: SectionStack) -> PolarShape:
    """The first-order change of :func:`to_polar` at x (n_nodes, 2) for node moves dx (mm).

    Linear in dx: lengths and offsets in mm, angles in rad, per unit of dx.
    The load stepping's predictor maps the path's slope through it.
    """
    return _change(_frames(x, stack), dx, stack)


def _change(fr: _Frames, dx: np.ndarray, stack: SectionStack) -> PolarShape:
    """First-order change of the polar shape with section geometry ``fr`` for node moves dx."""
    dxs = dx[stack.nodes]
    mid = stack.nodes.shape[1] // 2
    dcentre = dxs[:, mid]
    chord, across = fr.chord, fr.across
    dchord = dcentre[stack.starts + 1] - dcentre[stack.starts]
    dacross = dxs[:, -1] - dxs[:, 0]
    ell2 = np.einsum("ij,ij->i", chord, chord)
    dphi = (across[:, 0] * dacross[:, 1] - across[:, 1] * dacross[:, 0]) / np.einsum(
        "ij,ij->i", across, across
    )
    c, s, rel = fr.cos, fr.sin, fr.rel
    # d(R(-phi) rel) = R(-phi) (d rel - dphi k x rel)
    d0 = dxs[..., 0] - dcentre[:, None, 0] + dphi[:, None] * rel[..., 1]
    d1 = dxs[..., 1] - dcentre[:, None, 1] - dphi[:, None] * rel[..., 0]
    return PolarShape(
        np.einsum("ij,ij->i", chord, dchord) / np.sqrt(ell2),
        (chord[:, 0] * dchord[:, 1] - chord[:, 1] * dchord[:, 0]) / ell2,
        dphi,
        np.stack([c * d0 + s * d1, c * d1 - s * d0], -1),
    )


def _near(angle: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``angle`` shifted by whole turns to within pi of ``reference`` (rad)."""
    return reference + np.mod(angle - reference + np.pi, 2.0 * np.pi) - np.pi


def extrapolate(shapes: Sequence[PolarShape], weights: Sequence[float]) -> PolarShape:
    """The weighted sum of polar shapes (Lagrange extrapolation weights), angles unwrapped.

    Angles are taken within half a turn of the last shape's, so a section
    crossing +-pi between two states is extrapolated through its turn.
    """
    last = shapes[-1]
    return PolarShape(
        *(
            sum(
                w
                * (
                    _near(getattr(p, name), getattr(last, name))
                    if name in ("alpha", "phi")
                    else getattr(p, name)
                )
                for w, p in zip(weights, shapes)
            )
            for name in PolarShape._fields
        )
    )


def _chained(steps: np.ndarray, stack: SectionStack) -> np.ndarray:
    """Running sums of per-chord ``steps`` along each flexure, 0 at its first section."""
    total = np.cumsum(steps, axis=0)
    before = np.concatenate([np.zeros((1,) + steps.shape[1:]), total])[
        np.searchsorted(stack.starts, stack.first)
    ]
    out = np.zeros((stack.nodes.shape[0],) + steps.shape[1:])
    out[stack.starts + 1] = total - before[stack.chord_flexure]
    return out


def interior(
    shape: PolarShape, stack: SectionStack, start: np.ndarray, end: np.ndarray
) -> np.ndarray:
    """Node positions (n_interior, 2 n_t + 1, 2) of ``shape``'s interior sections, mm.

    The section centres are chained from each start face's centre ``start``
    (n_flexures, 2) by the chords; the mismatch with the end face's centre
    ``end`` is spread along the chain in proportion to arc length.
    """
    chords = shape.ell[:, None] * np.column_stack([np.cos(shape.alpha), np.sin(shape.alpha)])
    flexure = stack.section_flexure
    centre = start[flexure] + _chained(chords, stack)
    arc = _chained(shape.ell, stack)
    centre += (end - centre[stack.last])[flexure] * (arc / arc[stack.last][flexure])[:, None]
    inner = stack.interior
    c, s = np.cos(shape.phi[inner])[:, None], np.sin(shape.phi[inner])[:, None]
    off = shape.offset[inner]
    return centre[inner, None] + np.stack(
        [c * off[..., 0] - s * off[..., 1], s * off[..., 0] + c * off[..., 1]], -1
    )


def from_polar(shape: PolarShape, stack: SectionStack, x_ends: np.ndarray) -> np.ndarray:
    """Node positions (n_nodes, 2) of ``shape`` between the end-face nodes given in ``x_ends``.

    The end faces keep ``x_ends``'s positions (their bodies place them);
    only the interior sections are rebuilt (:func:`interior`).
    """
    mid = stack.nodes.shape[1] // 2
    x = x_ends.copy()
    x[stack.nodes[stack.interior].ravel()] = interior(
        shape, stack, x_ends[stack.nodes[stack.first, mid]], x_ends[stack.nodes[stack.last, mid]]
    ).reshape(-1, 2)
    return x
