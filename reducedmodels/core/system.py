"""The quasi-static multibody core shared by every flexibility model.

Unknowns are the poses (x, y, theta) of the non-ground rigid bodies plus the
private internal coordinates of the connectors (beam nodes, continuum nodes,
DCMM intermediate bodies ...). Every connector is conservative: it returns
its strain energy, gradient (internal forces) and Hessian (consistent
tangent) from the poses of the two bodies it joins and its internal
coordinates. Dead loads (:class:`~flexval.reducedmodels.core.loads.Loads`) add their potential.
Equilibrium is grad(Pi) = 0; :class:`System` assembles it, and the path
tracer (:mod:`flexval.reducedmodels.core.tracer`) solves it with the one Newton iteration
of :mod:`flexval.reducedmodels.core.newton`. Open and closed chains need no special code:
a closed chain is a connector graph with a loop. What a connector must and
may provide is :class:`flexval.reducedmodels.core.connector.Connector`.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from flexval.geometry import LoadCase, Mechanism
from flexval.geometry.kinematics import rotate_xy

from .connector import Connector, ConnectorGroup, LocalState, overrides
from .extrapolation import hermite_weights, lagrange_weights
from .loads import Loads
from .newton import NONLINEAR_UPDATE
from .settings import SolverError, SolverSettings
from .tangent import Tangent, TangentLayout


def local_hessian(connector: Connector, hessian: np.ndarray) -> np.ndarray | sp.csc_matrix:
    """The Hessian returned by ``connector.evaluate`` as a matrix over its local coordinates.

    Dense connectors return it as is; for a connector with a
    :meth:`~Connector.hessian_pattern` the values become a CSC matrix
    (duplicates summed).
    """
    pattern = connector.hessian_pattern()
    if pattern is None:
        return np.asarray(hessian)
    n = 6 + connector.n_internal
    return sp.csc_matrix((hessian, pattern), shape=(n, n))


def local_hessian_product(connector: Connector, hessian: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``local_hessian(connector, hessian) @ x`` without building the matrix.

    For a connector with a :meth:`~Connector.hessian_pattern` the product is
    one ``bincount`` over the pattern (a sparse matrix per call costs ten
    times more on the small connectors of the reduced models).
    """
    pattern = connector.hessian_pattern()
    if pattern is None:
        return np.asarray(hessian) @ x
    rows, cols = pattern
    return np.bincount(rows, weights=hessian * x[cols], minlength=x.size)


