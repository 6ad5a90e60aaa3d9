"""Displaced Compliance Matrix Method, DCMM_n (paper Sects. 2.3 and 3).

Each flexure is cut into n equal sub-arcs joined by n - 1 intermediate rigid
bodies (the rigid cross-sections at the cuts). Each sub-arc is its diagonal
compliance diag(w b^2, w a^2, w) at its centre of elasticity C, along its
ellipse axes (Eqs. 1-5). It acts between the two bodies it joins in the
*displaced* configuration (Eqs. 9-14): the relative displacement of the
follower's material point at C, measured in the displaced frame of the
leading body (the one nearer to body i of flexure e_ij), and the relative
rotation, are the arguments of the quadratic energy

    E = 1/2 u^T diag(1/(w b^2), 1/(w a^2), 1/w) u,
    u = [Q^T R(theta_L)^T (p_F(C) - p_L(C)),  theta_F - theta_L].

Forces follow as its gradient, so the element is conservative and its
tangent is exact and symmetric. For a straight sub-arc (b = 0) the axial
compliance L/EA replaces the vanishing w b^2.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from types import ModuleType
from typing import NamedTuple

import numpy as np

from flexval.geometry import Flexure, Mechanism
from flexval.geometry.compliance import curve_compliance
from flexval.geometry.kinematics import rotate_xy

from ..core.bending import TERMS as BENDING_TERMS
from ..core.bending import centre_separation
from ..core.chains import NodeChains
from ..core.connector import Connector, KernelEndPass, Reasons
from ..core.geometrycache import per_centre_line
from ..core.inertia import MassPoints, line_density, rigid_pieces
from ..core.sections import ForceStack, SectionForces, column_stacks
from ..core.validity import (
    MAX_RELATIVE_ROTATION,
    MAX_STRAIN,
    SCREEN_MARGIN,
    bending_strain_reasons,
    rotation_reasons,
    stretch_reasons,
    sway_load,
)
from .stacks import (
    Stack,
    chain_layout,
    end_points,
    sample_points,
    samples_per_sub_arc,
    stack_tables,
)
from .subarcs import split_parts, sub_arcs

CHAIN_HALF_BANDWIDTH = 2 * 3 - 1
"""Half-bandwidth of a DCMM chain's tangent numbered body after body: a sub-arc couples the
three coordinates (x, y, theta) of two neighbouring bodies."""


@functools.cache
def dcmm_kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.dcmmkernel`; each kernel is compiled, or loaded
    from the on-disk cache, where it is first called, off the path's clock
    (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import dcmmkernel

    return dcmmkernel


class ChainGeometry(NamedTuple):
    """What a DCMM chain takes from its centre line and its end bodies alone (mm, rad), the
    same for every copy of a study over sections (arrays read-only, shared)."""

    refs: tuple[tuple[float, float], ...]
    """The chain's reference points: body a's, the cuts (chain order), body b's."""
    refs_array: np.ndarray
    cuts: np.ndarray
    """The cut bodies' reference points at rest, (n - 1, 2)."""
    arc_lengths: tuple[float, ...]
    sub_lengths: np.ndarray
    """The sub-arcs' lengths in chain order (a tuple and an array)."""
    end_rel: tuple[tuple[float, float], tuple[float, float]]
    """The flexure's ends' offsets from the end bodies' reference points, body a's first."""
    sample_tangent: np.ndarray
    """Each sample's section direction towards body b at rest, rad."""
    sample_rel: np.ndarray
    """Each sample's point at rest as offsets from its sub-arc's leading and following
    bodies, (samples, 4)."""


