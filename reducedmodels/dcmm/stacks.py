"""How a DCMM connector's chain is laid out, alone and stacked with others.

A flexure cut into n sub-arcs is a chain of n + 1 bodies, its two end
bodies and n - 1 cut bodies; :func:`chain_layout` numbers them and the
sample points along each sub-arc where stresses and the validity monitor
look. :func:`stack_tables` and :class:`Stack` number the chain bodies,
sub-arcs and samples of many connectors stacked end to end, what the
end-of-path kernels (:mod:`flexval.reducedmodels.kernels.dcmmkernel`) read.
Units: mm, rad.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import numpy as np

from ..core.geometrycache import per_centre_line

SAMPLES_PER_SUB_ARC = 16
"""Segments of each displaced sub-arc of a uniform section at whose ends the section forces
are reported: its stress is M/(I/c) and N/A, whose peak lies at a sub-arc's end or where
the moment peaks, which a sub-arc's smooth moment puts within a few segments."""

SAMPLES_VARYING = 256
"""Segments over a whole flexure of varying section (a notch, a taper) at whose ends its
section forces are reported, at least :data:`SAMPLES_PER_SUB_ARC` per sub-arc: the stress
there is M c(s)/I(s), whose peak under a force across a notch lies off the waist, where
a few samples of a sub-arc miss it; the stations of the PRBM's notch pivot
(:data:`flexval.reducedmodels.prbm.pivot.STATIONS`, 257 points)."""


