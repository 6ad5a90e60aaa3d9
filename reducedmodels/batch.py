"""Many copies of one mechanism and model traced together: a batch.

A design study runs the same mechanism topology with the same model
thousands of times, with other dimensions and loads. Traced one by one,
each path pays the per-call costs of the core (Python, LAPACK's checks,
numpy's small-array overheads) at every Newton iteration; a 9-unknown
``dcmm:1`` path costs far more than its arithmetic. :class:`BatchSystem`
puts N copies side by side in one :class:`~flexval.reducedmodels.core.System`:
their connectors join the same groups (one compiled assembly for all), their
tangent is block-diagonal (one banded factorisation, whose band is one
copy's), and :func:`trace_batch` steps them together through the one tracer
(:func:`flexval.reducedmodels.tracer.trace`) with the one Newton iteration
applied to every copy at once (:func:`flexval.reducedmodels.newton.solve`).

How copies stay exactly what they are alone:

* every test of a Newton iteration is made per copy (its own residual
  relative to its own load scale, its own correction scaled by its own
  size, its own body motions); a copy that converges stops there and its
  tangent block keeps the values its own solve would return;
* every decision of load control (halve a predicted sub-step, accept or
  cut a step, grow the next) is made per copy as
  :class:`~flexval.reducedmodels.tracer.LoadControl` makes it; where the
  copies disagree, the minority leaves the batch
  and goes on as a batch of its own from the last reported level the copies
  shared, where each copy stands as its solo run stands, so the others are
  not held back and no work before that level is done twice. A batch that
  has lost a quarter of its copies goes on as a new batch without them
  (:data:`DEAD_WEIGHT`). A batch that cannot go on (step cutting fails, the
  sub-step budget) hands every copy left to a run alone from rest, which
  then fails or succeeds as it would alone.
* copies too large to gain from a batch (:data:`SOLO_UNKNOWNS`) are traced
  one by one.

A copy's path is its solo run's up to round-off: the batch factorises every
block in the band (a small copy alone takes dense LAPACK) and combines the
predictor's states elementwise, so the last digits of its iterates differ,
and where a Newton test lands within round-off of its bound the copy stops
an iteration or two earlier or later than alone. Over the 236
reduced-model paths of the built-in scenes (three copies each) the batch
and solo end values differ by at most 1.6e-11 of the mechanism's size
(lengths) and in rad, most by less than 1e-13. Within a batch, the
arithmetic of a copy does not depend on the other copies: its path is the
same bit for bit in a batch of any size.

Units: mm, N, N mm, rad; times in s.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from functools import cached_property
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from flexval.geometry import LoadCase, Mechanism, SceneError

from . import stability
from .allocator import keep_freed_memory
from .batchrecord import record_batch
from .blocktangent import BlockLayout, BlockMaps, BlockTangent, block_maps
from .connector import Connector
from .core import SolverError, SolverSettings, System, case_loads
from .linearbatch import linear_responses
from .loadpath import LoadPath
from .loads import Loads
from .tracer import Counters, LoadControl, PathPoint, TraceFailure, trace

Member = tuple[Mechanism, Sequence[Connector]]
"""One copy of a batch: its mechanism and the connectors a System of it joins."""


class BatchSystem(System):
    """Independent copies of one mechanism topology and model as one System.

    Parameters
    ----------
    members : sequence of System or (Mechanism, connectors)
        The copies: each a System built as for a solo run, or the mechanism
        and the connectors such a System would join (same family and
        resolution; any dimensions, sections and materials). They must have
        the same bodies and the same kinds of connectors in the same order,
        and share the ground's reference point (mm).
    settings : SolverSettings, optional
        The solver settings (default: the first System's, or the defaults).

    Attributes
    ----------
    members : list of (Mechanism, list of Connector)
    n_copies : int
    copy_dofs : list of int arrays
        Where each copy's coordinates (numbered as its own System numbers
        them) lie in the batch's.
    dof_copy : int array (n_dofs,)
        The copy each coordinate of the batch belongs to.
    slot_copy : int array (layout.size,)
        The copy each value slot of the tangent storage belongs to
        (``n_copies`` for a slot no entry uses).
    kept : array (layout.size,)
        Every copy's tangent values at its last accepted state (at rest
        before the first): what a copy's block holds while it takes no part
        in a solve, so that the block-diagonal factorisation stays that of
        stable blocks. Replaced as copies advance, never changed in place
        (solves and accepted tangents share it).
    """

    def __init__(self, members: Sequence[System | Member], settings: SolverSettings | None = None):
        if not members:
            raise ValueError("a batch needs at least one copy")
        self.solo_systems: dict[int, System] = {}
        pairs, lists = [], {}  # copies given one sequence of connectors share one list
        for k, member in enumerate(members):
            if isinstance(member, System):
                self.solo_systems[k] = member
                settings = settings or member.settings
            mechanism, connectors = _parts(member)
            if id(connectors) not in lists:
                lists[id(connectors)] = (connectors, list(connectors))
            pairs.append((mechanism, lists[id(connectors)][1]))
        settings = settings or SolverSettings()
        #: copy 0 as a System alone: the numbering and band order every copy shares
        self.template = self.solo_systems.get(0) or System(*pairs[0], settings)
        #: every copy numbered as copy 0 (the same connectors' sizes): no System per copy
        self.uniform = self._check(pairs)
        self.members, self.n_copies = pairs, len(pairs)
        ground = pairs[0][0].ground
        #: each copy's body names in the batch
        self.copy_names = names = self._names(pairs, ground)
        merged, origin = self._merged_connectors(pairs, None if self.uniform else names)
        #: (copy, index among the copy's connectors) of every connector of the batch, (n, 2)
        self.origin_table = origin
        self.copy_dofs: list[np.ndarray] | None = None
        #: copy_dofs as one table (copies, unknowns) where every copy is numbered as copy 0
        self._copy_table: np.ndarray | None = None
        super().__init__(self._merged_mechanism(pairs, ground, names), merged, settings)
        self._number_copies()
        self._dense = self._dense_blocks()
        if self._dense is not None and self.n_multipliers > 0:  # saddle points: block by block
            self.layout = BlockLayout(self.layout, self._dense)

    def number_connectors(self) -> tuple[np.ndarray, np.ndarray, list[int], np.ndarray]:
        """:meth:`System.number_connectors` of copies all numbered as copy 0, as one table.

        Copy k's bodies are the batch's bodies k b .. (k + 1) b - 1 (b bodies a
        copy, in copy 0's order), so a connector's pose dofs are its copy 0
        counterpart's shifted by 3 b k; the internal coordinates follow in
        the batch's connector order; each copy's internal angles are read
        once per sequence of connectors the copies share. The numbers the
        loop over every connector gives (``tests/test_batch.py``), without it.
        """
        if not self.uniform:
            return super().number_connectors()
        template, count = self.template, self.n_copies
        bodies = len(template.body_index)
        copy, index = self.origin_table[:, 0], self.origin_table[:, 1]
        starts = np.asarray(template.connector_offsets[:-1], np.int64)
        ends = template.all_dofs[starts[:, None] + np.arange(6)][index]  # copy 0's, -1: ground
        pose = np.where(ends >= 0, ends + 3 * bodies * copy[:, None], -1)
        poses = 3 * bodies * count
        sizes = (np.diff(template.connector_offsets) - 6)[
            index
        ]  # each connector's internal coordinates
        total = poses + int(sizes.sum())
        place = np.where(pose >= 0, pose, total + np.arange(6) % 3)
        bounds = np.concatenate([[0], np.cumsum(6 + sizes)])
        angles = np.tile([False, False, True], bodies * count)
        if not sizes.any():
            return pose.ravel(), place.ravel(), bounds.tolist(), angles
        dofs, places = np.empty(bounds[-1], np.int64), np.empty(bounds[-1], np.int64)
        at = bounds[:-1, None] + np.arange(6)
        dofs[at], places[at] = pose, place
        per = np.repeat(np.arange(sizes.size), sizes)  # the connector of each internal one
        offset = np.arange(per.size) - np.repeat(np.cumsum(sizes) - sizes, sizes)
        at = bounds[:-1][per] + 6 + offset
        dofs[at] = places[at] = poses + np.arange(per.size)
        # each distinct sequence of connectors' internal angles, in copy 0's internal order
        rows, table = {}, []
        for _, connectors in self.members:
            if id(connectors) not in rows:
                rows[id(connectors)] = len(table)
                table.append(
                    np.concatenate(
                        [np.zeros(0, bool)]
                        + [np.asarray(c.internal_is_rotation(), bool) for c in connectors]
                    )
                )
        row = np.array([rows[id(connectors)] for _, connectors in self.members])
        first = np.cumsum(np.diff(template.connector_offsets) - 6) - (
            np.diff(template.connector_offsets) - 6
        )
        internal = np.array(table)[row[copy[per]], first[index[per]] + offset]
        return dofs, places, bounds.tolist(), np.concatenate([angles, internal])

    @staticmethod
    def _check(pairs: list[Member]) -> bool:
        """Refuse copies that are not of copy 0's topology; True if every copy's connectors
        also have copy 0's numbers of internal coordinates (meshes may differ in size)."""
        mech0, connectors0 = pairs[0]
        ground, bodies = mech0.ground, list(mech0.bodies)
        kinds = [(type(c), c.bodies) for c in connectors0]
        sizes = [c.n_internal for c in connectors0]
        uniform, seen = True, set()
        for k, (mech, connectors) in enumerate(pairs):
            if (id(mech), id(connectors)) in seen:  # a copy of a copy checked already
                continue
            seen.add((id(mech), id(connectors)))
            if list(mech.bodies) != bodies or mech.ground != ground:
                raise ValueError(f"copy {k}: its bodies differ from copy 0's")
            if not np.array_equal(mech.bodies[ground].reference, mech0.bodies[ground].reference):
                raise ValueError(f"copy {k}: its ground's reference point differs from copy 0's")
            if [(type(c), c.bodies) for c in connectors] != kinds:
                raise ValueError(f"copy {k}: its connectors differ in kind from copy 0's")
            uniform = uniform and [c.n_internal for c in connectors] == sizes
        return uniform

    def _own(self, k: int) -> System:
        """The System whose numbering copy k has: copy 0's alone if all are alike."""
        return self.template if self.uniform else self.copy_system(k)

    def judges_stability(self) -> bool:
        """Whether every copy's stability is judged (each as alone,
        :meth:`System.judges_stability`)."""
        return all(self.copy_system(k).judges_stability() for k in range(self.n_copies))

    def stability_note(self) -> str | None:
        """The first copy's note on stability not judged, if any copy has one."""
        notes = (self.solo_systems[k].stability_note() for k in sorted(self.solo_systems))
        return next((note for note in notes if note is not None), None)

    def copy_system(self, k: int) -> System:
        """Copy k as a System alone (built on first use: a check of that copy, a solo run)."""
        if k not in self.solo_systems:
            self.solo_systems[k] = System(*self.members[k], self.settings)
        return self.solo_systems[k]

    @staticmethod
    def _names(pairs: list[Member], ground: str) -> list[dict[str, str]]:
        """Each copy's body names in the batch: copy k's body b is ``k/b``, the ground is
        shared, every copy's bodies being copy 0's (:meth:`_check`)."""
        moving = pairs[0][0].moving_bodies
        return [{ground: ground, **{b: f"{k}/{b}" for b in moving}} for k in range(len(pairs))]

    @staticmethod
    def _merged_connectors(
        pairs: list[Member], names: list[dict[str, str]] | None
    ) -> tuple[list[Connector], np.ndarray]:
        """Every copy's connectors, one class after the other; with ``names`` (:meth:`_names`)
        renamed to the batch's body names.

        Connectors of one class sit together so that each class is one group
        (one compiled assembly for all copies). Copies all numbered as copy 0
        (:attr:`uniform`) keep their connectors as they are: their numbering
        is copy 0's shifted (:meth:`number_connectors`), not looked up by body
        name, and the ground, the one body a connector's names are read for
        (:meth:`System.reaction`), keeps its name. Also returns, per
        connector, (copy, index among the copy's connectors), (n, 2).
        """
        kinds = list(dict.fromkeys(type(c) for c in pairs[0][1]))
        bodies = [
            [(j, c.bodies) for j, c in enumerate(pairs[0][1]) if type(c) is kind] for kind in kinds
        ]
        merged, origin, copies = [], [], np.arange(len(pairs), dtype=np.int64)
        for ends in bodies:  # a class after the other
            for k, (_, connectors) in enumerate(pairs):
                if names is None:
                    merged += [connectors[j] for j, _ in ends]
                else:
                    named = names[k]
                    merged += [
                        _shallow_copy(connectors[j], "bodies", (named[a], named[b]))
                        for j, (a, b) in ends
                    ]
            index = np.array([j for j, _ in ends], np.int64)
            origin.append(np.stack(np.broadcast_arrays(copies[:, None], index), axis=-1))
        return merged, np.concatenate(origin).reshape(-1, 2)

    @staticmethod
    def _merged_mechanism(
        pairs: list[Member], ground: str, names: list[dict[str, str]]
    ) -> Mechanism:
        """The bodies of every copy, renamed (``names``: :meth:`_names`), under the shared
        ground (copy 0 for the rest)."""
        first = pairs[0][0]
        moving = first.moving_bodies  # every copy's (:meth:`_check`)
        bodies = {ground: first.bodies[ground]}
        for (mechanism, _), named in zip(pairs, names):
            own = mechanism.bodies
            for name in moving:
                new = named[name]
                bodies[new] = _shallow_copy(own[name], "name", new)
        return Mechanism(
            bodies,
            first.flexures,
            ground,
            first.material,
            names[0][first.target_body],
            first.target_point,
            first.source,
        )

    @staticmethod
    def _combine(weights, states: np.ndarray) -> np.ndarray:
        """sum(w_i q_i) state after state, elementwise: BLAS's product of the weights and the
        states sums each coordinate's terms in an order that depends on how many
        coordinates there are (its vector kernels), which would make a copy's prediction
        depend on the batch's size."""
        out = weights[0] * states[0]
        for w, state in zip(weights[1:], states[1:]):
            out += w * state
        return out

    def _copy_numbering(self) -> list[np.ndarray]:
        """Where each copy's coordinates (its own System's numbering) lie in the batch's."""
        if self.uniform:
            return self._uniform_numbering()
        poses = [(i, body) for body, i in self.template.body_index.items()]
        copy_dofs = [np.empty(self._own(k).n_dofs, np.int64) for k in range(self.n_copies)]
        for k, named in enumerate(self.copy_names):
            for i, body in poses:
                j = self.body_index[named[body]]
                copy_dofs[k][3 * i : 3 * i + 3] = range(3 * j, 3 * j + 3)
        for m, (k, j) in enumerate(self.origin_table.tolist()):
            copy_dofs[k][self._own(k).local_to_global[j][6:]] = self.local_to_global[m][6:]
        return copy_dofs

    def _uniform_numbering(self) -> list[np.ndarray]:
        """:meth:`_copy_numbering` of copies all numbered as copy 0, as one table (copies, n):
        each copy's bodies' poses, then the internal coordinates of each of its connectors."""
        template, count = self.template, self.n_copies
        per_copy = len(template.body_index)  # copy k's bodies: the batch's k b .. (k + 1) b - 1
        table = np.empty((count, template.n_dofs), np.int64)
        table[:, : 3 * per_copy] = np.arange(count)[:, None] * 3 * per_copy + np.arange(
            3 * per_copy
        )
        sizes = np.diff(self.connector_offsets) - 6  # each connector's internal coordinates
        if sizes.any():
            origin = self.origin_table
            per = np.repeat(np.arange(sizes.size), sizes)  # the connector of each
            offset = np.arange(per.size) - np.repeat(np.cumsum(sizes) - sizes, sizes)
            batch = self.all_dofs[np.asarray(self.connector_offsets[:-1])[per] + 6 + offset]
            own_start = np.asarray(template.connector_offsets[:-1]) + 6
            own = template.all_dofs[own_start[origin[per, 1]] + offset]
            table[origin[per, 0], own] = batch
        self._copy_table = table
        return list(table)

    def tangent_ordering(self) -> np.ndarray | None:
        """The copies one after the other, each in its own band order.

        A copy whose own tangent is banded keeps its order (its block is
        then factorised with the arithmetic of the copy alone); copies all
        alike whose own tangent is dense take the reverse Cuthill-McKee order
        of copy 0's pattern. Either way each copy's block is a contiguous
        diagonal block of the band (:meth:`copy_unstable` reads it). Copies
        of different sizes with dense tangents of their own: None (the
        layout's order).
        """
        self.copy_dofs = self._copy_numbering()
        if self.uniform:
            template = self.template
            if template.layout.kind == "banded":
                perm = template.layout.perm
            else:
                from scipy.sparse.csgraph import reverse_cuthill_mckee

                n = template.n_dofs
                pattern = (template.pattern_rows, template.pattern_cols)
                graph = sp.csr_matrix((np.ones(pattern[0].size), pattern), shape=(n, n))
                perm = reverse_cuthill_mckee(graph, symmetric_mode=True).astype(np.int64)
            #: the band order of each copy's block (of the copy's own unknowns)
            self._tangent_order = perm
            return self._copy_table[:, perm].ravel()
        if any(self._own(k).layout.kind != "banded" for k in range(self.n_copies)):
            return None
        return np.concatenate(
            [dofs[self._own(k).layout.perm] for k, dofs in enumerate(self.copy_dofs)]
        )

    def _number_copies(self) -> None:
        """The maps between copies and batch, and every per-copy scale."""
        if self.copy_dofs is None:
            self.copy_dofs = self._copy_numbering()
        copy_dofs = self.copy_dofs
        dof_copy = np.empty(self.n_dofs, np.int64)
        if self._copy_table is not None:
            dof_copy[self._copy_table] = np.arange(self.n_copies)[:, None]
        else:
            for k, dofs in enumerate(copy_dofs):
                dof_copy[dofs] = k
        self.dof_copy = dof_copy
        # each distinct mechanism's size, target body (its index among a copy's bodies) and
        # target offsets (mm), read once; copy k's bodies are the batch's k b .. (k + 1) b - 1
        rows: dict[int, int] = {}
        row = np.empty(self.n_copies, np.int64)
        table = []
        own_bodies = self.template.body_index
        for k, (mechanism, _) in enumerate(self.members):
            r = rows.get(id(mechanism))
            if r is None:
                r = rows[id(mechanism)] = len(table)
                body = mechanism.target_body
                rx, ry = (mechanism.target_point - mechanism.bodies[body].reference).tolist()
                tx, ty = mechanism.target_point.tolist()
                table.append((mechanism.size(), own_bodies[body], rx, ry, tx, ty))
            row[k] = r
        found = np.array(table, float)[row]
        sizes = np.ascontiguousarray(found[:, 0])
        self.copy_sizes = sizes
        self.force_scale = np.where(self.is_rotation, 1.0 / sizes[dof_copy], 1.0)
        self._coordinate_scale = np.where(self.is_rotation, 1.0, sizes[dof_copy])
        self._by_copy = np.argsort(dof_copy, kind="stable")
        self._copy_starts = np.searchsorted(dof_copy[self._by_copy], np.arange(self.n_copies))
        body_copy = dof_copy[3 * np.arange(len(self.body_index))]
        self._bodies_by_copy = np.argsort(body_copy, kind="stable")
        self._body_starts = np.searchsorted(
            body_copy[self._bodies_by_copy], np.arange(self.n_copies)
        )
        target = np.arange(self.n_copies) * len(own_bodies) + found[:, 1].astype(np.int64)
        self._target_dof = 3 * target
        self._target_geometry = found[:, 2:].T  # rel x, rel y, rest x, rest y (mm)
        self._blocks: tuple | None = None  # see _block_maps
        self.kept = np.zeros(self.layout.size)
        self._rest: np.ndarray | None = None  # see initial_state

    @cached_property
    def slot_copy(self) -> np.ndarray:
        """The copy each value slot of the tangent storage belongs to (``n_copies`` for a slot no
        entry uses), made on first use: copies that take part in a solve all together never
        ask."""
        slot_copy = np.full(self.layout.size, self.n_copies, np.int64)
        used = self.layout.slots >= 0
        slot_copy[self.layout.slots[used]] = self.dof_copy[self.pattern_rows[used]]
        return slot_copy

    def initial_state(self) -> np.ndarray:
        """Every copy's undeformed configuration (:meth:`System.initial_state` in its own
        numbering: bodies at their reference points, connectors' internal coordinates at
        rest), found once for the copies of one mechanism and merged (a new array)."""
        if self._rest is None:
            own: dict[tuple[int, int], np.ndarray] = {}
            states = []
            for k, (mechanism, connectors) in enumerate(self.members):
                key = (id(mechanism), id(connectors))
                if key not in own:
                    numbering = self._own(k)
                    q = np.zeros(numbering.n_dofs)
                    for b, i in numbering.body_index.items():
                        q[3 * i : 3 * i + 2] = mechanism.bodies[b].reference
                    for c, idx in zip(connectors, numbering.local_to_global):
                        q[idx[6:]] = c.initial_internal()
                    own[key] = q
                states.append(own[key])
            self._rest = self.merge(states)
        return self._rest.copy()

    # --- between copies and batch ---------------------------------------
    def merge(self, states: Sequence[np.ndarray]) -> np.ndarray:
        """The batch's coordinates from each copy's (its own numbering)."""
        q = np.empty(self.n_dofs)
        if self._copy_table is not None:  # every copy numbered as copy 0: one table
            q[self._copy_table] = np.array(states, float).reshape(self._copy_table.shape)
            return q
        for dofs, state in zip(self.copy_dofs, states):
            q[dofs] = state
        return q

    def split(self, q: np.ndarray, k: int) -> np.ndarray:
        """Copy k's coordinates, in its own numbering, from the batch's."""
        return q[self.copy_dofs[k]]

    def copy_targets(self, states: np.ndarray) -> tuple[np.ndarray, ...]:
        """:meth:`System.target` of every copy at every state: dx, dy (mm) and rotation (rad),
        each (states, copies)."""
        dof = self._target_dof
        x, y, theta = states[:, dof], states[:, dof + 1], states[:, dof + 2]
        rx, ry, tx, ty = self._target_geometry
        c, s = np.cos(theta), np.sin(theta)
        return (x + (c * rx - s * ry)) - tx, (y + (s * rx + c * ry)) - ty, theta

    def batch_loads(self, cases: Sequence[LoadCase]) -> Loads:
        """Every copy's dead loads of its case (one per copy), in the batch's numbering.

        The result's ``scale`` is an array: each copy's own load scale (N),
        which its residual is relative to.
        """
        template, rows, parts = self.template, {}, []  # the loads of a case on a copy
        row = np.empty(self.n_copies, np.int64)  # each copy's among parts
        for k, ((mechanism, connectors), case) in enumerate(zip(self.members, cases)):
            key = (id(case), id(mechanism), id(connectors))  # copies of one mechanism and case
            r = rows.get(key)
            if r is None:
                r = rows[key] = len(parts)
                reference = {b: body.reference for b, body in mechanism.bodies.items()}
                parts.append(
                    case_loads(case, template.pose_dofs, reference, mechanism.size(), connectors)
                )
            row[k] = r
        # the copies' bodies' poses in the batch (each copy's own numbering is copy 0's)
        poses = (
            self._copy_table[:, : 3 * len(template.body_index)]
            if self._copy_table is not None
            else np.array([dofs[: 3 * len(template.body_index)] for dofs in self.copy_dofs])
        )

        def renumbered(local: list[np.ndarray]) -> np.ndarray:
            """Each copy's load dofs in its own numbering (parts' ``local``) in the batch's,
            copy after copy (-1: the ground)."""
            if len({p.shape for p in local}) == 1:  # as many loads on every copy: one table
                own = np.stack(local)[row].reshape(self.n_copies, -1)
                at = np.take_along_axis(poses, np.maximum(own, 0), axis=1)
                return np.where(own >= 0, at, -1).ravel()
            return np.concatenate(
                [np.where(local[r] >= 0, poses[k][local[r]], -1).ravel() for k, r in enumerate(row)]
            )

        def in_order(values: list[np.ndarray]) -> np.ndarray:
            """Each copy's part's ``values`` (parts' own), copy after copy, flat."""
            if len({v.shape for v in values}) == 1:
                return np.stack(values)[row].ravel()
            return np.concatenate([values[r].ravel() for r in row.tolist()])

        loads = Loads(
            renumbered([p.dofs for p in parts]).reshape(-1, 3),
            in_order([p.forces for p in parts]).reshape(-1, 2),
            in_order([p.rels for p in parts]).reshape(-1, 2),
            renumbered([p.moment_dofs for p in parts]).astype(np.int64),
            in_order([p.moments for p in parts]),
            np.array([p.scale for p in parts])[row],
        )
        loads.vectorise()  # the same arithmetic in a batch of any size
        return loads

    # --- per-copy versions of the core's measures -----------------------
    def copy_residuals(self, grad: np.ndarray, loads: Loads) -> np.ndarray:
        """:meth:`System.residual` of every copy (dimensionless), from the batch's gradient."""
        scaled = np.abs(grad * self.force_scale)[self._by_copy]
        return np.maximum.reduceat(scaled, self._copy_starts) / loads.scale

    def copy_steps(self, du: np.ndarray) -> np.ndarray:
        """The largest scaled correction of every copy (lengths / size, angles)."""
        return np.maximum.reduceat(np.abs(self.scaled(du))[self._by_copy], self._copy_starts)

    def motion_ratios(self, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
        """:meth:`System.motion_ratio` of every copy (> 1: a body moved too far)."""
        s, poses = self.settings, 3 * len(self.body_index)
        d = (q1[:poses] - q0[:poses]).reshape(-1, 3)[self._bodies_by_copy]
        rotation = np.maximum.reduceat(np.abs(d[:, 2]), self._body_starts)
        translation = np.maximum.reduceat(np.hypot(d[:, 0], d[:, 1]), self._body_starts)
        return np.maximum(
            rotation / s.max_rotation_step,
            translation / (s.max_translation_step * self.copy_sizes),
        )

    def motion_ratio(self, q0: np.ndarray, q1: np.ndarray) -> float:
        """The largest of :meth:`motion_ratios` (the batch moves as far as its farthest copy)."""
        return float(self.motion_ratios(q0, q1).max())

    def refusals(
        self, q: np.ndarray, loads: Loads, factor: float, among: np.ndarray
    ) -> dict[int, str]:
        """The copies (of ``among``) whose connectors refuse state q, with the reason.

        Each is assembled alone (a failed batch assembly does not say which copy refused).
        """
        found = {}
        for k in np.flatnonzero(among).tolist():
            system = self.copy_system(k)
            try:
                system.assemble(self.split(q, k), self.copy_loads(k), factor)
            except (ValueError, FloatingPointError) as exc:
                found[k] = str(exc)
        return found

    def copy_unstable(self, q: np.ndarray, tangent, factor: float, among: np.ndarray) -> np.ndarray:
        """Which copies of ``among`` are at an unstable equilibrium (bool per copy).

        The inertia of a block-diagonal tangent is the sum of its blocks',
        and a stable block has as many negative eigenvalues as multipliers:
        when the whole tangent has no more, every copy is stable (one count,
        the common case). Otherwise each copy is judged alone on its tangent
        at its state.
        """
        unstable = np.zeros(self.n_copies, bool)
        if self._block_maps() is not None:
            if self.n_multipliers == 0 and tangent.positive_definite():
                return unstable
            unstable = self._block_inertia(tangent, among) > 0
            for k in np.flatnonzero(unstable).tolist():  # as alone: judged where its rest is
                unstable[k] = self.copy_system(k).judges_stability()
            return unstable
        negative = self.instability(tangent)
        if negative is None or negative <= 0:
            return unstable
        for k in np.flatnonzero(among).tolist():
            system = self.copy_system(k)
            _, _, own = system.assemble(self.split(q, k), self.copy_loads(k), factor)
            unstable[k] = system.unstable(own)
        return unstable

    def copy_blocks(self, into: np.ndarray, source: np.ndarray, copies: np.ndarray) -> None:
        """Copy the tangent values of the copies ``copies`` (bool per copy) from storage
        ``source`` into storage ``into``."""
        if copies.all():
            np.copyto(into, source)
        elif copies.any():
            at = np.append(copies, False)[self.slot_copy]
            into[at] = source[at]

    def _block_maps(self) -> tuple | None:
        """Where each copy's diagonal block lies in the band (built on first use), or None
        when the copies are not all alike in band storage: copy k's block is the band's
        columns k m .. k m + m - 1 (m unknowns a copy), its entries (i, j), j - i <= b."""
        if self._blocks is None and self.uniform and self.layout.kind == "banded":
            m, b = self.template.n_dofs, self.layout.b
            i = np.concatenate([np.arange(m - d) for d in range(min(b, m - 1) + 1)])
            j = np.concatenate([np.arange(d, m) for d in range(min(b, m - 1) + 1)])
            columns = (np.arange(self.n_copies) * m)[:, None] + j[None, :]
            multipliers = sum(c.n_multipliers for c in self.template.connectors)
            self._blocks = (m, i, j, b + i - j, columns, multipliers)
        return self._blocks

    def _dense_blocks(self) -> BlockMaps | None:
        """Where copies all alike whose own tangents are dense have their blocks in the band
        and their unknowns in the batch, each block in its copy's own numbering; None for
        other batches."""
        if not (self.uniform and self.template.layout.kind == "dense"):
            return None
        if self.layout.kind != "banded":
            return None
        own = np.argsort(self._tangent_order)  # a copy's own unknown p: its block's row own[p]
        return block_maps(own, self.layout.b, self._copy_table)

    def _block_inertia(self, tangent, among: np.ndarray) -> np.ndarray:
        """The negative eigenvalues beyond its multipliers of every copy of ``among`` (0 for
        the others), from its diagonal block, by the kernel its own tangent counts with.

        A copy whose own tangent is dense is judged as its own System judges
        it: the block in the copy's own numbering, the pivots of its
        Bunch-Kaufman LDL^T counted by the one rule
        (:meth:`~flexval.reducedmodels.tangent.DenseTangent.negative_eigenvalues`),
        every block of the batch in one compiled loop
        (:meth:`~flexval.reducedmodels.blocktangent.BlockTangent.copy_negative`:
        a saddle point's tangent is one already, factorised for its solves).
        A larger copy, banded alone, is its own band in the batch's (the
        copies are numbered in their own orders, one after the other, with
        the same half-bandwidth), counted by
        :func:`~flexval.reducedmodels.stability.band_count` as its own
        banded tangent counts it. Not judged counts as stable, as alone.
        """
        m, _, _, _, _, multipliers = self._block_maps()
        chosen = np.flatnonzero(among)
        negative = np.zeros(self.n_copies, np.int64)
        if self._dense is not None:
            if not isinstance(tangent, BlockTangent):
                flat = tangent.storage.ravel(order="F")  # the layout's flat storage
                tangent = BlockTangent(flat, tangent.perm, tangent.b, self._dense)
            counts = tangent.copy_negative()[chosen]
            negative[chosen] = np.where(counts >= 0, counts - multipliers, 0)  # -1: not finite,
            return negative  # not judged (as its own System's check)
        band = np.asarray(tangent.storage)
        for c in chosen.tolist():
            count = stability.band_count(band[:, c * m : (c + 1) * m])
            negative[c] = count - multipliers if count is not None else 0
        return negative

    def use_loads(self, cases: Sequence[LoadCase]) -> Loads:
        """:meth:`batch_loads` of ``cases`` (kept for per-copy checks); keeps the rest tangent."""
        self._cases = list(cases)
        loads = self.batch_loads(cases)
        self.kept = self.assemble_storage(self.initial_state(), loads, 0.0)[2]
        return loads

    def copy_loads(self, k: int) -> Loads:
        """Copy k's loads of its case in its own numbering (for a check of the copy alone)."""
        return self.copy_system(k).loads(self._cases[k])


BATCH_UNKNOWNS = 40_000
"""Most unknowns of one batch (larger sets of copies are traced as several): the band of a
batch this size, some 10 MB with the factor, stays in the processor's caches. Cost per path
on the open chain f+ (2-core machine): beam:100 3.9, 3.7, 4.1 ms in batches of 25, 50, 100
copies (23,000 to 91,000 unknowns), beam:20 0.84, 0.83, 1.02 ms in batches of 100, 250, 500
(19,000 to 93,000), dcmm:1 0.19, 0.21, 0.22 ms in batches of 250, 1000, 4000 (2,000 to
36,000)."""


SOLO_UNKNOWNS = 500
"""Most unknowns of a copy that :func:`run_batch` traces in a batch with others (copies with
more are traced one by one, each by its family's own runner): a copy's own band is then wide
enough that sharing the iteration saves little, and copies that part ways cost more than
that. Open chain f+, 2-core machine: beam:100 (900 unknowns) runs 1.15x faster batched than
alone with identical copies but 0.84x with sections drawn from N(1, 0.02)
(``benchmarks/bench_batch.py --spread 0.02``); beam:20 (180 unknowns) 2.6x and 1.3x."""


def _shallow_copy(item, attribute: str, value):
    """A shallow copy of ``item`` (a connector, a frozen dataclass) with ``attribute`` set.

    What ``copy.copy`` and then setting the attribute make of an object whose
    state is its ``__dict__``, without copy's generic protocol (a fifth of
    the time; a batch renames every copy's bodies and connectors).
    """
    new = object.__new__(type(item))
    state = new.__dict__  # written directly: a frozen dataclass's __setattr__ refuses
    state.update(item.__dict__)
    state[attribute] = value
    return new


def _parts(member: System | Member) -> Member:
    """A copy's mechanism and connectors, given as a System or as the pair."""
    return (member.mechanism, member.connectors) if isinstance(member, System) else member


def _unknowns(member: System | Member) -> int:
    """The unknowns of one copy: its bodies' poses and its connectors' internal coordinates."""
    mechanism, connectors = _parts(member)
    return 3 * len(mechanism.moving_bodies) + sum(c.n_internal for c in connectors)


@contextmanager
def collection_paused() -> Iterator[None]:
    """Python's cyclic garbage collector paused within the block (as it was, after it).

    A batch creates some ten small objects per copy and level (renamed
    connectors, numbering maps, each path's lists and dicts); every 700 of
    them start a collection, which scans all the batch's live objects as they
    age: a third of a ``dcmm:1`` batch's time (1000 copies, open chain f+,
    measured). Reference counting still frees what a batch drops; cycles
    wait for the next collection after the block.
    """
    paused = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if paused:
            gc.enable()


class _Start(NamedTuple):
    """A reported point of a batch where some of its copies go on as a batch of their own."""

    batch: BatchSystem
    all_points: list[PathPoint]
    carried: dict
    count: int
    positions: list[int]
    """The copies' places in ``batch``, in the order of the new batch."""

    def take(self, batch: BatchSystem) -> np.ndarray:
        """The index, in the old batch's numbering, of each unknown of ``batch``."""
        take = np.empty(batch.n_dofs, np.int64)
        for dofs, j in zip(batch.copy_dofs, self.positions):
            take[dofs] = self.batch.copy_dofs[j]
        return take

    def points(self, take: np.ndarray) -> list[PathPoint]:
        """The points up to the start, in the new batch's numbering (as its own would be)."""
        n, chosen = self.batch.n_copies, self.positions
        return [
            PathPoint(
                p.state[take],
                p.factor,
                np.broadcast_to(p.iterations, (n,))[chosen],
                None,
                p.step,
                Counters(
                    np.broadcast_to(p.counters.newton_iterations, (n,))[chosen],
                    p.counters.step_cuts,
                    p.counters.substeps,
                ),
                p.bifurcations,
            )
            for p in self.all_points[: self.count]
        ]


class _Group(NamedTuple):
    """Copies to trace as one batch: from rest, or from where they left another batch."""

    copies: list[int]
    start: _Start | None = None


DEAD_WEIGHT = 0.25
"""Share of a batch's copies that may have left it before the rest go on as a new batch (from
the point just reached), for copies of at least :data:`REBUILD_UNKNOWNS` unknowns: a copy that
left still takes its place in every assembly and factorisation of its batch, while a new
batch costs its build once."""
REBUILD_UNKNOWNS = 16
"""Fewest unknowns of a copy for which a batch sheds the copies that left it
(:data:`DEAD_WEIGHT`): below, a dead copy's share of an iteration costs less than building
the new batch. Open chain f+, 1000 copies with sections drawn from N(1, 0.02), CPU time per
path with and without shedding: dcmm:1 (9 unknowns) 0.35 and 0.32 ms, dcmm:2 (18) 0.48 and
0.47, prbm (21) 0.44 and 0.47, dcmm:3 (27) 0.61 and 0.63, beam:20 (180) 1.44 and 1.74."""


def _dead_weight(active: np.ndarray, unknowns: int) -> bool:
    """Whether a batch of copies of ``unknowns`` unknowns, ``active`` still in it, carries too
    many that left (:data:`DEAD_WEIGHT`, :data:`REBUILD_UNKNOWNS`)."""
    dead = active.size - int(np.count_nonzero(active))
    return (
        unknowns >= REBUILD_UNKNOWNS
        and 0 < dead < active.size
        and dead >= DEAD_WEIGHT * active.size
    )


@collection_paused()
def trace_batch(
    members: Sequence[System | Member],
    cases: Sequence[LoadCase],
    levels: int | None = None,
    model: str = "",
    scene: str = "",
    settings: dict | None = None,
) -> list[LoadPath | SolverError]:
    """The load-control paths of many copies, traced together where they agree.

    Parameters
    ----------
    members : sequence of System or (Mechanism, connectors)
        The copies (see :class:`BatchSystem`).
    cases : sequence of LoadCase
        Each copy's load case; all must request the same load factors
        (``levels`` equal steps, default each case's own).
    levels, model, scene, settings :
        As for :func:`flexval.reducedmodels.recorder.solve_path`.

    Returns
    -------
    list of LoadPath or SolverError
        Per copy, in order: its path, or the error its solo run raises. The
        copies that leave a batch by a vote go on together as a batch of
        their own from the last reported level they shared; the copies of a
        batch that cannot go on are each traced alone from rest. Every copy
        is traced by the batch's arithmetic, so its
        path does not depend on which copies it was traced with (a sweep
        gives the same rows whatever its task sizes). Each path's
        ``seconds`` is its share of the wall time of every batch it was
        traced in (a batch's time split evenly among its copies, so the
        paths' seconds add up to the whole), ``stats["batch"]`` the number
        of copies its last batch recorded.
    """
    keep_freed_memory()
    distinct = {id(case): case for case in cases}.values()  # each case once
    factors = [case.factors(levels) for case in distinct]
    if any(not np.array_equal(f, factors[0]) for f in factors):
        raise ValueError("the copies' load cases request different load factors")
    size = max(1, BATCH_UNKNOWNS // max(_unknowns(members[0]), 1)) if members else 1
    if len(members) > size:
        return [
            path
            for start in range(0, len(members), size)
            for path in trace_batch(
                members[start : start + size],
                cases[start : start + size],
                levels,
                model,
                scene,
                settings,
            )
        ]
    results: list[LoadPath | SolverError | None] = [None] * len(members)
    groups = [_Group(list(range(len(members))))]  # copies to trace as one batch, in turn
    spent = np.zeros(len(members))  # each copy's share of the batches it was traced in, s
    while groups:
        group = groups.pop(0)
        copies = group.copies
        t0 = time.perf_counter()
        batch = BatchSystem([members[k] for k in copies])
        loads = batch.use_loads([cases[k] for k in copies])
        stepping = LoadControl(factors[0], batch)
        unknowns = batch.n_dofs // len(copies)
        points: list[PathPoint] = []
        shared: list[tuple[dict, int]] = []  # at each point: load control's snapshot, points
        resume = None
        if group.start is not None:  # go on from the point where these copies left a batch
            take = group.start.take(batch)
            points = group.start.points(take)
            stepping.resume(group.start.carried, take, loads)
            shared.append((stepping.snapshot(), len(points)))
            resume = points[-1].counters
        left_at = np.full(len(copies), -1)  # the snapshot each copy that left goes on from
        active = stepping.active.copy()
        failure = None
        try:
            for point in trace(batch, loads, stepping, stepping.newton, resume):
                left_at[active & ~stepping.active] = len(shared) - 1
                points.append(point)
                shared.append((stepping.snapshot(), len(points)))
                active = stepping.active.copy()
                if not stepping.finished() and _dead_weight(active, unknowns):
                    left_at[active] = len(shared) - 1  # the rest go on without the dead weight
                    stepping.leave(active)
                    active[:] = False
                    break
        except TraceFailure as exc:
            failure = exc
        left_at[active & ~stepping.active] = len(shared) - 1
        group_cases = [cases[k] for k in copies]
        if failure is not None and (len(copies) > 1 or group.start is not None):
            # each copy alone from rest: its own way to fail, as its solo run meets it
            spent[copies] += (time.perf_counter() - t0) / len(copies)
            groups += [_Group([k]) for k in copies]
            continue
        kept = [0] if failure is not None else np.flatnonzero(stepping.active).tolist()
        paths = record_batch(batch, points, kept, group_cases, model, scene, settings, failure)
        spent[copies] += (time.perf_counter() - t0) / len(copies)
        seconds = spent[copies].tolist()
        for j, path in zip(kept, paths):
            recorded = path.path if isinstance(path, SolverError) else path
            recorded.seconds = seconds[j]
            recorded.stats["batch"] = len(kept)
            results[copies[j]] = path
        for where in np.unique(left_at[~stepping.active]).tolist():
            gone = np.flatnonzero(~stepping.active & (left_at == where)).tolist()
            gone = [j for j in gone if results[copies[j]] is None]
            if where < 0:  # their first solve failed: each from rest, alone
                groups += [_Group([copies[j]]) for j in gone]
            elif gone:  # on together from the last point they shared
                start = _Start(batch, points, *shared[where], gone)
                groups.append(_Group([copies[j] for j in gone], start))
    return results


RUN_FAILURES = (
    SolverError,
    SceneError,
    ArithmeticError,
    ValueError,
    RuntimeError,
    np.linalg.LinAlgError,
)
"""What a model's run may raise for one copy and :func:`run_batch` returns as its result: the
solver's failure, a flexure the model cannot represent, a state or a tangent it cannot handle."""


@collection_paused()
def run_batch(
    mechanisms: Sequence[Mechanism],
    spec,
    cases: Sequence[LoadCase],
    levels: int | None = None,
    scene: str = "",
) -> list[LoadPath | Exception]:
    """Every copy's load path with the model ``spec``: its own mechanism and load case.

    A family that builds a System and traces it by load control (beams,
    DCMM, PRBM, the continuum) runs as :func:`trace_batch`; a linear family
    that builds connectors (``ee``: its path is the linear response of its
    connectors at rest) as
    :func:`~flexval.reducedmodels.linearbatch.linear_responses`, every copy's
    small solve and outputs at once; another linear family copy by copy
    through its own runner, and so does every copy of a batch whose cases
    prescribe a motion (displacement control). Copies given the same mechanism
    object share its connectors (built once). Each path's ``seconds`` includes its share of
    building the connectors.

    Parameters
    ----------
    mechanisms : sequence of Mechanism
        One per copy, all of one topology (bodies, flexures and pins alike).
    spec : ModelSpec
        The model (see :func:`flexval.reducedmodels.catalogue.parse_model`).
    cases : sequence of LoadCase
        One per copy, requesting the same load factors.
    levels, scene :
        As for the family's runner.

    Returns
    -------
    list of LoadPath or Exception
        Per copy, in order: its path, or what its solo run raises (one of
        :data:`RUN_FAILURES`: a copy the model cannot build, a solver
        failure). Copies are grouped by topology (bodies, connectors and
        their sizes, load factors), each group traced as its own batches.
    """
    from .catalogue import LINEAR

    keep_freed_memory()
    family = spec.model_family
    results: list[LoadPath | Exception | None] = [None] * len(mechanisms)

    def alone(k: int) -> None:
        try:
            path = family.trace(mechanisms[k], spec, cases[k], levels=levels, scene=scene)
        except RUN_FAILURES as exc:
            results[k] = exc
            return
        path.stats["batch"] = 1
        results[k] = path

    linear = family.has(LINEAR)
    driven = any(case.drive is not None for case in cases)  # a prescribed motion: each alone
    if family.system is None or (linear and family.connectors is None) or driven:
        for k in range(len(mechanisms)):
            alone(k)
        return results
    t0 = time.perf_counter()
    options = dict(spec.kwargs)
    built: dict[int, System | Member | Exception] = {}  # copies of one mechanism share it
    for m in mechanisms:
        if id(m) in built:
            continue
        try:
            built[id(m)] = (
                family.system(m, spec, None, **options)
                if family.connectors is None
                else (m, family.connectors(m, spec, **options))
            )
        except RUN_FAILURES as exc:
            built[id(m)] = exc
        member = built[id(m)]
        if not linear and not isinstance(member, Exception) and _unknowns(member) > SOLO_UNKNOWNS:
            for k in range(len(mechanisms)):  # copies this large: each alone (SOLO_UNKNOWNS)
                alone(k)
            return results
    for k, m in enumerate(mechanisms):
        if isinstance(built[id(m)], Exception):
            results[k] = built[id(m)]
    build = (time.perf_counter() - t0) / max(len(mechanisms), 1)
    groups: dict[tuple, list[int]] = {}  # copies that can share a batch, in order
    keys: dict[tuple[int, int], tuple] = {}
    for k in range(len(mechanisms)):
        if results[k] is None:
            member = built[id(mechanisms[k])]
            at = (id(member), id(cases[k]))  # copies of one mechanism and case share a key
            if at not in keys:
                keys[at] = _topology(member, cases[k].factors(levels))
            groups.setdefault(keys[at], []).append(k)
    for todo in groups.values():
        members = [built[id(mechanisms[k])] for k in todo]
        try:
            if linear:
                traced = linear_responses(members, [cases[k] for k in todo], levels, spec.id, scene)
                for path in traced:
                    if isinstance(path, LoadPath):
                        path.stats["batch"] = len(todo)
            else:
                traced = trace_batch(
                    members, [cases[k] for k in todo], levels, spec.id, scene, options
                )
        except RUN_FAILURES:  # a batch it cannot trace: each copy alone
            for k in todo:
                alone(k)
            continue
        for k, result in zip(todo, traced):
            if isinstance(result, LoadPath):
                result.seconds += build
            results[k] = result
    return results


def _topology(member: System | Member, factors: np.ndarray) -> tuple:
    """What copies must share to be one batch (:meth:`BatchSystem._check`) and to be traced
    through the same load factors: a key that groups the copies of a sweep's block whose
    flexures change kind, or whose meshes change size, into batches of their own."""
    mechanism, connectors = _parts(member)
    ground = mechanism.ground
    return (
        tuple(mechanism.bodies),
        ground,
        tuple(mechanism.bodies[ground].reference.tolist()),
        tuple((type(c), c.bodies, c.n_internal) for c in connectors),
        tuple(np.asarray(factors, float).tolist()),
    )