@per_centre_line
def chain_geometry(
    shape,
    n: int,
    forward: bool,
    samples: int,
    ref_a: tuple[float, float],
    ref_b: tuple[float, float],
) -> ChainGeometry:
    """The :class:`ChainGeometry` of the centre line ``shape`` cut into n sub-arcs of
    ``samples`` segments each, run from its start (``forward``) or its end, between bodies
    whose reference points are ``ref_a`` and ``ref_b`` (mm); kept per centre line."""
    parts = [part for part, _, _ in split_parts(shape, n)]
    if not forward:
        parts = parts[::-1]
    cuts = [tuple(end_points(p)[1 if forward else 0]) for p in parts[:-1]]
    refs = (ref_a, *cuts, ref_b)
    ends = list(end_points(shape))
    if not forward:
        ends = ends[::-1]  # body a's first
    end_rel = tuple((ex - rx, ey - ry) for (ex, ey), (rx, ry) in zip(ends, (ref_a, ref_b)))
    refs_array = np.array(refs)
    arc_lengths = tuple(p.length for p in parts)
    points, tangent = sample_points(shape, n, forward, samples)
    layout = chain_layout(n, forward, samples)
    sample_rel = (points[:, None] - refs_array[layout.sample_ends]).reshape(-1, 4)
    arrays = [refs_array, np.array(cuts).reshape(-1, 2), np.array(arc_lengths), sample_rel]
    for array in arrays:
        array.flags.writeable = False
    return ChainGeometry(
        refs,
        arrays[0],
        arrays[1],
        arc_lengths,
        arrays[2],
        end_rel,
        tangent,
        arrays[3],
    )