def samples_per_sub_arc(n: int, varying: bool) -> int:
    """Segments of each of a flexure's n sub-arcs at whose ends its section forces are
    reported: :data:`SAMPLES_PER_SUB_ARC`, and on a varying section enough for
    :data:`SAMPLES_VARYING` over the flexure."""
    if not varying:
        return SAMPLES_PER_SUB_ARC
    return max(SAMPLES_PER_SUB_ARC, -(-SAMPLES_VARYING // n))


@dataclasses.dataclass(frozen=True)
class ChainLayout:
    """The index arrays of a DCMM_n chain, the same for every flexure with the same n and direction.

    Attributes
    ----------
    element_dofs : int64 array (n, 6)
        Local coordinates of each sub-arc's two bodies: a -> 0..2, cut k -> 6 + 3k, b -> 3..5.
    lead, follow : int64 arrays (n,)
        Each sub-arc's leading and following body's first local coordinate.
    values : int64 array (n, 36)
        Each sub-arc's Hessian entries' places among the connector's Hessian values.
    rows, cols : int arrays (36 n,)
        Local (row, col) of each row-major 6x6 sub-arc Hessian entry.
    is_rotation : bool array (3 (n - 1),)
        Which internal coordinates are angles.
    sample_part, sample_w : arrays (m,)
        Sub-arc (chain order) and fraction along it of each sample, a cut sampled once.
    sample_ends : int64 array (m, 2)
        Each sample's sub-arc's leading and following body in the chain (a: 0, cuts, b: n).
    sample_at : array (m,)
        Each sample's arc-length fraction from the flexure's start, in chain order.
    station_order, stations : arrays (m,)
        The order of the samples from the flexure's first end and their
        arc-length fractions from it, increasing.
    """

    element_dofs: np.ndarray
    lead: np.ndarray
    follow: np.ndarray
    values: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    is_rotation: np.ndarray
    sample_part: np.ndarray
    sample_w: np.ndarray
    sample_ends: np.ndarray
    sample_at: np.ndarray
    station_order: np.ndarray
    stations: np.ndarray


@functools.lru_cache(maxsize=64)
def chain_layout(n: int, forward: bool, samples: int = SAMPLES_PER_SUB_ARC) -> ChainLayout:
    """The layout of a chain of n sub-arcs run from the flexure's start (``forward``) or end,
    each sampled at the ends of ``samples`` equal segments.

    It depends on these numbers only, so the flexures of a model share it
    (computed once, like a module constant; the arrays are read-only).
    """
    slots = (
        [np.arange(0, 3)]
        + [np.arange(6 + 3 * k, 9 + 3 * k) for k in range(n - 1)]
        + [np.arange(3, 6)]
    )
    element_dofs = np.array([np.concatenate([slots[k], slots[k + 1]]) for k in range(n)], np.int64)
    w = np.linspace(0.0, 1.0, samples + 1)  # each sample's fraction from its leading cut
    sample_w = np.concatenate([w] + [w[1:]] * (n - 1))
    sample_part = np.concatenate(
        [np.zeros(len(w), int)] + [np.full(len(w) - 1, k) for k in range(1, n)]
    )
    fractions = np.concatenate([w / n] + [(k + w[1:]) / n for k in range(1, n)])
    at = fractions if forward else 1.0 - fractions
    order = np.argsort(at, kind="stable")  # the fractions are distinct
    layout = ChainLayout(
        element_dofs,
        element_dofs[:, 0].copy(),
        element_dofs[:, 3].copy(),
        np.arange(36 * n, dtype=np.int64).reshape(n, 36),
        np.repeat(element_dofs, 6, axis=1).ravel(),
        np.tile(element_dofs, (1, 6)).ravel(),
        np.tile([False, False, True], n - 1),
        sample_part,
        sample_w,
        np.stack([sample_part, sample_part + 1], 1).astype(np.int64),
        at,
        order,
        at[order],
    )
    for array in dataclasses.astuple(layout):
        if isinstance(array, np.ndarray):
            array.flags.writeable = False
    return layout


class StackTables(NamedTuple):
    """The numbering of the chain bodies, sub-arcs and samples of DCMM connectors in one stack.

    It depends only on each connector's number of sub-arcs and direction
    (:func:`stack_tables`); :class:`Stack` adds the connectors' geometry.

    Attributes
    ----------
    first : int64 array (c,)
        Each connector's end body a among the stacked chain bodies.
    sub_arc_body : int64 array (e,)
        Each sub-arc's leading body (its following one is the next).
    sub_arc_start : int64 array (c + 1,)
        Each connector's first sub-arc (and the end).
    lead, follow, sub_arc, last : int64 arrays (s,)
        Each sample's leading and following bodies, its sub-arc and its
        connector's body b.
    connector : int64 array (s,)
        Each sample's connector.
    w : float array (s,)
        Each sample's fraction along its sub-arc.
    order : int64 array (s,)
        The samples in station order, connector by connector.
    sample_start : list of int (c + 1,)
        Each connector's first sample (and the end).
    pose_order : int64 array
        The connectors' local coordinates [pose_a, pose_b, internal], laid
        end to end, in the stack's order of chain bodies (a, cuts, b).
    element_dofs : int64 array (e, 6)
        Each sub-arc's two bodies' coordinates among those local coordinates.
    hessian_rows, hessian_cols : int64 arrays
        The connectors' Hessian values' places among them
        (:meth:`DcmmConnector.hessian_pattern` shifted to each connector's
        first coordinate).
    """

    first: np.ndarray
    sub_arc_body: np.ndarray
    sub_arc_start: np.ndarray
    lead: np.ndarray
    follow: np.ndarray
    sub_arc: np.ndarray
    last: np.ndarray
    connector: np.ndarray
    w: np.ndarray
    order: np.ndarray
    sample_start: list
    pose_order: np.ndarray
    element_dofs: np.ndarray
    hessian_rows: np.ndarray
    hessian_cols: np.ndarray


@per_centre_line
def end_points(shape) -> tuple[tuple[float, float], tuple[float, float]]:
    """The start and end points of a centre line, as float pairs (mm)."""
    (x0, y0), (x1, y1) = shape.end_points.tolist()
    return (x0, y0), (x1, y1)


@per_centre_line
def sample_points(
    shape, n: int, forward: bool, samples: int = SAMPLES_PER_SUB_ARC
) -> tuple[np.ndarray, np.ndarray]:
    """The points (mm) of the chain's samples at rest on the centre line of n sub-arcs
    (``samples`` segments each), and the direction of each one's section towards the chain's
    second body (rad), read-only."""
    s = shape.length * chain_layout(n, forward, samples).sample_at
    points = shape.point(s)
    tangent = shape.tangent_angle(s)
    if not forward:
        tangent += np.pi
    points.flags.writeable = False
    tangent.flags.writeable = False
    return points, tangent


@functools.lru_cache(maxsize=64)
def stack_tables(chains: tuple[tuple[int, bool, int], ...]) -> StackTables:
    """The tables of a stack of chains given as (sub-arcs, runs forward, samples per sub-arc)
    each, in order.

    They depend on these numbers only (not on the geometry), so the systems
    of a model share them, like :func:`chain_layout` (the arrays are read-only).
    """
    first, sub_arc_start, sub_arc_body, sample_start = [], [0], [], [0]
    lead, sub_arc, order, last, connector, w, pose_order = [], [], [], [], [], [], []
    element_dofs, rows, cols = [], [], []
    body = start = 0
    for j, (n, forward, samples) in enumerate(chains):
        layout = chain_layout(n, forward, samples)
        first.append(body)
        sub_arc_body += range(body, body + n)
        part, count = layout.sample_part, layout.sample_part.size
        lead.append(part + body)
        sub_arc.append(part + sub_arc_start[-1])
        order.append(layout.station_order + sample_start[-1])
        w.append(layout.sample_w)
        last += [body + n] * count
        connector += [j] * count
        sub_arc_start.append(sub_arc_start[-1] + n)
        sample_start.append(sample_start[-1] + count)
        body += n + 1
        m = 6 + 3 * (n - 1)  # [pose_a, pose_b, internal] -> a, internal, b
        pose_order += [
            *range(start, start + 3),
            *range(start + 6, start + m),
            *range(start + 3, start + 6),
        ]
        element_dofs.append(layout.element_dofs + start)
        rows.append(layout.rows + start)
        cols.append(layout.cols + start)
        start += m
    lead = np.concatenate(lead).astype(np.int64)
    tables = StackTables(
        np.array(first, np.int64),
        np.array(sub_arc_body, np.int64),
        np.array(sub_arc_start, np.int64),
        lead,
        lead + 1,
        np.concatenate(sub_arc).astype(np.int64),
        np.array(last, np.int64),
        np.array(connector, np.int64),
        np.concatenate(w),
        np.concatenate(order).astype(np.int64),
        sample_start,
        np.array(pose_order, np.int64),
        np.concatenate(element_dofs),
        np.concatenate(rows).astype(np.int64),
        np.concatenate(cols).astype(np.int64),
    )
    for array in tables:
        if isinstance(array, np.ndarray):
            array.flags.writeable = False
    return tables


@dataclasses.dataclass(frozen=True)
class Stack:
    """Several DCMM connectors in one stack: its numbering and the connectors' geometry.

    What the end-of-path kernels read (:mod:`flexval.reducedmodels.kernels.dcmmkernel`).

    Attributes
    ----------
    tables : StackTables
        The numbering of the stack's chain bodies, sub-arcs and samples.
    end_rel : float array (c, 4)
        Flexure ends' offsets from bodies a and b (mm).
    lengths : float array (e,)
        Sub-arc lengths (mm).
    parameters : float array (e, PARAMETERS)
        Each sub-arc's :func:`flexval.reducedmodels.kernels.dcmmkernel.sub_arc` parameters.
    rel : float array (s, 4)
        Each sample's offsets from its leading and following bodies (mm).
    tangent : float array (s,)
        Each sample's section direction at rest (rad, towards body b).
    """

    tables: StackTables
    end_rel: np.ndarray
    lengths: np.ndarray
    parameters: np.ndarray
    rel: np.ndarray
    tangent: np.ndarray

    @classmethod
    def of(cls, connectors, tables: StackTables) -> Stack:
        """The stack of ``connectors`` (DcmmConnector), in their order, with their tables."""
        return cls(
            tables,
            np.array([(*c.end_rel[0], *c.end_rel[1]) for c in connectors]),
            np.concatenate([c.sub_lengths for c in connectors]),
            np.concatenate([c.parameters for c in connectors]),
            np.concatenate([c.sample_rel for c in connectors]),
            np.concatenate([c.sample_tangent for c in connectors]),
        )

    @staticmethod
    def poses(levels) -> np.ndarray:
        """The stacked chain bodies' poses at each of k levels, (k, bodies, 3) (mm, rad)."""
        return np.concatenate(
            [
                x
                for states in levels
                for pose_a, pose_b, internal in states
                for x in (pose_a, internal, pose_b)
            ]
        ).reshape(len(levels), -1, 3)
