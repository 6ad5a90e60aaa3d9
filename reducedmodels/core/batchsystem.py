"""A batch of copies of one mechanism and model: one System numbered copy after copy.

:class:`BatchSystem` puts N copies side by side in one
:class:`~flexval.reducedmodels.core.system.System`: their connectors join the
same groups (one compiled assembly for all), their tangent is block-diagonal
(one banded factorisation, whose band is one copy's), and every measure the
one Newton solve and load control take per copy (residual, correction, body
motions, stability) is given per copy. How the copies are traced together is
:mod:`flexval.reducedmodels.core.batch`'s.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from flexval.geometry import LoadCase, Mechanism

from . import stability
from .blocktangent import BlockLayout, BlockMaps, BlockTangent, block_maps
from .connector import Connector
from .loads import Loads
from .settings import SolverSettings
from .system import System, case_loads

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
            mechanism, connectors = copy_parts(member)
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

    def copy_layout(self) -> tuple[np.ndarray, list[Member]]:
        """:meth:`System.copy_layout` of the copies: :attr:`origin_table` and :attr:`members`."""
        return self.origin_table, self.members

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

    def batch_loads(self, cases: Sequence[LoadCase], known: dict | None = None) -> Loads:
        """Every copy's dead loads of its case (one per copy), in the batch's numbering.

        The result's ``scale`` is an array: each copy's own load scale (N),
        which its residual is relative to. ``known`` keeps each copy's loads in its own
        numbering (copy 0's) across the batches of one set of copies, keyed by the ids
        of its case, mechanism and connector objects (:func:`~.batch.trace_batch` passes
        one).
        """
        template, rows, parts = self.template, {}, []  # the loads of a case on a copy
        known = {} if known is None else known
        row = np.empty(self.n_copies, np.int64)  # each copy's among parts
        for k, ((mechanism, connectors), case) in enumerate(zip(self.members, cases)):
            key = (id(case), id(mechanism), id(connectors))  # copies of one mechanism and case
            r = rows.get(key)
            if r is None:
                r = rows[key] = len(parts)
                # a batch holds its own lists of the copies' connectors: known by the objects
                same = (id(case), id(mechanism), *map(id, connectors))
                part = known.get(same)
                if part is None:
                    reference = {b: body.reference for b, body in mechanism.bodies.items()}
                    part = known[same] = case_loads(
                        case, template.pose_dofs, reference, mechanism.size(), connectors
                    )
                parts.append(part)
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
        (:meth:`~flexval.reducedmodels.core.tangent.DenseTangent.negative_eigenvalues`),
        every block of the batch in one compiled loop
        (:meth:`~flexval.reducedmodels.core.blocktangent.BlockTangent.copy_negative`:
        a saddle point's tangent is one already, factorised for its solves).
        A larger copy, banded alone, is its own band in the batch's (the
        copies are numbered in their own orders, one after the other, with
        the same half-bandwidth), counted by
        :func:`~flexval.reducedmodels.core.stability.band_count` as its own
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

    def use_loads(self, cases: Sequence[LoadCase], known: dict | None = None) -> Loads:
        """:meth:`batch_loads` of ``cases`` (kept for per-copy checks); keeps the rest tangent."""
        self._cases = list(cases)
        loads = self.batch_loads(cases, known)
        self.kept = self.assemble_storage(self.initial_state(), loads, 0.0)[2]
        return loads

    def copy_loads(self, k: int) -> Loads:
        """Copy k's loads of its case in its own numbering (for a check of the copy alone)."""
        return self.copy_system(k).loads(self._cases[k])


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


def copy_parts(member: System | Member) -> Member:
    """A copy's mechanism and connectors, given as a System or as the pair."""
    return (member.mechanism, member.connectors) if isinstance(member, System) else member


def copy_unknowns(member: System | Member) -> int:
    """The unknowns of one copy: its bodies' poses and its connectors' internal coordinates."""
    mechanism, connectors = copy_parts(member)
    return 3 * len(mechanism.moving_bodies) + sum(c.n_internal for c in connectors)