class DcmmConnector(Connector):
    """DCMM_n model of one flexure (a :class:`~flexval.reducedmodels.core.connector.Connector`).

    Internal coordinates are the poses of the n - 1 intermediate bodies,
    whose reference points are the cut points on the centre line.

    ``frame`` chooses the body whose displaced frame measures each element's
    relative displacement: ``"leader"`` (body i of e_ij, as the paper's Sect. 3
    states; the default) or ``"follower"`` (body j). The two agree for small
    relative rotations and as n grows, but DCMM_1 on the closed chain
    depends strongly on the choice (see the report's sensitivity table); the
    paper's closed-chain DCMM_1 figures are closer to ``"follower"``.
    """

    def __init__(self, flexure: Flexure, mechanism: Mechanism, n: int, frame: str = "leader"):
        if n < 1:
            raise ValueError(f"dcmm: number of sub-arcs must be >= 1, got {n}")
        if frame not in ("leader", "follower"):
            raise ValueError(f"dcmm: frame must be 'leader' or 'follower', got {frame!r}")
        if frame == "follower":  # measure in the displaced frame of body j of e_ij
            flexure = dataclasses.replace(flexure, bodies=flexure.bodies[::-1])
        self.name = flexure.name
        self.bodies = tuple(flexure.bodies)
        self.n_internal = 3 * (n - 1)
        # one compliance has no geometric stiffness for a straight flexure's sway, nor
        # a sub-arc's for its own
        self.sway_load = sway_load(flexure, mechanism, n)
        self.sway_span = "leaf" if n == 1 else "sub-arc"
        shape = flexure.shape
        subs = sub_arcs(flexure, mechanism.material, n)
        forward = flexure.start_body == self.bodies[0]  # chain runs start -> end
        if not forward:
            subs = subs[::-1]
        self._samples = samples_per_sub_arc(n, not flexure.section.is_uniform)
        self._layout = chain_layout(n, forward, self._samples)
        geometry = chain_geometry(
            shape,
            n,
            forward,
            self._samples,
            tuple(mechanism.bodies[self.bodies[0]].reference.tolist()),
            tuple(mechanism.bodies[self.bodies[1]].reference.tolist()),
        )
        refs = geometry.refs
        self._cuts, self._refs = geometry.cuts, geometry.refs_array
        self._arc_lengths, self.sub_lengths = geometry.arc_lengths, geometry.sub_lengths
        self.end_rel = geometry.end_rel
        self.sample_tangent, self.sample_rel = geometry.sample_tangent, geometry.sample_rel
        # each sub-arc's parameters of flexval.reducedmodels.kernels.dcmmkernel.sub_arc:
        # offsets of its centre of elasticity from its two bodies (mm), ellipse
        # axes, inverse compliances, and a calibrated notch hinge's bending kinematics
        bends = _bends(flexure, mechanism.material)
        parameters = []
        for (lx, ly), (fx, fy), sub in zip(refs, refs[1:], subs):
            ell, compliance = sub.ellipse, sub.compliance
            cx, cy = ell.center.tolist()
            parameters.append(
                [
                    cx - lx,
                    cy - ly,
                    cx - fx,
                    cy - fy,
                    *ell.axes.ravel().tolist(),
                    *(1.0 / c for c in compliance),
                    *(_bending_parameters(flexure, sub, forward) if bends else _NO_BENDING),
                ]
            )
        self.parameters = np.array(parameters)
        self._section = flexure.section
        # each sub-arc's bending and axial flexibility (chain order): how the chain's closure
        # shares a gap between its chords (chains.NodeChains)
        self._chord_flexibility = (
            np.array([sub.compliance[2] for sub in subs]),
            np.array([_axial_flexibility(flexure, mechanism.material, sub) for sub in subs]),
        )
        # each sub-arc's relative rotation limits (chain order, rad): the thinnest fibre's
        # strain (infinite for a uniform section) and, the screen's, the smallest of all
        self._strain_limits = [sub.strain_limit for sub in subs]
        self._turn_limits = [sub.turn_limit for sub in subs]
        self._turn_limit = min(self._turn_limits)
        self._centre_line, self._forward = shape, forward

    def mass_points(self, density: float) -> MassPoints:
        """The flexure's mass (density in t/mm^3) on the chain's bodies, as rigid pieces.

        Lumping rule: each body of the chain (the end bodies and the n - 1
        cut bodies) carries the flexure between the midpoints of its
        neighbouring sub-arcs (the half sub-arc next to an end body, the two
        halves on either side of a cut), rigidly, with that piece's exact
        mass, centre of mass and rotary inertia
        (:func:`flexval.reducedmodels.core.inertia.rigid_pieces`). Total mass, centre of
        mass and rotary inertia of the whole flexure are exact at rest. On a
        clamped-free beam f1 comes out above Euler-Bernoulli by 2.0 % at
        n = 1 and 3.6 % / n^2 as n grows (half of each sub-arc on each end
        cross-section, HRZ: -32 % / n^2), and the self-weight sag is off by
        exactly -1 / (6 n^2) in the linear limit (HRZ: +1 / (3 n^2)); see the
        documentation's frequency comparison, which also gives the cost (the closed
        chain's modes 2-4, where massless links get all their inertia from
        these pieces). ``dcmm:1`` has no cut body: the half next to the
        ground is lost to it, and a single sub-arc has one elastic mode per
        end motion, so only the first mode of each direction is represented
        (its second bending frequency is 39 % low on a cantilever).
        """
        n = len(self.sub_lengths)
        sub_length = self.sub_lengths[0]  # equal sub-arcs
        bounds = np.clip((np.arange(n + 2) - 0.5) * sub_length, 0.0, n * sub_length)
        mass, rel, rotary = rigid_pieces(
            self._centre_line,
            self._forward,
            bounds,
            self._refs,
            line_density(density, self._section),
        )
        dofs = np.vstack(
            [np.arange(3), 6 + np.arange(self.n_internal).reshape(-1, 3), np.arange(3, 6)]
        )
        return MassPoints(dofs, rel, mass, rotary)

    def initial_internal(self) -> np.ndarray:
        """Cut-point bodies at rest: (x, y, 0) each."""
        rest = np.zeros((len(self._cuts), 3))
        rest[:, :2] = self._cuts
        return rest.ravel()

    def internal_is_rotation(self) -> np.ndarray:
        """Every third internal coordinate is an angle."""
        return self._layout.is_rotation

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """Local (rows, cols) of the Hessian values :meth:`evaluate` returns: 36 per sub-arc."""
        return self._layout.rows, self._layout.cols

    @classmethod
    def group(cls, connectors) -> DcmmGroup:
        """The DCMM connectors of a run, evaluated in one compiled call (:class:`DcmmGroup`)."""
        return DcmmGroup(connectors)

    def evaluate(self, pose_a, pose_b, internal):
        """Energy (N mm), gradient over [pose_a, pose_b, internal] and the Hessian values.

        Each sub-arc's gradient is added onto its two bodies' coordinates in
        the sub-arcs' order; the Hessian values are the sub-arcs' in turn
        (see :meth:`hessian_pattern`).
        """
        layout = self._layout
        gradient, hessian = np.zeros(6 + self.n_internal), np.zeros(layout.values.size)
        energy = dcmm_kernels().assemble_sub_arcs(
            np.concatenate([pose_a, pose_b, internal]),
            layout.lead,
            layout.follow,
            self.parameters,
            layout.element_dofs,
            layout.values,
            gradient,
            hessian,
        )
        return energy, gradient, hessian

    def _points(self, pose_a, pose_b, internal) -> tuple[list, list[tuple[float, float]]]:
        """Chain poses and the polyline flexure end, cut points, flexure end (float pairs, mm).

        Plain floats: the validity monitor runs this at every load level, and
        for a few sub-arcs small numpy arrays cost more than the algebra.
        """
        chain = [pose_a.tolist(), *np.asarray(internal).reshape(-1, 3).tolist(), pose_b.tolist()]
        (xa, ya, ta), (xb, yb, tb) = chain[0], chain[-1]
        ea, eb = rotate_xy(ta, *self.end_rel[0]), rotate_xy(tb, *self.end_rel[1])
        points = [
            (xa + ea[0], ya + ea[1]),
            *((p[0], p[1]) for p in chain[1:-1]),
            (xb + eb[0], yb + eb[1]),
        ]
        return chain, points

    def validity(self, pose_a, pose_b, internal) -> list[str]:
        """Reasons: sub-arc chords longer than their arcs, relative rotations over the limits.

        A sub-arc's chord may shorten freely (bending) but not exceed the
        arc's length by more than the strain limit: its ends would have to be
        farther apart than the material allows. See :mod:`flexval.reducedmodels.core.validity`.
        """
        chain, points = self._points(pose_a, pose_b, internal)
        chords = [math.dist(p, r) for p, r in zip(points, points[1:])]
        turns = [f[2] - lead[2] for lead, f in zip(chain, chain[1:])]
        if max(c / a for c, a in zip(chords, self._arc_lengths)) - 1.0 <= MAX_STRAIN and all(
            abs(t) <= limit for t, limit in zip(turns, self._turn_limits)
        ):
            return []
        reasons = stretch_reasons(
            "sub-arc chord", np.array(chords), np.array(self._arc_lengths), one_sided=True
        ) + rotation_reasons("sub-arc", np.array(turns), MAX_RELATIVE_ROTATION)
        if self._turn_limit < MAX_RELATIVE_ROTATION:
            reasons += bending_strain_reasons(
                "sub-arc", np.array(turns), np.array(self._strain_limits)
            )
        return reasons

    def path_validity(self, states) -> Reasons:
        """:meth:`validity` at k states, screened in one vectorised pass
        (see :class:`DcmmGroup`)."""
        return DcmmGroup([self]).path_validity([[state] for state in states])[0]

    def shape(self, pose_a, pose_b, internal) -> np.ndarray:
        """Polyline through the flexure ends and the cut points, mm."""
        return np.array(self._points(pose_a, pose_b, internal)[1])

    def section_forces(
        self, pose_a, pose_b, internal, gradient: np.ndarray | None = None
    ) -> SectionForces:
        """Normal force (N) and bending moment (N mm) along the displaced sub-arcs.

        Each sub-arc's own generalised force (its gradient on its following
        body's pose) carried by statics to points of its displaced shape,
        :func:`~flexval.reducedmodels.dcmm.stacks.samples_per_sub_arc` segments each (more on
        a varying section): the displaced sub-arc is
        the blend (1 - w) x_leading + w x_following of the point carried
        rigidly by each of its bodies, w the fraction along the sub-arc (it
        leaves the leading body's cut and reaches the following body's; a
        cut, shared by two sub-arcs, is sampled once), and its sections turn
        with the same blend of the two bodies' rotations. ``gradient`` (a
        linear response's K0 dq) gives the flexure's end wrench instead,
        carried along every sub-arc.
        """
        group, state = DcmmGroup([self]), (pose_a, pose_b, internal)
        if gradient is not None:
            return group.section_forces([state], [gradient])[0]
        forces = group.path_section_forces([[state]])[0]
        return SectionForces(forces.at, forces.axial[0], forces.moment[0])

    def path_section_forces(self, states) -> SectionForces:
        """:meth:`section_forces` at k states (a load path), stacked (k, m), in one pass."""
        return DcmmGroup([self]).path_section_forces([[state] for state in states])[0]