@dataclass
class System:
    """A mechanism made of rigid bodies and flexure connectors, ready to solve."""

    mechanism: Mechanism
    connectors: Sequence[Connector]
    settings: SolverSettings = field(default_factory=SolverSettings)

    def __post_init__(self) -> None:
        mech = self.mechanism
        self.size = mech.size()
        self.body_index = {b: k for k, b in enumerate(mech.moving_bodies)}
        #: the target point's offset from its body's reference point and its place at rest (mm)
        self._target_offsets = (
            (mech.target_point - mech.bodies[mech.target_body].reference).tolist(),
            mech.target_point.tolist(),
        )
        #: every connector's global dofs [pose_a, pose_b, internal] in one array (ground: -1);
        #: connector k's are ``all_dofs[connector_offsets[k]:connector_offsets[k + 1]]``, and
        #: ``_all_gather`` holds their places in [q, ground pose] (the ground's pose after q)
        self.all_dofs, self._all_gather, self.connector_offsets, self.is_rotation = (
            self.number_connectors()
        )
        # the poses, then every connector's internal coordinates (its local ones but the six)
        self.n_dofs = (
            3 * len(self.body_index) + self.connector_offsets[-1] - 6 * len(self.connectors)
        )
        self.n_multipliers = sum(c.n_multipliers for c in self.connectors)
        self._rest_negative: int | None = None  # the rule's count at rest (judges_stability)
        #: residual weights: forces as is, moments per unit of mechanism size (N)
        self.force_scale = np.where(self.is_rotation, 1.0 / self.size, 1.0)
        #: what :meth:`scaled` divides by: the size for lengths, 1 for angles (mm or 1)
        self._coordinate_scale = np.where(self.is_rotation, 1.0, self.size)
        self._groups = connector_groups(self.connectors)
        # groups of connectors that predict or update their internal coordinates
        # themselves, with those coordinates' global dofs (the defaults give what
        # the core computes for every coordinate anyway)
        self._predictors, self._updaters = (
            [
                (group, run, np.concatenate([idx[6:] for idx in self.local_to_global[run]]))
                for group, run in self._groups
                if overrides(group.connectors[0], hook)
                and sum(c.n_internal for c in group.connectors)
            ]
            for hook in ("predict_internal", "update_internal")
        )
        #: scaled Newton correction above which :meth:`update` applies the connectors' updates
        self.update_threshold = min(
            (
                c.update_above
                for group, _, _ in self._updaters
                for c in group.connectors
                if c.update_above is not None
            ),
            default=NONLINEAR_UPDATE,
        )
        self._build_scatter()

    @cached_property
    def reference(self) -> dict[str, np.ndarray]:
        """Every body's reference point by name (mm), read on first use (a batch's thousands
        of bodies are placed by their copies')."""
        return {b: body.reference for b, body in self.mechanism.bodies.items()}

    @cached_property
    def local_to_global(self) -> list[np.ndarray]:
        """Each connector's global dofs [pose_a, pose_b, internal] (views of ``all_dofs``),
        made on first use: a batch of thousands of connectors reads few of them."""
        return self._split(self.all_dofs, self.connector_offsets)

    @cached_property
    def _gather(self) -> list[np.ndarray]:
        """Each connector's local coordinates' places in [q, ground pose] (views of
        ``_all_gather``), made on first use."""
        return self._split(self._all_gather, self.connector_offsets)

    def number_connectors(self) -> tuple[np.ndarray, np.ndarray, list[int], np.ndarray]:
        """The unknowns: the moving bodies' poses, then each connector's internal coordinates.

        Returns every connector's global dofs [pose_a, pose_b, internal] laid
        end to end (ground: -1), their places in [q, ground pose] (the
        ground's pose read after q), where each connector's start (and the
        end), and which unknowns are angles; built from plain lists. A
        subclass numbering many connectors at once (a batch of copies,
        :class:`flexval.reducedmodels.core.batch.BatchSystem`) overrides it.
        """
        mech = self.mechanism
        n = 3 * len(self.body_index)
        total = n + sum(c.n_internal for c in self.connectors)
        pose = {b: [3 * k, 3 * k + 1, 3 * k + 2] for b, k in self.body_index.items()}
        place = {**pose, mech.ground: [total, total + 1, total + 2]}
        pose[mech.ground] = [-1, -1, -1]
        dofs, places, bounds = [], [], [0]
        rot_mask = [np.array([False, False, True] * len(self.body_index))]
        for c in self.connectors:
            internal = list(range(n, n + c.n_internal))
            a, b = c.bodies
            dofs += pose[a] + pose[b] + internal
            places += place[a] + place[b] + internal
            bounds.append(len(dofs))
            rot_mask.append(np.asarray(c.internal_is_rotation(), bool))
            n += c.n_internal
        return (
            np.array(dofs, np.int64),
            np.array(places, np.int64),
            bounds,
            np.concatenate(rot_mask),
        )

    def _build_scatter(self) -> None:
        """Index maps of the assembly, computed once (the sparsity pattern never changes).

        * ``_gather[k]``: positions of connector k's local coordinates in
          ``[q, ground pose]`` (ground dofs read the fixed ground pose);
        * ``_assemblers``: the groups that add their gradients and tangent
          entries into the global arrays themselves
          (:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.assembler`: the
          compiled kernels of beams, DCMM sub-arcs and PRBM chains), given
          these maps for their connectors;
        * for the other groups, whose gradients and Hessian values are
          concatenated: ``_grad_dofs`` / ``_grad_keep``, the global dof of
          every kept entry of the gradients (ground entries dropped), and
          ``_hess_keep`` / ``_hess_slots``, the kept entries of the Hessian
          values and their places in the tangent storage;
        * ``_diagonal_slots``: where each dof's diagonal entry is stored (the
          loads add to it);
        * ``_predictors`` / ``_updaters`` get the group's function of the
          global coordinates
          (:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.predictor`,
          :meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.updater`) as a fourth
          entry, None where the group has none.
        """
        n, bounds, all_gather = self.n_dofs, self.connector_offsets, self._all_gather

        def of_run(values: np.ndarray, offsets: list[int], run: slice) -> np.ndarray:
            """The entries of a run of consecutive connectors (a view)."""
            return values[offsets[run.start] : offsets[run.stop]]

        # each group's Hessian entries in global dofs, ground entries dropped (kept: keep)
        rows, cols, hess_keep = [], [], []
        for group, run in self._groups:
            dofs = of_run(self.all_dofs, bounds, run)
            local_rows, local_cols = group.hessian_pattern()
            r, cc = dofs[local_rows], dofs[local_cols]
            keep = (r >= 0) & (cc >= 0)
            rows.append(r[keep]), cols.append(cc[keep]), hess_keep.append(keep)
        ground = self.mechanism.bodies[self.mechanism.ground].reference
        self._ground_pose = np.array([ground[0], ground[1], 0.0])
        # assembly's work arrays, reused: [q, ground pose] for the assemblers (q's part
        # overwritten at each assembly) and the loads' tangent diagonal (kept zero); so one
        # System assembles in one thread at a time (sweeps run systems in processes)
        self._coordinates = self.extended(np.zeros(n))
        self._load_diagonal = np.zeros(n)
        diagonal = np.arange(n)
        compiled = any(group.compiled for group, _ in self._groups)
        #: the global row and column of every value slot of the tangent's pattern (the layout's
        #: slots' order)
        self.pattern_rows = np.concatenate([*rows, diagonal])
        self.pattern_cols = np.concatenate([*cols, diagonal])
        self.layout = TangentLayout(
            n,
            self.pattern_rows,
            self.pattern_cols,
            self.n_multipliers,
            compiled,
            self.tangent_ordering(),
        )
        # each group's Hessian values -> storage slots (-1: a ground entry, dropped)
        group_slots, start = [], 0
        for keep in hess_keep:
            slots = np.full(keep.size, -1, np.int64)
            kept = int(np.count_nonzero(keep))
            slots[keep] = self.layout.slots[start : start + kept]
            group_slots.append(slots)
            start += kept
        self._diagonal_slots = self.layout.slots[-n:]
        self._diagonal_slot_list = self._diagonal_slots.tolist()  # read one by one per assembly

        #: each group's local coordinates laid end to end, as positions in [q, ground pose]
        self._group_gathers = [of_run(all_gather, bounds, run) for _, run in self._groups]
        self._assemblers, self._generic, generic_slots = [], [], []
        for (group, run), slots in zip(self._groups, group_slots):
            assembler = group.assembler(
                of_run(all_gather, bounds, run), of_run(self.all_dofs, bounds, run), slots
            )
            if assembler is None:
                self._generic.append((group, run))
                generic_slots.append(slots)
            else:
                self._assemblers.append(assembler)
        # predictors and updaters with a function of the global coordinates use it (or None)
        self._predictors = [
            (group, run, internal, group.predictor(of_run(all_gather, bounds, run)))
            for group, run, internal in self._predictors
        ]
        self._updaters = [
            (group, run, internal, group.updater(of_run(all_gather, bounds, run)))
            for group, run, internal in self._updaters
        ]
        all_grad = np.concatenate(
            [of_run(self.all_dofs, bounds, run) for _, run in self._generic] or [np.zeros(0, int)]
        )
        self._grad_keep = all_grad >= 0
        self._grad_dofs = all_grad[self._grad_keep]
        generic_slots = np.concatenate(generic_slots or [np.zeros(0, np.int64)])
        self._hess_keep = generic_slots >= 0
        self._hess_slots = generic_slots[self._hess_keep]

    def tangent_ordering(self) -> np.ndarray | None:
        """The unknowns' order for a banded tangent, or None for the layout's own (see
        :class:`~flexval.reducedmodels.core.tangent.TangentLayout`); a batch of copies gives
        each copy's block its copy's order."""
        return None

    @staticmethod
    def _split(values: np.ndarray, bounds: list[int]) -> list[np.ndarray]:
        """``values[bounds[k]:bounds[k + 1]]`` for every k (views)."""
        return [values[start:stop] for start, stop in zip(bounds, bounds[1:])]

    def pose_dofs(self, body: str) -> np.ndarray:
        """Global dof numbers of a body's pose (all -1 for the ground)."""
        if body == self.mechanism.ground:
            return np.full(3, -1)
        k = self.body_index[body]
        return np.arange(3 * k, 3 * k + 3)

    def initial_state(self) -> np.ndarray:
        """Coordinates of the undeformed configuration."""
        q = np.zeros(self.n_dofs)
        for b, k in self.body_index.items():
            q[3 * k : 3 * k + 2] = self.reference[b]
        for c, idx in zip(self.connectors, self.local_to_global):
            q[idx[6:]] = c.initial_internal()
        return q

    def pose(self, q: np.ndarray, body: str) -> np.ndarray:
        """Pose (x, y, theta) of ``body`` in state q (ground: fixed)."""
        if body == self.mechanism.ground:
            return self._ground_pose.copy()
        k = self.body_index[body]
        return q[3 * k : 3 * k + 3]

    def copy_layout(self) -> tuple[np.ndarray, list[tuple[Mechanism, Sequence[Connector]]]]:
        """Every connector's (copy, index among its copy's connectors), (n, 2) of int, and each
        copy's mechanism and connectors: a System alone is one copy, a batch many
        (:meth:`flexval.reducedmodels.core.batchsystem.BatchSystem.copy_layout`). What the
        recorder's end pass reads to give each copy its own verdicts and stresses."""
        count = len(self.connectors)
        origin = np.column_stack([np.zeros(count, np.int64), np.arange(count, dtype=np.int64)])
        return origin, [(self.mechanism, self.connectors)]

    @property
    def groups(self) -> list[tuple[ConnectorGroup, slice]]:
        """The runs of consecutive connectors of one class, each with its group (built once)."""
        return self._groups

    def extended(self, q: np.ndarray) -> np.ndarray:
        """The coordinates ``[q, ground pose]`` the connectors' gather maps read (a new array)."""
        return np.concatenate([q, self._ground_pose])

    def local_states(self, q: np.ndarray) -> list[LocalState]:
        """(pose_a, pose_b, internal) of every connector in state q."""
        extended = self.extended(q)
        out = []
        for gather in self._gather:
            local = extended[gather]
            out.append((local[:3], local[3:6], local[6:]))
        return out

    def group_coordinates(self, states: Sequence[np.ndarray]) -> list[np.ndarray]:
        """Each group's local coordinates laid end to end at k states, (k, m) each (mm, rad).

        One gather per group for all the states (a load path's end pass);
        in the order of :attr:`groups`, each row the group's connectors'
        [pose_a, pose_b, internal] one after the other.
        """
        n = self.n_dofs
        extended = np.empty((len(states), n + 3))
        extended[:, :n] = states
        extended[:, n:] = self._ground_pose
        return [extended[:, gather] for gather in self._group_gathers]

    # --- loads -----------------------------------------------------------
    def loads(self, case: LoadCase) -> Loads:
        """Dead loads of ``case`` at full value in global dof numbering.

        Connectors that carry dead loads of their own (weights, see
        :mod:`flexval.reducedmodels.core.inertia`) declare their size as
        ``dead_load_scale`` (N); it joins the force scale of the residual test,
        so that a case without load (or a small one) still has a meaningful one. A case
        that prescribes a motion loads the drive's multipliers (:meth:`drive_loads`); a
        case that does not, on a System with a drive, holds the driven point where it is
        at rest.
        """
        drives = self.drive_loads() if case.drive is not None else None  # else: held at rest
        return case_loads(case, self.pose_dofs, self.reference, self.size, self.connectors, drives)

    def _drive(self) -> tuple[int, Connector] | None:
        """(index, connector) of the mechanism's drive, if it has one."""
        from .drives import DriveConnector

        return next(
            ((k, c) for k, c in enumerate(self.connectors) if isinstance(c, DriveConnector)), None
        )

    def drive_loads(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The global dofs of the drive's multipliers and their loads (N), or None."""
        found = self._drive()
        if found is None:
            return None
        k, drive = found
        return self.local_to_global[k][6:], drive.multiplier_loads()

    def check_drive(self, case: LoadCase, model: str = "") -> None:
        """Refuse a prescribed motion this System cannot follow, before tracing it.

        A well-posed drive makes the saddle-point tangent at rest exactly one
        negative eigenvalue per multiplier (:meth:`unstable`). Fewer mean zero
        eigenvalues: the drive prescribes a direction the model already holds
        rigid (the PRBM's inextensible straight leaves), so no motion of it
        exists and load control would cut its steps to nothing.

        Raises
        ------
        SolverError
            At load factor 0, naming the model and the drive's body.
        """
        if case.drive is None or self._drive() is None:
            return
        negative = self._rest_instability()
        if negative < 0:
            raise SolverError(
                f"{model or 'model'} on load case '{case.name}': the prescribed motion of body "
                f"{case.drive.body!r} moves it along a direction this model holds rigid "
                f"(its tangent at rest is singular there: {-negative} zero eigenvalue(s); "
                "the PRBM's straight leaves are inextensible links): prescribe fewer "
                "components, or 'flexval stiffness' names the rigid directions",
                0.0,
            )

    def drive_reaction(self, q: np.ndarray) -> np.ndarray | None:
        """[Fx, Fy, M] the drive applies to its body at its point (N, N, N mm), or None."""
        found = self._drive()
        if found is None:
            return None
        k, drive = found
        return drive.reaction(q[self.local_to_global[k][6:]])

    # --- assembly --------------------------------------------------------
    def assemble(
        self, q: np.ndarray, loads: Loads, factor: float
    ) -> tuple[float, np.ndarray, Tangent]:
        """Total potential (N mm), its gradient and the tangent at state q and load factor.

        See :meth:`assemble_storage`; the tangent wraps its storage.
        """
        energy, grad, storage = self.assemble_storage(q, loads, factor)
        return energy, grad, self.layout.tangent(storage)

    def assemble_storage(
        self, q: np.ndarray, loads: Loads, factor: float
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Total potential (N mm), its gradient and the tangent's values in
        :attr:`layout`'s storage.

        Every connector is evaluated once, each run of consecutive connectors
        of one class through its :meth:`~Connector.group`: a group with an
        assembler (beams) adds into the global gradient and the tangent
        storage itself; the others' gradients and Hessian values are
        scattered with the index maps of :meth:`_build_scatter` into the
        storage the :class:`~flexval.reducedmodels.core.tangent.TangentLayout` chose.
        """
        n = self.n_dofs
        energy = 0.0
        if self._generic:
            grads, hessians = [], []
            states = self.local_states(q)
            for group, run in self._generic:
                e, g, h = group.evaluate(states[run])
                energy += e
                grads.append(g)
                hessians.append(h)
            grad = np.bincount(
                self._grad_dofs, weights=np.concatenate(grads)[self._grad_keep], minlength=n
            )
            storage = np.bincount(
                self._hess_slots,
                weights=np.concatenate(hessians)[self._hess_keep],
                minlength=self.layout.size,
            )
        else:
            grad, storage = np.zeros(n), np.zeros(self.layout.size)
        if self._assemblers:
            coordinates = self._coordinates  # [q, ground pose], the ground's part set once
            coordinates[:n] = q
            for assembler in self._assemblers:
                energy += assembler(coordinates, grad, storage)
        diagonal = self._load_diagonal  # zero between assemblies
        energy += loads.add_to(q, factor, grad, diagonal)
        if loads.many:
            dofs = loads.diagonal_array
            storage[self._diagonal_slots[dofs]] += diagonal[dofs]
            diagonal[dofs] = 0.0
            return energy, grad, storage
        for dof in loads.diagonal_dofs:  # the few loaded bodies' rotations
            value = diagonal[dof]
            if value:
                storage[self._diagonal_slot_list[dof]] += value
                diagonal[dof] = 0.0
        return energy, grad, storage

    def reaction(self, q: np.ndarray) -> np.ndarray:
        """Force (N) and moment (N mm, about the ground's reference point) the ground exerts."""
        total = np.zeros(3)
        g_name = self.mechanism.ground
        for c, local in zip(self.connectors, self.local_states(q)):
            if g_name not in c.bodies:
                continue
            _, g, _ = c.evaluate(*local)
            for k, b in enumerate(c.bodies):
                if b == g_name:
                    total += g[3 * k : 3 * k + 3]
        return total

    # --- outputs ---------------------------------------------------------
    def target(self, q: np.ndarray) -> tuple[float, float, float]:
        """Target point displacement (dx, dy) in mm and target body rotation in rad."""
        x, y, theta = self.pose(q, self.mechanism.target_body).tolist()  # floats: once per level
        (rel_x, rel_y), (tx, ty) = self._target_offsets
        rx, ry = rotate_xy(theta, rel_x, rel_y)
        return (x + rx) - tx, (y + ry) - ty, theta

    def target_arm(self, q: np.ndarray) -> tuple[float, float]:
        """The target point's offset from its body's reference point in state q, mm."""
        theta = float(self.pose(q, self.mechanism.target_body)[2])
        return rotate_xy(theta, *self._target_offsets[0])

    def update(self, q: np.ndarray, du: np.ndarray) -> np.ndarray:
        """State after the Newton correction du: q + du, or a connector's own update.

        A connector may map its internal coordinates nonlinearly
        (:meth:`Connector.update_internal`), provided the map equals q + du
        to first order so that Newton stays quadratic.
        """
        new = q + du
        if self._updaters:
            extended = self.extended(q), self.extended(new)
            local = None
            for group, run, internal, update in self._updaters:
                if update is not None:
                    new[internal] = update(*extended)
                    continue
                if local is None:  # from q + du, as the updates before this one found it
                    local = self.local_states(q), self.local_states(extended[1][: q.size])
                new[internal] = group.update_internal(local[0][run], local[1][run])
        return new

    @property
    def predicts_internal(self) -> bool:
        """True if some connector predicts its own internal coordinates (see :meth:`predict`)."""
        return bool(self._predictors)

    @property
    def predicts_with_slope(self) -> bool:
        """True if every connector that predicts its own coordinates can use the path's slope.

        (Those with a :meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.predictor`;
        then a slope given to :meth:`predict` raises the degree of the whole
        prediction, and a caller computes it only then.)
        """
        return all(predictor is not None for *_, predictor in self._predictors)

    def remembered(self, q: np.ndarray) -> list:
        """What the connectors' own predictors keep of a converged state q (see :meth:`predict`).

        One entry per predicting group: the memory its
        :meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.predictor` keeps, or
        the group's :meth:`local_states`. A caller that predicts many times
        from one history computes it once per state.
        """
        extended, local, out = None, None, []
        for _, run, _, predictor in self._predictors:
            if predictor is not None:
                extended = self.extended(q) if extended is None else extended
                out.append(predictor[0](extended))
            else:
                local = self.local_states(q) if local is None else local
                out.append(local[run])
        return out

    def predict(
        self,
        history: Sequence[tuple[np.ndarray, float]],
        factor: float,
        past: Sequence[list] | None = None,
        slope: np.ndarray | None = None,
    ) -> np.ndarray:
        """Predicted state at ``factor`` from converged (state, factor) pairs, oldest first.

        Coordinates are extrapolated by the Lagrange polynomial through the
        history (degree one less than the states: from k states an O(h^k)
        error, where the secant's is O(h^2)); connectors then predict their own internal
        coordinates (:meth:`Connector.predict_internal`, given their local
        states along the history, the weights and their bodies' predicted
        poses): nearly inextensible flexures extrapolated node by node in
        Cartesian coordinates come out stretched, and Newton then spends
        iterations pulling the stretch back out. ``past``, if given, holds
        :meth:`remembered` of each state of the history (else it is computed
        here).

        ``slope``, if given, is dq/dfactor at the last state (mm, rad per
        unit factor; K^-1 f from its tangent): the polynomial then matches
        it too, one degree higher (Hermite). Groups with a
        :meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.predictor` get it and
        the Hermite weights; the other connectors' predictors extrapolate the
        states alone, with the states' Lagrange weights.
        """
        factors = [lam for _, lam in history]
        states = np.array([q for q, _ in history])
        if slope is None:
            weights, slope_weight = lagrange_weights(factors, factor), 0.0
            guess = self._combine(weights, states)
        else:
            weights, slope_weight = hermite_weights(factors, factor)
            guess = self._combine(weights, states)
            guess += slope_weight * slope
        if self._predictors:
            if past is None:
                past = [self.remembered(q) for q, _ in history]
            poses = self.extended(guess)
            now, states_weights = None, weights
            for k, (group, run, internal, predictor) in enumerate(self._predictors):
                if predictor is not None:
                    memories = np.array([state[k] for state in past])
                    if slope is None:
                        guess[internal] = predictor[1](memories, np.asarray(weights, float), poses)
                    else:
                        guess[internal] = predictor[1](
                            memories,
                            np.asarray(weights, float),
                            poses,
                            np.concatenate([slope, np.zeros(3)]),
                            slope_weight,
                        )
                    continue
                if now is None:  # the guess as the predictions before this one found it
                    now = self.local_states(poses[: guess.size])
                    if slope is not None:
                        states_weights = lagrange_weights(factors, factor)
                guess[internal] = group.predict_internal(
                    [state[k] for state in past], states_weights, [state[:2] for state in now[run]]
                )
        return guess

    @staticmethod
    def _combine(weights: Sequence[float], states: np.ndarray) -> np.ndarray:
        """sum(w_i q_i) over the states (k, n): one BLAS product."""
        return np.dot(weights, states)

    def validity(self, q: np.ndarray) -> list[str]:
        """Every connector's reasons why state q is outside its model's range of meaning.

        Each reason is prefixed with the connector's name; empty: valid
        (see :meth:`Connector.validity`).
        """
        return [
            f"{c.name}: {why}"
            for c, local in zip(self.connectors, self.local_states(q))
            for why in c.validity(*local)
        ]

    def motion_ratio(self, q0: np.ndarray, q1: np.ndarray) -> float:
        """Largest body motion from q0 to q1 over the settings' step bounds (> 1: too far)."""
        s = self.settings
        poses = 3 * len(self.body_index)  # the bodies' coordinates come first
        # plain floats in one loop: a mechanism has a few bodies, and numpy calls (or
        # list slices and maps) cost more than the sums
        before, after = q0[:poses].tolist(), q1[:poses].tolist()
        rotation = translation = 0.0
        for k in range(0, poses, 3):
            turn = abs(after[k + 2] - before[k + 2])
            shift = math.hypot(after[k] - before[k], after[k + 1] - before[k + 1])
            if turn > rotation:
                rotation = turn
            if shift > translation:
                translation = shift
        return max(
            rotation / s.max_rotation_step, translation / (s.max_translation_step * self.size)
        )

    def unstable(self, tangent: Tangent | None) -> bool:
        """True if the tangent has more negative eigenvalues than the system has multipliers.

        Each Lagrange multiplier makes a stable saddle-point tangent one
        eigenvalue indefinite; an inertia that cannot be judged (or no
        tangent) counts as stable, and so does every state of a System whose
        rule cannot judge its rest state (:meth:`judges_stability`).
        """
        negative = self.instability(tangent)
        return negative is not None and negative > 0 and self.judges_stability()

    def resolves(self, rest: Tangent | None) -> bool:
        """Whether double precision resolves this System: its tangent at rest proves positive
        definite.

        The unloaded mechanism is a stable structure, so without multipliers
        its tangent at rest is positive definite and its Cholesky succeeds.
        Where it fails, the stiffest and softest parts of the System (the
        axial stiffness of the shortest element, the bending of the whole
        flexure) lie further apart than the arithmetic's 16 digits: Newton's
        corrections are then round-off and the path cannot be traced (beams of
        about 10^4 elements per flexure on the paper's scenes). Saddle points,
        and tangents without a Cholesky, are taken as resolved.
        """
        if rest is None or self.n_multipliers:
            return True
        return bool(rest.positive_definite())

    def judges_stability(self) -> bool:
        """Whether the stability rule can judge this System's states (computed once, on the
        first unstable verdict).

        The unloaded mechanism at rest is a stable structure (a scene is
        checked to be one), so its tangent has no negative eigenvalue. Where
        the rule still counts one there, the resolution is beyond what double
        precision can judge (a beam of 10^4 or more elements per flexure: its
        tip pivots are formed from terms 10^12 times larger), and no state of
        the System is judged: its paths carry :meth:`stability_note`.
        """
        return self._rest_instability() == 0

    def _rest_instability(self) -> int:
        """The rule's count (:meth:`instability`) on the tangent at rest, computed once (0
        where it cannot be judged): 0 for a stable structure the rule resolves, positive
        beyond what double precision resolves, negative where the tangent is singular along
        a constraint (:meth:`check_drive`)."""
        if self._rest_negative is None:
            from flexval.geometry import Moment

            rest = LoadCase("rest", (Moment(self.mechanism.target_body, 0.0),), 2)
            tangent = self.assemble(self.initial_state(), self.loads(rest), 0.0)[2]
            self._rest_negative = self.instability(tangent) or 0
        return self._rest_negative

    def stability_note(self) -> str | None:
        """Why this System's stability verdicts are not judged (None: they are, or no state
        was found unstable)."""
        if not self._rest_negative:
            return None
        return (
            "not judged: the tangent at rest, stable by construction, already counts "
            f"{self._rest_negative} negative pivot(s) beyond round-off (the resolution is "
            "beyond what double precision can judge)"
        )

    def instability(self, tangent: Tangent | None) -> int | None:
        """The tangent's negative eigenvalues beyond those its multipliers make (None: not judged).

        Zero on a stable equilibrium; it changes where the path passes a
        limit point or a bifurcation (an eigenvalue of the tangent crosses
        zero). Counted by the one rule of
        :mod:`flexval.reducedmodels.core.stability` (each pivot against its own
        round-off), so the count does not depend on the units or the
        resolution.
        """
        if tangent is None:
            return None
        negative = tangent.negative_eigenvalues()
        return None if negative is None else negative - self.n_multipliers

    def residual(self, grad: np.ndarray, loads: Loads) -> float:
        """Largest out-of-balance force (moments per unit size) relative to the load scale."""
        return float(np.maximum.reduce(np.abs(grad * self.force_scale), initial=0.0)) / loads.scale

    def scaled(self, v: np.ndarray) -> np.ndarray:
        """Dimensionless version of a coordinate vector (lengths / size, angles as is)."""
        return v / self._coordinate_scale


def case_loads(
    case: LoadCase,
    pose_dofs,
    reference: dict,
    size: float,
    connectors: Sequence[Connector],
    multipliers: tuple[np.ndarray, np.ndarray] | None = None,
) -> Loads:
    """Dead loads of ``case`` at full value, numbered by ``pose_dofs(body)`` (see
    :meth:`System.loads`): the bodies' reference points (mm), the mechanism's size (mm) and
    the connectors, whose own dead loads (``dead_load_scale``, N) join the force scale;
    ``multipliers``: a drive's (:meth:`System.drive_loads`)."""
    loads = Loads.of_case(case, pose_dofs, reference, size, multipliers)
    loads.scale = max([loads.scale, *(c.dead_load_scale for c in connectors)])
    return loads


def connector_groups(connectors: Sequence[Connector]) -> list[tuple[ConnectorGroup, slice]]:
    """The runs of consecutive connectors of one class, each with its group and its slice.

    Runs keep the connectors' order, so the concatenated gradients and
    Hessians are the same as evaluated one by one.
    """
    runs, start = [], 0
    for kind, run in itertools.groupby(map(type, connectors)):  # one pass in C
        stop = start + len(list(run))
        runs.append((kind, slice(start, stop)))
        start = stop
    return [(kind.group(connectors[run]), run) for kind, run in runs]
