"""The connector contract: what a flexure (or joint) model gives the multibody core.

A connector joins two bodies ``bodies = (a, b)``. Its local coordinate vector
is ``[pose_a (3), pose_b (3), internal (n_internal)]``: the poses (x, y,
theta) of the two bodies (mm, mm, rad) and the connector's private internal
coordinates (beam nodes, continuum nodes, DCMM intermediate bodies, PRBM link
angles, Lagrange multipliers ...). It is conservative: :meth:`Connector.evaluate`
returns its energy, gradient and Hessian over those coordinates, and the core
assembles them. Every hook the core calls is declared here; the optional ones
have a documented default, so a minimal connector implements only
:meth:`~Connector.evaluate` and :meth:`~Connector.shape` (and sets ``name``,
``bodies`` and, if it has any, ``n_internal``).

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import scipy.sparse as sp

    from flexval.geometry import Section

    from .inertia import MassPoints
    from .sections import ForceStack, SectionForces

LocalState = tuple[np.ndarray, np.ndarray, np.ndarray]
Reasons = Sequence[Sequence[str]]
"""The validity monitor's reasons at each of a path's levels (an empty sequence: valid there;
a connector valid at every level may give one immutable sequence of empty ones)."""
"""(pose_a, pose_b, internal) of one connector: (3,), (3,), (n_internal,)."""


class Connector(ABC):
    """Base class of every connector of :class:`flexval.reducedmodels.core.system.System`.

    Attributes
    ----------
    name : str
        Unique name (the flexure's or the pin's), used in outputs and messages.
    bodies : tuple of str
        The two bodies joined, (a, b); either may be the ground.
    n_internal : int
        Number of internal coordinates (default 0: a connector acting
        directly between the two poses).
    n_multipliers : int
        How many internal coordinates are Lagrange multipliers (default 0);
        each makes the tangent one negative eigenvalue indefinite at a stable
        state, which the core's stability test accounts for.
    sway_load : float or None
        For a model of a straight (or shallow) flexure without geometric
        stiffness for the sway of its ends or of its parts (it cannot buckle
        there): the compression (N) beyond which its states are outside its
        validity (:func:`flexval.reducedmodels.core.validity.sway_load`); None
        (default) for a model that buckles itself, which the stability test
        finds.
    sway_span : str
        What ``sway_load`` is the Euler load of, for messages: ``"leaf"``
        (default: the whole flexure) or ``"sub-arc"``.
    dead_load_scale : float
        The largest dead load the connector carries itself (N; its weights,
        :class:`flexval.reducedmodels.core.inertia.Weighted`): it joins the force
        scale of the residual test (default 0).
    surface_stress : callable or None
        ``surface_stress(forces, section) -> (at, stress)``: the flexure's surface
        fibre stress (MPa) along it, from its section forces
        (:class:`~flexval.reducedmodels.core.sections.SectionForces`), and the
        arc-length fractions where it is given, for a flexure whose
        true peak is not the beam formula's |N|/A + |M| h/(2I) (a calibrated notch
        hinge: :meth:`flexval.reducedmodels.notchcorrection.NotchFactors.surface_stress`);
        the path then records that peak too (``LoadPath.fibre_stress``). None
        (default): the beam formula is the surface stress.
    """

    name: str
    bodies: tuple[str, str]
    n_internal: int = 0
    n_multipliers: int = 0
    sway_load: float | None = None
    sway_span: str = "leaf"
    dead_load_scale: float = 0.0
    surface_stress: Callable[[SectionForces, Section], tuple[np.ndarray, np.ndarray]] | None = None

    # --- required --------------------------------------------------------
    @abstractmethod
    def evaluate(
        self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Energy (N mm), gradient (6 + n_internal) and Hessian.

        The gradient holds the generalised forces conjugate to the local
        coordinates (N on lengths, N mm on angles). The Hessian is a dense
        (6 + n_internal) square array, or, if :meth:`hessian_pattern` returns
        a pattern, the values of its entries (duplicates summed).

        Raises
        ------
        ValueError
            If the state is outside the model's domain (e.g. an inverted
            element); the core then treats the Newton iterate as refused and
            cuts the step.
        """

    @abstractmethod
    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Deformed centre line (or representative polyline) as points (m, 2), mm."""

    # --- optional, with defaults ----------------------------------------
    @classmethod
    def group(cls, connectors: Sequence[Connector]) -> ConnectorGroup:
        """The evaluator of several connectors of this class at once (built once by the core).

        The core evaluates each run of consecutive connectors of one class
        through the group this returns. Default: a :class:`ConnectorGroup`,
        which calls :meth:`evaluate` connector by connector. A class whose
        connectors are cheap but many small array calls each (beam elements)
        overrides it with one vectorised evaluation of the whole run; its
        :meth:`evaluate` should then evaluate a group of one, so that there is
        one implementation.
        """
        return ConnectorGroup(connectors)

    def initial_internal(self) -> np.ndarray:
        """Internal coordinates in the undeformed configuration (default: zeros)."""
        return np.zeros(self.n_internal)

    def internal_is_rotation(self) -> np.ndarray:
        """Boolean mask (n_internal,): True where an internal coordinate is an angle (rad).

        Default: none is. The core scales angles as they are and lengths by
        the mechanism size in its step bounds and norms.
        """
        return np.zeros(self.n_internal, dtype=bool)

    update_above: float | None = None
    """Scaled Newton correction above which the core applies :meth:`update_internal`.

    None: :data:`flexval.reducedmodels.core.newton.NONLINEAR_UPDATE`, set for chords as
    long as a fraction of the mechanism. Connectors whose coordinates are
    much closer together turn far more for the same scaled correction and
    set a lower value (a meshed flexure: 0, always)."""

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Local (rows, cols) of the Hessian values :meth:`evaluate` returns, fixed for life.

        Default None: the Hessian is dense. A sparse connector returns the
        pattern once; its entries may repeat (values are summed).
        """
        return None

    def predict_internal(
        self,
        states: Sequence[LocalState],
        weights: Sequence[float],
        pose_a: np.ndarray,
        pose_b: np.ndarray,
    ) -> np.ndarray:
        """Internal coordinates predicted for the next load step (predictor of the stepping).

        Default: the same Lagrange extrapolation the core applies to every
        coordinate, ``sum(w_k internal_k)``. Override it when extrapolating
        coordinates one by one is poor (e.g. nearly inextensible chords that
        turn come out stretched).

        Parameters
        ----------
        states : sequence of (pose_a, pose_b, internal)
            The connector's converged local states, oldest first.
        weights : sequence of float
            Lagrange extrapolation weights of those states at the new load
            factor (they sum to 1).
        pose_a, pose_b : array (3,)
            The bodies' predicted poses (x, y mm; theta rad).
        """
        return sum(w * state[2] for w, state in zip(weights, states))

    def update_internal(self, old: LocalState, new: LocalState) -> np.ndarray:
        """Internal coordinates after a Newton correction (from the old and the linear update).

        Default: the linear update, ``new[2]`` (= q + du). An override must
        agree with it to first order in the correction, so that Newton stays
        quadratic.
        """
        return new[2]

    def validity(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> list[str]:
        """Reasons why this state lies outside the model's range of meaning (empty: valid).

        Evaluated at every converged load level without stopping the run
        (the validity monitor). Default: no concerns. Each reason states the
        measured value and the threshold, e.g. ``"element 3 chord stretch
        12.5 % > 2 %"``.
        """
        return []

    def path_validity(self, states: Sequence[LocalState]) -> Reasons:
        """:meth:`validity` at each of several states (a load path's levels).

        The path recorder asks once per path, so that a connector can screen
        all the states in one vectorised pass and name reasons only where
        there are any. Default: :meth:`validity` state by state.
        """
        return [self.validity(*state) for state in states]

    def rigid_directions(self) -> Sequence[tuple[np.ndarray, np.ndarray]]:
        """The relative motions of its two bodies this connector holds rigid at rest, to first
        order: each a point (mm) and a unit direction along which the two bodies' points there
        move alike, both global. Default none: a connector with a stiffness for every motion.

        The PRBM's straight leaf (rigid links on one line) holds its axis; a
        pin holds both directions at its point. Where such directions lock
        one motion more than once, how the connectors share a load along it
        is statically indeterminate (:mod:`flexval.reducedmodels.core.redundancy`).
        """
        return ()

    # --- optional mass (flexval.reducedmodels.core.inertia) ---------------------------
    def mass_points(self, density: float) -> MassPoints | None:
        """The connector's mass as point masses over its local coordinates.

        ``density`` is the flexure material's, t/mm^3. Returns a
        :class:`flexval.reducedmodels.core.inertia.MassPoints` table (mass in t, rotary
        inertia in t mm^2, offsets in mm), which also gives the weight under
        gravity. Default None: massless (pins, and any model that does not
        say how its flexure's mass is distributed); a modal or dynamic
        analysis then treats the internal coordinates as quasi-static and
        refuses massless body coordinates.
        """
        return None

    def mass_matrix(
        self, density: float, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> sp.spmatrix | None:
        """A consistent mass matrix over the local coordinates at this state (t, t mm, t mm^2).

        Default None: the mass is that of :meth:`mass_points`. A connector
        that returns one (the continuum) has it used for the mass matrix,
        while its ``mass_points`` still give its weight; it must then give
        its velocity-dependent inertia forces by :meth:`convective_forces`.
        """
        return None

    def convective_forces(
        self,
        density: float,
        pose_a: np.ndarray,
        pose_b: np.ndarray,
        internal: np.ndarray,
        velocity: np.ndarray,
    ) -> np.ndarray | None:
        """Velocity-dependent inertia forces of a :meth:`mass_matrix` (N, N mm), local.

        For a kinetic energy 1/2 v^T M(q) v they are M'(q) v - 1/2 d(v^T M v)/dq,
        so that the equations of motion read M a + c = f. ``velocity`` holds
        the local coordinates' rates (mm/s, rad/s). Default None: the
        connector has no consistent mass (its mass points' convective forces
        are the core's).
        """
        return None

    def section_forces(
        self,
        pose_a: np.ndarray,
        pose_b: np.ndarray,
        internal: np.ndarray,
        gradient: np.ndarray | None = None,
    ) -> SectionForces | None:
        """Normal force (N) and bending moment (N mm) along the flexure at a converged state.

        Recorded at every load level by the path recorder, which turns them
        into the peak outer-fibre stress of the flexure's section (MPa) and
        where it occurs (:class:`flexval.reducedmodels.core.sections.SectionForces`).
        They come from the model's own internal forces; a flexure model
        typically passes its energy gradient on the end body's pose and its
        displaced centre line to
        :func:`flexval.reducedmodels.core.sections.statics_section_forces`.
        Default: None, the connector reports no section forces (a pin).

        Parameters
        ----------
        pose_a, pose_b, internal : ndarray
            The local state (internal coordinates in equilibrium).
        gradient : array (6 + n_internal,), optional
            The local energy gradient at this state if already known (e.g.
            the linear response's K0 dq); default: from :meth:`evaluate`.
        """
        return None

    def path_section_forces(self, states: Sequence[LocalState]) -> SectionForces | None:
        """The section forces of :meth:`section_forces` at several states, stacked.

        The path recorder asks once per load path, for every converged level
        at once, so that a connector can compute them in one vectorised pass
        instead of one call per level.

        Parameters
        ----------
        states : sequence of (pose_a, pose_b, internal)
            k local states, internal coordinates in equilibrium.

        Returns
        -------
        SectionForces or None
            Normal force (N) and bending moment (N mm) as (k, m) arrays at the
            model's m stations, which are the same at every state; None if
            the connector reports no section forces. Default:
            :meth:`section_forces` state by state.
        """
        forces = [self.section_forces(*state) for state in states]
        if not forces or forces[0] is None:
            return None
        from .sections import SectionForces

        return SectionForces(
            forces[0].at, np.array([f.axial for f in forces]), np.array([f.moment for f in forces])
        )


def _same_arrays(a: tuple | None, b: tuple | None) -> bool:
    """Whether two Hessian patterns are the same arrays (a pattern returned as a new tuple
    of a connector's fixed rows and columns at each call)."""
    return a is not None and b is not None and a[0] is b[0] and a[1] is b[1]


class ConnectorGroup:
    """Connectors evaluated together: their energies summed, gradients and Hessians concatenated.

    This default evaluates them one by one with :meth:`Connector.evaluate`;
    a connector class may return a vectorised subclass from
    :meth:`Connector.group`.

    Parameters
    ----------
    connectors : sequence of Connector
        The connectors, in the order their states are given.
    """

    compiled: bool = False
    """True if :meth:`assembler` runs compiled kernels (numba is then loaded, and the core's
    tangent layout may use the compiled banded factorisation too)."""

    def __init__(self, connectors: Sequence[Connector]):
        self.connectors = tuple(connectors)

    def evaluate(self, states: Sequence[LocalState]) -> tuple[float, np.ndarray, np.ndarray]:
        """Total energy (N mm), concatenated gradients and concatenated Hessian values.

        ``states`` holds each connector's (pose_a, pose_b, internal), in the
        order of :attr:`connectors`. The gradients and (raveled) Hessians are
        those :meth:`Connector.evaluate` returns, one after the other.
        """
        energy, grads, hessians = 0.0, [], []
        for c, local in zip(self.connectors, states):
            e, g, h = c.evaluate(*local)
            energy += e
            grads.append(g)
            hessians.append(np.ravel(h))
        return energy, np.concatenate(grads), np.concatenate(hessians)

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of :meth:`evaluate`'s concatenated Hessian values in the
        concatenated local coordinates.

        Each connector's :meth:`Connector.hessian_pattern` (a dense Hessian:
        every entry, row by row) shifted by the connector's first local
        coordinate, one after the other; the core asks once, when it builds
        its index maps.
        """
        patterns = [c.hessian_pattern() for c in self.connectors]
        sizes = [6 + c.n_internal for c in self.connectors]
        first = patterns[0] if patterns else None
        if (
            patterns
            and all(p is first or _same_arrays(p, first) for p in patterns)
            and len(set(sizes)) == 1
        ):
            # connectors alike (a batch's copies): one pattern, shifted by each one's start
            m, pattern = sizes[0], patterns[0]
            if pattern is None:
                pattern = np.repeat(np.arange(m), m), np.tile(np.arange(m), m)
            starts = (m * np.arange(len(sizes), dtype=np.int64))[:, None]
            return (pattern[0] + starts).ravel(), (pattern[1] + starts).ravel()
        rows, cols, start = [], [], 0
        for pattern, m in zip(patterns, sizes):
            if pattern is None:
                pattern = np.repeat(np.arange(m), m), np.tile(np.arange(m), m)
            rows.append(pattern[0] + start), cols.append(pattern[1] + start)
            start += m
        return (
            np.concatenate(rows or [np.zeros(0, np.int64)]),
            np.concatenate(cols or [np.zeros(0, np.int64)]),
        )

    def assembler(
        self, gather: np.ndarray, grad_dofs: np.ndarray, hess_slots: np.ndarray
    ) -> Callable[[np.ndarray, np.ndarray, np.ndarray], float] | None:
        """A function that adds the group's gradient and tangent into the global arrays, or None.

        The core calls it once, with the index maps of the concatenated local
        coordinates: ``gather`` (their positions in the coordinates
        ``[q, ground pose]``), ``grad_dofs`` (their global dofs, -1 for the
        ground's) and ``hess_slots`` (where each concatenated Hessian value of
        :meth:`evaluate` goes in the tangent storage, -1: dropped). The
        function, called as ``f(coordinates, grad, storage)``, adds the
        gradient (N, N mm) into ``grad`` and the Hessian values into
        ``storage`` and returns the energy (N mm): what the core would do
        with :meth:`evaluate`'s results, without building them.
        Default: None, the core scatters :meth:`evaluate`'s results itself.
        """
        return None

    def predictor(
        self, gather: np.ndarray
    ) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[..., np.ndarray]] | None:
        """:meth:`predict_internal` as functions of global coordinates, or None.

        Called once with ``gather`` as for :meth:`assembler`; returns
        ``(remember, predict)``. ``remember(coordinates)`` is what the
        prediction keeps of a converged state (``[q, ground pose]``, an
        array, computed once per state); ``predict(memories, weights, guess,
        slope=None, slope_weight=0.0)``, with ``memories`` (k, m) those of
        the history (oldest first), their extrapolation weights (k,) and
        ``guess`` the coordinates whose poses are the predicted ones,
        returns what :meth:`predict_internal` would; given the path's slope
        at the last state (coordinates per unit load factor, zero on the
        ground) and its weight, ``weights`` are Hermite weights and the
        prediction is one degree higher (see :meth:`System.predict`).
        Default: None (the core builds the local states).
        """
        return None

    def updater(self, gather: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray] | None:
        """:meth:`update_internal` as a function of global coordinates, or None.

        As :meth:`predictor`: ``f(old, new)`` with the coordinates
        ``[q, ground pose]`` before and after the linear update.
        """
        return None

    def path_validity(self, levels: Sequence[Sequence[LocalState]]) -> list[Reasons]:
        """Each connector's :meth:`Connector.path_validity`: reasons per connector, then per level.

        ``levels`` holds, for each of k states (a load path's levels), the
        connectors' local states in the order of :attr:`connectors`.
        """
        return [
            c.path_validity([states[j] for states in levels]) for j, c in enumerate(self.connectors)
        ]

    def path_section_forces(
        self, levels: Sequence[Sequence[LocalState]]
    ) -> list[SectionForces | None]:
        """Each connector's :meth:`Connector.path_section_forces` at k levels
        (as ``path_validity``)."""
        return [
            c.path_section_forces([states[j] for states in levels])
            for j, c in enumerate(self.connectors)
        ]

    def path_end_pass(
        self, coordinates: np.ndarray
    ) -> tuple[list[Reasons], list[SectionForces | None]]:
        """:meth:`path_validity` and :meth:`path_section_forces` of the same k levels, together.

        What a path's end pass records (:func:`flexval.reducedmodels.core.recorder.path_end_pass`).
        ``coordinates`` (k, m) holds the connectors' local coordinates
        [pose_a, pose_b, internal] laid end to end at each level (mm, rad);
        a group that reads them as they are, or whose two answers share work
        (the beams: one compiled pass), overrides this. Default: the two
        calls on the connectors' local states.
        """
        levels = self.local_levels(coordinates)
        return self.path_validity(levels), self.path_section_forces(levels)

    def path_end_stacks(self, coordinates: np.ndarray) -> tuple[list[Reasons], list[ForceStack]]:
        """:meth:`path_end_pass` with the section forces as stacks of connectors whose
        stations are the same (:class:`~flexval.reducedmodels.core.sections.ForceStack`).

        What a batch's end pass records
        (:func:`flexval.reducedmodels.core.batch.record_batch`): a group whose copies'
        connectors share their stations (``prbm``'s chains, DCMM's sub-arcs) stacks
        them as its kernels give them, without a SectionForces per connector.
        Default: each connector with forces a stack of its own.
        """
        from .sections import ForceStack

        verdicts, forces = self.path_end_pass(coordinates)
        stacks = [
            ForceStack([j], f.at, f.axial[None], f.moment[None])
            for j, f in enumerate(forces)
            if f is not None
        ]
        return verdicts, stacks

    def local_levels(self, coordinates: np.ndarray) -> list[list[LocalState]]:
        """The connectors' local states at each level from their coordinates laid
        end to end (k, m)."""
        sizes = [6 + c.n_internal for c in self.connectors]
        levels = []
        for row in coordinates:
            states, start = [], 0
            for m in sizes:
                states.append(
                    (row[start : start + 3], row[start + 3 : start + 6], row[start + 6 : start + m])
                )
                start += m
            levels.append(states)
        return levels

    def section_forces(
        self, states: Sequence[LocalState], gradients: Sequence[np.ndarray]
    ) -> list[SectionForces | None]:
        """Each connector's :meth:`Connector.section_forces` at its state with a known gradient.

        ``states`` and ``gradients`` hold each connector's local state and
        local energy gradient (e.g. a linear response's K0 dq), in the order
        of :attr:`connectors`. Default: connector by connector.
        """
        return [
            c.section_forces(*local, gradient=g)
            for c, local, g in zip(self.connectors, states, gradients)
        ]

    def predict_internal(
        self,
        past: Sequence[Sequence[LocalState]],
        weights: Sequence[float],
        poses: Sequence[tuple[np.ndarray, np.ndarray]],
    ) -> np.ndarray:
        """The connectors' predicted internal coordinates for the next load step, concatenated.

        ``past`` holds, for each converged state (oldest first), the
        connectors' local states; ``poses`` each connector's predicted
        (pose_a, pose_b); see :meth:`Connector.predict_internal`.
        """
        return np.concatenate(
            [
                c.predict_internal([states[k] for states in past], weights, *pose)
                for k, (c, pose) in enumerate(zip(self.connectors, poses))
            ]
        )

    def update_internal(self, old: Sequence[LocalState], new: Sequence[LocalState]) -> np.ndarray:
        """The connectors' internal coordinates after a Newton correction, concatenated.

        ``old`` and ``new`` hold each connector's local state before and
        after the linear update (see :meth:`Connector.update_internal`).
        """
        return np.concatenate(
            [c.update_internal(o, n) for c, o, n in zip(self.connectors, old, new)]
        )


class KernelEndPass(ConnectorGroup):
    """A group whose end pass gives every connector's section forces as one kernel's arrays.

    :meth:`_end_pass` computes the verdicts and the arrays once; a path's
    few connectors then take their forces apart (:meth:`_split`), a batch's
    copies stacked by stations (:meth:`_stacks`). ``prbm``'s chains and
    DCMM's sub-arcs are such groups.
    """

    def path_end_pass(self, coordinates: np.ndarray) -> tuple[list[Reasons], list[SectionForces]]:
        """:meth:`ConnectorGroup.path_end_pass` from :meth:`_end_pass`, each connector's
        forces apart."""
        verdicts, axial, moment = self._end_pass(coordinates)
        forces = self._split(axial, moment)
        return with_sway_reasons(self.connectors, verdicts, forces), forces

    def path_end_stacks(self, coordinates: np.ndarray) -> tuple[list[Reasons], list[ForceStack]]:
        """:meth:`ConnectorGroup.path_end_stacks` from :meth:`_end_pass`, the connectors of
        the same stations stacked."""
        verdicts, axial, moment = self._end_pass(coordinates)
        if any(c.sway_load is not None for c in self.connectors):
            verdicts = with_sway_reasons(self.connectors, verdicts, self._split(axial, moment))
        return verdicts, self._stacks(axial, moment)

    def _end_pass(self, coordinates: np.ndarray) -> tuple[list[Reasons], np.ndarray, np.ndarray]:
        """The verdicts of the k levels of ``coordinates`` (as :meth:`path_end_pass` takes
        them) and the kernel's normal forces (N) and bending moments (N mm)."""
        raise NotImplementedError

    def _split(self, axial: np.ndarray, moment: np.ndarray) -> list[SectionForces]:
        """Each connector's section forces (k, m) from :meth:`_end_pass`'s arrays."""
        raise NotImplementedError

    def _stacks(self, axial: np.ndarray, moment: np.ndarray) -> list[ForceStack]:
        """The connectors' section forces from :meth:`_end_pass`'s arrays, stacked by stations
        (:func:`flexval.reducedmodels.core.sections.column_stacks`)."""
        raise NotImplementedError


def overrides(connector: Connector, hook: str) -> bool:
    """True if ``connector``'s class replaces the base class's default ``hook``.

    The core calls :meth:`Connector.predict_internal` and
    :meth:`Connector.update_internal` only on connectors that override them:
    the defaults compute exactly what the core already does for every
    coordinate, so skipping them gives the same numbers without gathering
    the local states.
    """
    return getattr(type(connector), hook) is not getattr(Connector, hook)


def with_sway_reasons(
    connectors: Sequence[Connector], verdicts: list[Reasons], forces: Sequence
) -> list[Reasons]:
    """``verdicts`` with, for every connector that has a :attr:`Connector.sway_load`, the
    levels whose compression exceeds it named (:func:`flexval.reducedmodels.core.validity.
    sway_reasons`); ``forces`` are the connectors' section forces (k levels) in order. New
    lists where reasons are added: a group may share one verdict among its connectors."""
    from .validity import sway_reasons

    if not any(c.sway_load is not None for c in connectors):
        return verdicts
    out = list(verdicts)
    for j, (c, found) in enumerate(zip(connectors, forces)):
        if c.sway_load is None or found is None:
            continue
        extra = sway_reasons(found.axial, c.sway_load, c.sway_span)
        if any(extra):
            out[j] = [[*why, *more] for why, more in zip(verdicts[j], extra)]
    return out