CHAIN_PREDICTION_FROM = 10
"""Sub-arcs from which a DCMM chain's cut bodies are predicted and updated chord-wise
(:class:`DcmmChainConnector`): below, the coordinate-wise predictor costs less than the
iterations the chord-wise one saves (the paper paths, ``benchmarks/bench_ab.py``: 0.87x at
4 sub-arcs, 0.98x at 8, 1.10x at 10, 1.89x at 30)."""


class DcmmChainConnector(DcmmConnector):
    """A DCMM connector of many sub-arcs, whose cut bodies are predicted for the next load
    step and corrected by Newton as a chain of nearly inextensible chords
    (:class:`flexval.reducedmodels.core.chains.NodeChains`), as a beam's nodes are: extrapolated
    or corrected coordinate by coordinate, every chord that turns comes out stretched,
    and the axial stiffness of short sub-arcs turns that into forces far beyond the load
    (on the open chain's m+, dcmm:100 takes 60 Newton iterations this way, 3,652
    coordinate-wise)."""

    update_above = 1e-7
    """Newton corrections go through :meth:`update_internal` down to 1e-7 (scaled), as a
    beam's nodes do (:attr:`flexval.reducedmodels.beam.elements.BeamConnector.update_above`): the
    cut bodies are a chain of nearly inextensible chords too."""

    def predict_internal(self, states, weights, pose_a, pose_b) -> np.ndarray:
        """The cut bodies extrapolated in chord lengths and turns and the chain closed between
        the end bodies by its least-energy bending
        (:meth:`flexval.reducedmodels.core.chains.NodeChains.predict_internal`): extrapolated
        coordinate by coordinate, every turning chord comes out stretched, and the axial
        stiffness of short sub-arcs turns that into forces far beyond the load."""
        group = DcmmGroup([self])
        return group.predict_internal([[state] for state in states], weights, [(pose_a, pose_b)])

    def update_internal(self, old, new) -> np.ndarray:
        """The cut bodies after a Newton correction, chords turned instead of sheared
        (:meth:`flexval.reducedmodels.core.chains.NodeChains.update_internal`); equal to the
        linear update to first order, so Newton stays quadratic."""
        return DcmmGroup([self]).update_internal([old], [new])


def dcmm_connector(flexure: Flexure, mechanism: Mechanism, n: int, **options) -> DcmmConnector:
    """The DCMM connector of ``flexure`` with ``n`` sub-arcs: a :class:`DcmmChainConnector`
    from :data:`CHAIN_PREDICTION_FROM` sub-arcs."""
    kind = DcmmChainConnector if n >= CHAIN_PREDICTION_FROM else DcmmConnector
    return kind(flexure, mechanism, n, **options)


class DcmmGroup(KernelEndPass):
    """DCMM connectors evaluated together (:meth:`DcmmConnector.group`).

    Every sub-arc of the run is evaluated by one call of the compiled
    :func:`flexval.reducedmodels.kernels.dcmmkernel.assemble_sub_arcs`, which adds the
    results straight into the System's gradient and tangent storage
    (:meth:`assembler`), in the order of the connector-by-connector
    evaluation. A load path's validity and section forces are computed for
    all the connectors' sub-arcs and samples stacked (:class:`Stack`), in
    one set of array operations.
    """

    compiled = True

    def __init__(self, connectors):
        super().__init__(connectors)
        self._stack: Stack | None = None
        self._tables = stack_tables(
            tuple((len(c.parameters), c._forward, c._samples) for c in self.connectors)
        )
        self._chains = _node_chains(self.connectors)

    def predictor(self, gather: np.ndarray):
        """:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.predictor`: the chains'
        (:meth:`flexval.reducedmodels.core.chains.NodeChains.predictor`)."""
        return self._chains.predictor(gather)

    def updater(self, gather: np.ndarray):
        """:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.updater`: the chains'."""
        return self._chains.updater(gather)

    def predict_internal(self, past, weights, poses) -> np.ndarray:
        """Every connector's cut bodies predicted at once (see
        :meth:`DcmmConnector.predict_internal`)."""
        return self._chains.predict_internal(past, weights, poses)

    def update_internal(self, old, new) -> np.ndarray:
        """Every connector's cut bodies after a Newton correction at once (see
        :meth:`DcmmConnector.update_internal`)."""
        return self._chains.update_internal(old, new)

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of the connectors' Hessian values laid end to end (see the base class)."""
        return self._tables.hessian_rows, self._tables.hessian_cols

    def assembler(
        self, gather: np.ndarray, grad_dofs: np.ndarray, hess_slots: np.ndarray
    ) -> Callable[[np.ndarray, np.ndarray, np.ndarray], float]:
        """The compiled kernel adding every sub-arc into the System's gradient and tangent.

        See :meth:`ConnectorGroup.assembler`; a body's (or a cut's) three
        coordinates are consecutive in ``[q, ground pose]``, and the Hessian
        values are the sub-arcs' 36 in turn.
        """
        assemble_sub_arcs = dcmm_kernels().assemble_sub_arcs
        dofs = self._tables.element_dofs  # each sub-arc's bodies among the local coordinates
        fixed = (
            np.ascontiguousarray(gather[dofs[:, 0]], np.int64),
            np.ascontiguousarray(gather[dofs[:, 3]], np.int64),
            self.stack().parameters,
            np.ascontiguousarray(grad_dofs[dofs], np.int64),
            np.ascontiguousarray(hess_slots, np.int64).reshape(-1, 36),
        )

        def add(coordinates: np.ndarray, grad: np.ndarray, storage: np.ndarray) -> float:
            return assemble_sub_arcs(coordinates, *fixed, grad, storage)

        return add

    def stack(self) -> Stack:
        """The connectors' stack (built on first use)."""
        if self._stack is None:
            self._stack = Stack.of(self.connectors, self._tables)
        return self._stack

    def _end_pass(self, coordinates: np.ndarray) -> tuple[list[Reasons], np.ndarray, np.ndarray]:
        """The verdicts, and every sample's normal force and moment (k, samples), of the levels.

        ``coordinates`` (k, m): the connectors' local coordinates at each
        level (:meth:`ConnectorGroup.path_end_pass`), taken into the stack's
        chain of poses by one gather; local states are made only for the
        pairs the screen sends to the scalar check.
        """
        poses = coordinates[:, self._tables.pose_order].reshape(len(coordinates), -1, 3)
        verdicts = self._verdicts(poses, lambda: self.local_levels(coordinates))
        return (verdicts, *self._statics(poses))

    def path_validity(self, levels) -> list[Reasons]:
        """Each connector's :meth:`DcmmConnector.validity` at each level, screened in one pass.

        Every level's chord strains and relative rotations come from one
        compiled call (:func:`flexval.reducedmodels.kernels.dcmmkernel.chain_measures`);
        only (level, connector) pairs within
        :data:`~flexval.reducedmodels.core.validity.SCREEN_MARGIN` of a limit (or beyond)
        are judged by the scalar check, so the verdicts are its own.
        """
        return self._verdicts(self.stack().poses(levels), lambda: levels)

    def _verdicts(self, poses: np.ndarray, levels_of: Callable[[], list]) -> list[Reasons]:
        """:meth:`path_validity` from the stacked poses; ``levels_of()`` gives the local states."""
        stack, tables = self.stack(), self._tables
        strain, turn = dcmm_kernels().chain_measures(
            poses,
            tables.first,
            stack.end_rel,
            tables.sub_arc_body,
            stack.lengths,
            tables.sub_arc_start,
        )
        limits = np.array([c._turn_limit for c in self.connectors])
        near = ((strain > MAX_STRAIN - SCREEN_MARGIN) | (turn > limits - SCREEN_MARGIN)).T
        screened = near.any(axis=1).tolist()  # the connectors near a limit at some level
        levels = levels_of() if any(screened) else []
        valid = ((),) * len(poses)  # no reason at any level: one shared, immutable
        return [
            [c.validity(*states[j]) if flag else [] for states, flag in zip(levels, near[j])]
            if screen
            else valid
            for j, (c, screen) in enumerate(zip(self.connectors, screened))
        ]

    def path_section_forces(self, levels) -> list[SectionForces]:
        """Each connector's :meth:`DcmmConnector.section_forces` at k levels, stacked (k, m).

        Each sub-arc's own wrench (its gradient on its following body's
        pose) carried by statics to its samples: two compiled calls for all
        the levels and connectors.
        """
        return self._forces(self.stack().poses(levels))

    def _forces(self, poses: np.ndarray) -> list[SectionForces]:
        """:meth:`path_section_forces` from the stacked poses (k, bodies, 3)."""
        return self._split(*self._statics(poses))

    def _statics(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every sample's normal force (N) and bending moment (N mm), (k, samples), from the
        stacked poses (k, bodies, 3): each sub-arc's own wrench carried by statics."""
        stack, tables = self.stack(), self._tables
        kernels = dcmm_kernels()
        wrenches = kernels.sub_arc_wrenches(poses, tables.sub_arc_body, stack.parameters)
        return kernels.sample_statics(
            poses,
            wrenches,
            tables.sub_arc,
            tables.follow,
            tables.lead,
            tables.w,
            stack.rel,
            stack.tangent,
            tables.order,
        )

    def section_forces(self, states, gradients) -> list[SectionForces]:
        """Each connector's :meth:`DcmmConnector.section_forces` with a known gradient, in one pass.

        Each connector's end wrench (its gradient on body b's pose) carried
        along all its sub-arcs to its samples, every connector's samples in
        one compiled call.
        """
        stack, tables = self.stack(), self._tables
        wrenches = np.array([np.asarray(g, float)[3:6] for g in gradients])[None]
        axial, moment = dcmm_kernels().sample_statics(
            stack.poses([states]),
            wrenches,
            tables.connector,
            tables.last,
            tables.lead,
            tables.w,
            stack.rel,
            stack.tangent,
            tables.order,
        )
        return self._split(axial[0], moment[0])

    def _split(self, axial: np.ndarray, moment: np.ndarray) -> list[SectionForces]:
        """Each connector's section forces from the stack's (..., samples) in station order
        (slices: a path's or a state's few connectors; a batch's take :meth:`_stacks`)."""
        bounds = self._tables.sample_start
        return [
            SectionForces(c._layout.stations, axial[..., start:stop], moment[..., start:stop])
            for c, start, stop in zip(self.connectors, bounds, bounds[1:])
        ]

    def _stacks(self, axial: np.ndarray, moment: np.ndarray) -> list[ForceStack]:
        """The connectors' section forces from the stack's (k, samples), stacked by stations
        (:func:`~flexval.reducedmodels.core.sections.column_stacks`): connector j's samples are
        the columns ``sample_start[j]`` on, in station order."""
        of_layout: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # a batch's copies share one
        stations = []
        for c in self.connectors:
            found = of_layout.get(id(c._layout))
            if found is None:
                at = c._layout.stations
                found = of_layout[id(c._layout)] = (at, np.arange(at.size))
            stations.append(found)
        return column_stacks(axial, moment, stations, np.asarray(self._tables.sample_start[:-1]))


def _node_chains(connectors) -> NodeChains:
    """The chains of DCMM connectors laid end to end: each its flexure's end point on body a,
    its cut bodies, its end point on body b; a connector's local coordinates are [pose_a,
    pose_b, cuts] (3 each)."""
    node_dof, node_rel, attached, counts = [], [], [], []
    start = 0
    for c in connectors:
        cuts = c.n_internal // 3
        node_dof += [start, *(start + 6 + 3 * np.arange(cuts)).tolist(), start + 3]
        node_rel += [c.end_rel[0], *([(0.0, 0.0)] * cuts), c.end_rel[1]]
        attached += [True, *([False] * cuts), True]
        counts.append(cuts + 2)
        start += 6 + c.n_internal
    return NodeChains(
        np.array(node_dof, np.int64),
        np.array(node_rel, float).reshape(-1, 2),
        np.array(attached, bool),
        np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
        np.concatenate([c._chord_flexibility[0] for c in connectors]),
        np.concatenate([c._chord_flexibility[1] for c in connectors]),
    )


_NO_BENDING = (0.0,) * (2 + 2 * BENDING_TERMS)
"""A sub-arc's bending parameters where it has none (its axis t zero)."""


def _bends(flexure: Flexure, material) -> bool:
    """Whether ``flexure``'s sub-arcs take their bending kinematics
    (:mod:`flexval.reducedmodels.core.bending`): a calibrated notch hinge's (the material
    the correction gives it, :func:`flexval.reducedmodels.notchcorrection.corrected_material`,
    is ``shear_flexible``); plain Euler-Bernoulli hinges (``eb``) and every other flexure
    keep the paper's element."""
    profile = flexure.section.profile
    return profile is not None and profile.kind == "notch" and material.shear_flexible


def _bending_parameters(flexure: Flexure, sub, forward: bool) -> tuple[float, ...]:
    """A straight sub-arc's axis at rest from its leading to its following body and the
    series of its centre separation (:func:`flexval.reducedmodels.core.bending.
    centre_separation`), run from its leading end: the chain runs from the flexure's start
    (``forward``) or from its end."""
    s0, s1 = (sub.start, sub.end) if forward else (sub.end, sub.start)
    start, end = (np.asarray(flexure.shape.point(s), float) for s in (s0, s1))
    axis = (end - start) / np.linalg.norm(end - start)
    a, b = centre_separation(flexure.section, float(s0), float(s1), BENDING_TERMS)
    return (*axis.tolist(), *a, *b)


def _axial_flexibility(flexure: Flexure, material, sub) -> float:
    """A sub-arc's integral of ds / (E A(s)), mm/N: length / EA for a uniform section, else
    the trace of its axial compliance integral (the tangent is a unit vector)."""
    section = flexure.section
    if section.is_uniform:
        return (sub.end - sub.start) / (material.youngs_modulus * section.area)
    part = curve_compliance(flexure.shape, section, material, sub.start, sub.end)
    return float(np.trace(part.axial))
