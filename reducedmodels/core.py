"""The quasi-static multibody core shared by every flexibility model.

Unknowns are the poses (x, y, theta) of the non-ground rigid bodies plus the
private internal coordinates of the connectors (beam nodes, continuum nodes,
DCMM intermediate bodies ...). Every connector is conservative: it returns
its strain energy, gradient (internal forces) and Hessian (consistent
tangent) from the poses of the two bodies it joins and its internal
coordinates. Dead loads add their potential. Equilibrium is
grad(Pi) = 0, solved by Newton-Raphson with the exact tangent and adaptive
load stepping. Open and closed chains need no special code: a closed chain
is a connector graph with a loop.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import NamedTuple, Protocol, Sequence

import numpy as np
import scipy.sparse as sp

from geometry import Force, LoadCase, Mechanism, Moment

from .loadpath import LoadPath
from .rigid import rigid_points
from .tangent import Tangent, TangentLayout


class Connector(Protocol):
    """A flexure model between two bodies.

    Its local coordinate vector is ``[pose_a (3), pose_b (3), internal
    (n_internal)]`` with ``(a, b) = bodies``. A connector with a sparse
    Hessian also defines ``hessian_pattern()``, returning the local
    (rows, cols) of its entries, fixed for its lifetime; its ``evaluate``
    then returns the Hessian as the values of those entries. Without it the
    Hessian is a dense (6 + n_internal) square array.
    """

    name: str
    bodies: tuple[str, str]
    n_internal: int
    #: how many internal coordinates are Lagrange multipliers (optional, default 0);
    #: each makes the tangent one negative eigenvalue indefinite at a stable state
    n_multipliers: int

    def initial_internal(self) -> np.ndarray:
        """Internal coordinates in the undeformed configuration."""
        ...

    def internal_is_rotation(self) -> np.ndarray:
        """Boolean mask (n_internal,): True where an internal coordinate is an angle."""
        ...

    def evaluate(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
                 ) -> tuple[float, np.ndarray, np.ndarray]:
        """Energy (N mm), gradient (6 + n) and Hessian (dense square, or pattern values)."""
        ...

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Deformed centre line as points (m, 2), mm (for plots)."""
        ...


def local_hessian(connector: Connector, hessian: np.ndarray) -> np.ndarray | sp.csc_matrix:
    """The Hessian returned by ``connector.evaluate`` as a matrix over its local coordinates.

    Dense connectors return it as is; for a connector with a
    ``hessian_pattern`` the values become a CSC matrix (duplicates summed).
    """
    pattern = getattr(connector, "hessian_pattern", None)
    if pattern is None:
        return np.asarray(hessian)
    n = 6 + connector.n_internal
    return sp.csc_matrix((hessian, pattern()), shape=(n, n))


class SolverError(RuntimeError):
    """The solver could not reach the requested load.

    Attributes
    ----------
    load_factor : float
        The last converged load factor (0..1).
    path : LoadPath or None
        The levels converged before the failure.
    """

    def __init__(self, message: str, load_factor: float, path: LoadPath | None = None):
        super().__init__(message)
        self.load_factor = load_factor
        self.path = path


@dataclass
class SolverSettings:
    """Newton and load-stepping parameters (dimensionless unless stated).

    ``force_tol`` is relative to the full-load magnitude, ``step_tol`` is the
    scaled correction (translations / mechanism size, rotations in rad): since
    Newton converges quadratically, the error left after a correction of
    1e-8 is of order 1e-16. ``error_tol`` bounds the error left after a
    correction as estimated from the contraction of the last two (see
    :func:`newton`); 1e-10 keeps equilibrium to ~1e-8 of the load even on
    stiff (axial) modes.
    ``max_rotation_step`` (rad) and ``max_translation_step`` (fraction of the
    mechanism size) bound how far any body may move in one sub-step, so the
    stepping follows soft stretches of the path instead of leaping over them.
    ``max_excursion`` abandons a Newton iteration whose iterates move a body
    that many times the sub-step bounds (the step is cut instead);
    ``max_stall`` abandons one whose residual has not improved on its best
    value for that many iterations (wandering along a soft mode).
    ``check_stability`` rejects a sub-step whose equilibrium is unstable
    (load control cannot pass a limit point; use arc-length continuation).
    """

    force_tol: float = 1e-10
    step_tol: float = 1e-8
    error_tol: float = 1e-10
    max_iterations: int = 25
    max_cuts: int = 40
    max_substeps: int = 20000
    max_rotation_step: float = 0.25
    max_translation_step: float = 0.05
    fast_iterations: int = 5
    max_excursion: float = 4.0
    max_stall: int = 5
    check_stability: bool = True


@dataclass
class _Loads:
    """Dead loads of one load case, at full value, ready for the potential."""

    dofs: np.ndarray          # (k, 3) global dofs of the loaded body (-1: ground)
    forces: np.ndarray        # (k, 2) force vectors, N
    rels: np.ndarray          # (k, 2) point offsets from the body reference, mm
    moment_dofs: np.ndarray   # (j,) global theta dofs
    moments: np.ndarray       # (j,) N mm
    scale: float              # force scale for tolerances, N


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
        self.reference = {b: mech.bodies[b].reference for b in mech.bodies}
        n = 3 * len(self.body_index)
        self._local_to_global = []
        rot_mask = [np.tile([False, False, True], len(self.body_index))]
        for c in self.connectors:
            idx = np.concatenate([self.pose_dofs(c.bodies[0]), self.pose_dofs(c.bodies[1]),
                                  n + np.arange(c.n_internal)])
            self._local_to_global.append(idx)
            rot_mask.append(np.asarray(c.internal_is_rotation(), bool))
            n += c.n_internal
        self.n_dofs = n
        self.is_rotation = np.concatenate(rot_mask)
        self.n_multipliers = sum(getattr(c, "n_multipliers", 0) for c in self.connectors)
        #: residual weights: forces as is, moments per unit of mechanism size (N)
        self.force_scale = np.where(self.is_rotation, 1.0 / self.size, 1.0)
        # connectors that predict or update their internal coordinates themselves
        self._predictors = [(k, c.predict_internal) for k, c in enumerate(self.connectors)
                            if c.n_internal and hasattr(c, "predict_internal")]
        self._updaters = [(k, c.update_internal) for k, c in enumerate(self.connectors)
                          if c.n_internal and hasattr(c, "update_internal")]
        self._build_scatter()

    def _build_scatter(self) -> None:
        """Index maps of the assembly, computed once (the sparsity pattern never changes).

        * ``_gather[k]``: positions of connector k's local coordinates in
          ``[q, ground pose]`` (ground dofs read the fixed ground pose);
        * ``_grad_dofs`` / ``_grad_keep``: global dof of every kept entry of the
          concatenated local gradients (ground entries dropped);
        * ``_hess_keep``: kept entries of the concatenated local Hessian values;
          the tangent layout adds one diagonal slot per dof for the loads.
        """
        n = self.n_dofs
        gathers, grad_idx, rows, cols, hess_keep = [], [], [], [], []
        for c, idx in zip(self.connectors, self._local_to_global):
            gathers.append(np.where(idx >= 0, idx, n + np.arange(idx.size) % 3))
            grad_idx.append(idx)
            pattern = getattr(c, "hessian_pattern", None)
            if pattern is None:
                r, cc = np.repeat(idx, idx.size), np.tile(idx, idx.size)
            else:
                lr, lc = pattern()
                r, cc = idx[lr], idx[lc]
            keep = (r >= 0) & (cc >= 0)
            rows.append(r[keep]), cols.append(cc[keep]), hess_keep.append(keep)
        ground = self.reference[self.mechanism.ground]
        self._ground_pose = np.array([ground[0], ground[1], 0.0])
        self._gather = gathers
        all_grad = np.concatenate(grad_idx) if grad_idx else np.zeros(0, int)
        self._grad_keep = all_grad >= 0
        self._grad_dofs = all_grad[self._grad_keep]
        self._hess_keep = np.concatenate([*hess_keep, np.ones(n, bool)])
        diagonal = np.arange(n)
        self.layout = TangentLayout(n, np.concatenate([*rows, diagonal]),
                                    np.concatenate([*cols, diagonal]), self.n_multipliers)

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
            q[3 * k:3 * k + 2] = self.reference[b]
        for c, idx in zip(self.connectors, self._local_to_global):
            q[idx[6:]] = c.initial_internal()
        return q

    def pose(self, q: np.ndarray, body: str) -> np.ndarray:
        """Pose (x, y, theta) of ``body`` in state q (ground: fixed)."""
        if body == self.mechanism.ground:
            return self._ground_pose.copy()
        k = self.body_index[body]
        return q[3 * k:3 * k + 3]

    def local_states(self, q: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """(pose_a, pose_b, internal) of every connector in state q."""
        extended = np.concatenate([q, self._ground_pose])
        out = []
        for gather in self._gather:
            local = extended[gather]
            out.append((local[:3], local[3:6], local[6:]))
        return out

    # --- loads -----------------------------------------------------------
    def loads(self, case: LoadCase) -> _Loads:
        """Dead loads of ``case`` at full value in global dof numbering."""
        fd, ff, fr, md, mv = [], [], [], [], []
        for comp in case.components:
            dofs = self.pose_dofs(comp.body)
            if isinstance(comp, Force):
                fd.append(dofs)
                ff.append(comp.vector)
                fr.append(np.asarray(comp.point, float) - self.reference[comp.body])
            elif isinstance(comp, Moment):
                md.append(dofs[2])
                mv.append(comp.value)
        forces = np.array(ff).reshape(-1, 2)
        moments = np.array(mv, float)
        scale = max([float(np.abs(forces).max(initial=0.0)),
                     float(np.abs(moments).max(initial=0.0)) / self.size, 1e-300])
        return _Loads(np.array(fd, int).reshape(-1, 3), forces, np.array(fr).reshape(-1, 2),
                      np.array(md, int), moments, scale)

    # --- assembly --------------------------------------------------------
    def assemble(self, q: np.ndarray, loads: _Loads, factor: float
                 ) -> tuple[float, np.ndarray, Tangent]:
        """Total potential (N mm), its gradient and the tangent at state q and load factor.

        Every connector is evaluated once; the gradients and Hessian values
        are scattered with the index maps of :meth:`_build_scatter` into the
        storage the :class:`~reducedmodels.tangent.TangentLayout` chose.
        """
        energy = 0.0
        grads, hessians = [], []
        for c, local in zip(self.connectors, self.local_states(q)):
            e, g, h = c.evaluate(*local)
            energy += e
            grads.append(g)
            hessians.append(h.ravel())
        n = self.n_dofs
        grad = (np.bincount(self._grad_dofs, weights=np.concatenate(grads)[self._grad_keep],
                            minlength=n) if grads else np.zeros(n))
        diagonal = np.zeros(n)
        # dead forces at material points, x = p + R(theta) rel: potential -factor f.x
        for (ix, iy, it), (fx, fy), (rx, ry) in zip(loads.dofs.tolist(), loads.forces.tolist(),
                                                    loads.rels.tolist()):
            if ix < 0:
                continue
            c, s = math.cos(q[it]), math.sin(q[it])
            rrx, rry = c * rx - s * ry, s * rx + c * ry              # R(theta) rel
            energy -= factor * (fx * (q[ix] + rrx) + fy * (q[iy] + rry))
            grad[ix] -= factor * fx
            grad[iy] -= factor * fy
            grad[it] -= factor * (fy * rrx - fx * rry)              # f . dx/dtheta
            diagonal[it] += factor * (fx * rrx + fy * rry)          # -f . d2x/dtheta2
        for dof, m in zip(loads.moment_dofs.tolist(), loads.moments.tolist()):
            if dof >= 0:
                energy -= factor * m * q[dof]
                grad[dof] -= factor * m
        values = np.concatenate([*hessians, diagonal])
        return energy, grad, self.layout.build(values[self._hess_keep])

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
                    total += g[3 * k:3 * k + 3]
        return total

    # --- outputs ---------------------------------------------------------
    def target(self, q: np.ndarray) -> tuple[float, float, float]:
        """Target point displacement (dx, dy) in mm and target body rotation in rad."""
        mech = self.mechanism
        pose = self.pose(q, mech.target_body)
        rel = mech.target_point - self.reference[mech.target_body]
        x, _, _ = rigid_points(pose, rel[None])
        d = x[0] - mech.target_point
        return float(d[0]), float(d[1]), float(pose[2])

    def update(self, q: np.ndarray, du: np.ndarray) -> np.ndarray:
        """State after the Newton correction du: q + du, or a connector's own update.

        A connector may map its internal coordinates nonlinearly
        (``update_internal(old_local, new_local)``), provided the map equals
        q + du to first order so that Newton stays quadratic.
        """
        new = q + du
        if self._updaters:
            before, after = self.local_states(q), self.local_states(new)
            for k, update in self._updaters:
                new[self._local_to_global[k][6:]] = update(before[k], after[k])
        return new

    def residual(self, grad: np.ndarray, loads: _Loads) -> float:
        """Largest out-of-balance force (moments per unit size) relative to the load scale."""
        return float(np.abs(grad * self.force_scale).max(initial=0.0)) / loads.scale

    def scaled(self, v: np.ndarray) -> np.ndarray:
        """Dimensionless version of a coordinate vector (lengths / size, angles as is)."""
        return np.where(self.is_rotation, v, v / self.size)


CONTRACTION_EVIDENCE = 1e-3
"""Residual drop (relative to the first iterate) that shows Newton is contracting."""


EXCURSION_CHECK = 1e-3
"""Scaled correction below which an iterate cannot newly leave the sub-step's bounds
(they are 0.25 rad and 0.05 of the size; a smaller correction only matters
right at the edge, where the next large one is caught)."""


NONLINEAR_UPDATE = 1e-3
"""Scaled correction above which connectors apply their own nonlinear update.
Below it the second-order stretch a linear update leaves in a turning chord,
(correction)^2 / 2 < 5e-7, no longer costs iterations, and q + du is cheaper."""


class NewtonResult(NamedTuple):
    """Outcome of :func:`newton` at one load factor.

    ``state`` is None on failure, with ``reason`` saying why. ``tangent`` is
    the tangent at the last assembled iterate: at the converged state when
    the residual test ended the iteration, else one correction before it
    (close enough to judge stability: its eigenvalues differ by O(|du|)).
    """

    state: np.ndarray | None
    iterations: int
    reason: str
    tangent: Tangent | None


def newton(system: System, q: np.ndarray, loads: _Loads, factor: float,
           settings: SolverSettings, origin: np.ndarray | None = None) -> NewtonResult:
    """Newton-Raphson with the exact tangent at a fixed load factor.

    Converged when the residual is below ``force_tol`` (relative to the load
    scale), when the last correction du_k is below ``step_tol`` (scaled
    coordinates), or when the error it leaves, estimated from the
    contraction of the last two corrections as |du_k| min(1, |du_k| /
    |du_(k-1)|) (an over-estimate under quadratic convergence), is below
    ``error_tol``. The estimate is trusted only once the iteration is seen to
    contract (the residual has fallen below ``CONTRACTION_EVIDENCE`` of its
    first value): a stiff membrane mode can carry a large force on a tiny
    correction before Newton has found its basin. So the iteration stops as
    soon as the answer is known, instead of spending one more assembly and
    solve to prove it.

    Newton that has lost its way is abandoned early, since cutting the load
    step is cheaper than letting it wander to ``max_iterations``: when the
    residual has not improved on its best value for ``max_stall``
    iterations, or, with ``origin`` (the state where the sub-step started),
    when an iterate moves a body more than ``max_excursion`` times the
    sub-step bounds away from it.
    """
    res0, best, stalled, last_step = None, math.inf, 0, None
    for it in range(settings.max_iterations + 1):
        try:
            _, g, K = system.assemble(q, loads, factor)
        except (ValueError, FloatingPointError) as exc:   # a connector refused the state
            return NewtonResult(None, it, f"invalid state ({exc})", None)
        res = system.residual(g, loads)
        if not np.isfinite(res):
            return NewtonResult(None, it, "non-finite residual", None)
        if res <= settings.force_tol:
            return NewtonResult(q, it, "", K)
        res0 = res if res0 is None else res0
        if res > 1e8 * max(res0, 1.0):
            return NewtonResult(None, it, f"diverging residual {res:.3g}", None)
        best, stalled = (res, 0) if res < best else (best, stalled + 1)
        if stalled >= settings.max_stall:
            return NewtonResult(None, it, f"stalled (no lower residual in {stalled} iterations, "
                                f"best {best:.3g})", None)
        if it == settings.max_iterations:
            break
        try:
            du = K.solve(-g)
        except (RuntimeError, np.linalg.LinAlgError) as exc:  # singular factor
            return NewtonResult(None, it, f"singular tangent ({exc})", None)
        step = float(np.abs(system.scaled(du)).max(initial=0.0))
        if not math.isfinite(step):
            return NewtonResult(None, it, "singular tangent", None)
        q = system.update(q, du) if step > NONLINEAR_UPDATE else q + du
        contracting = last_step is not None and res <= CONTRACTION_EVIDENCE * res0
        if step <= settings.step_tol or (contracting and step * min(1.0, step / last_step)
                                         <= settings.error_tol):
            return NewtonResult(q, it + 1, "", K)
        last_step = step
        if (origin is not None and step > EXCURSION_CHECK
                and _motion_ratio(system, origin, q, settings) > settings.max_excursion):
            return NewtonResult(None, it + 1, "iterates left the sub-step's bounds", None)
    return NewtonResult(None, settings.max_iterations,
                        f"no convergence in {settings.max_iterations} iterations "
                        f"(residual {res:.3g})", None)


def _motion_ratio(system: System, q0: np.ndarray, q1: np.ndarray, s: SolverSettings) -> float:
    """Largest body motion of a sub-step relative to its bound (> 1: too far)."""
    dq = np.abs(q1 - q0)[: 3 * len(system.body_index)].reshape(-1, 3)
    if dq.size == 0:
        return 0.0
    return float(max(dq[:, 2].max() / s.max_rotation_step,
                     np.hypot(dq[:, 0], dq[:, 1]).max()
                     / (s.max_translation_step * system.size)))


def _unstable(system: System, tangent: Tangent) -> bool:
    """True if the tangent has more negative eigenvalues than the system has multipliers.

    Each Lagrange multiplier makes a stable saddle-point tangent one
    eigenvalue indefinite; an inertia that cannot be judged counts as stable.
    """
    negative = tangent.negative_eigenvalues()
    return negative is not None and negative > system.n_multipliers


def lagrange_weights(factors: Sequence[float], factor: float) -> list[float]:
    """Weights of the Lagrange polynomial through ``factors`` evaluated at ``factor`` (sum 1)."""
    weights = []
    for i, li in enumerate(factors):
        w = 1.0
        for j, lj in enumerate(factors):
            if j != i:
                w *= (factor - lj) / (li - lj)
        weights.append(w)
    return weights


def extrapolate(system: System, history: Sequence[tuple[np.ndarray, float]], factor: float
                ) -> np.ndarray:
    """Predicted state at ``factor`` from up to three converged (state, factor) pairs.

    Coordinates are extrapolated by the Lagrange polynomial through the
    history (quadratic from three states: an O(h^3) error where the secant's
    is O(h^2)). A connector may predict its own internal coordinates
    instead (``predict_internal(states, weights, pose_a, pose_b)``, with its
    local states along the history, the weights and its bodies' predicted
    poses): nearly inextensible flexures extrapolated node by node in
    Cartesian coordinates come out stretched, and Newton then spends
    iterations pulling the stretch back out.
    """
    weights = lagrange_weights([lam for _, lam in history], factor)
    guess = sum(w * q for w, (q, _) in zip(weights, history))
    if system._predictors:
        past = [system.local_states(q) for q, _ in history]
        now = system.local_states(guess)
        for k, predict in system._predictors:
            guess[system._local_to_global[k][6:]] = predict([p[k] for p in past], weights,
                                                            now[k][0], now[k][1])
    return guess


def solve_path(system: System, case: LoadCase, levels: int | None = None,
               model: str = "", settings: dict | None = None, scene: str = "",
               record_poses: bool = False, record_shapes: bool = False,
               record_reactions: bool = False) -> LoadPath:
    """Trace the load path of ``case`` through its requested levels.

    Between two requested levels the load factor advances in sub-steps
    that are halved when Newton fails or a body moves more than the bounds in
    :class:`SolverSettings`, and doubled after easy steps; the reported
    levels are exactly the requested ones.

    Raises
    ------
    SolverError
        When step cutting cannot save a step; carries the last converged load
        factor and the partial LoadPath.
    """
    t0 = time.perf_counter()
    s = system.settings
    loads = system.loads(case)
    factors = case.factors(levels)
    q = system.initial_state()
    lp = LoadPath(model=model, load_case=case.name, load=[], dx=[], dy=[], rotation=[],
                  seconds=0.0, settings=settings or {}, scene=scene, load_unit=case.unit,
                  poses={b: [] for b in system.mechanism.bodies} if record_poses else None,
                  shapes={c.name: [] for c in system.connectors} if record_shapes else None,
                  reactions=[] if record_reactions else None)
    stats = {"unknowns": system.n_dofs, "newton_iterations": 0, "step_cuts": 0, "substeps": 0,
             "iterations": []}

    def record(qk: np.ndarray, lam: float, iters: int) -> None:
        dx, dy, rot = system.target(qk)
        lp.load.append(lam * case.magnitude)
        lp.dx.append(dx), lp.dy.append(dy), lp.rotation.append(rot)
        if lp.reactions is not None:
            lp.reactions.append(system.reaction(qk).tolist())
        stats["iterations"].append(iters)
        if lp.poses is not None:
            for b in system.mechanism.bodies:
                lp.poses[b].append(system.pose(qk, b).tolist())
        if lp.shapes is not None:
            for c, local in zip(system.connectors, system.local_states(qk)):
                lp.shapes[c.name].append(c.shape(*local).tolist())

    def fail(msg: str, lam: float) -> SolverError:
        stats["failure"] = msg
        lp.converged, lp.stats = False, stats
        lp.seconds = time.perf_counter() - t0
        return SolverError(f"{model or 'model'} on load case '{case.name}': {msg}; last converged "
                           f"load {lam * case.magnitude:.6g} {case.unit} "
                           f"({100 * lam:.2f} % of full load)", lam, lp)

    first = newton(system, q, loads, factors[0], s)
    if first.state is None:
        raise fail(first.reason, 0.0)
    q, lam = first.state, factors[0]
    history = [(q, lam)]               # converged (state, factor) pairs for the predictor
    stats["newton_iterations"] += first.iterations
    record(q, lam, first.iterations)
    spacing = factors[1] - factors[0] if len(factors) > 1 else 1.0
    step = spacing
    min_step = spacing * 0.5 ** s.max_cuts
    for target in factors[1:]:
        level_iters = 0
        while lam < target - 1e-14 * spacing:
            trial = min(lam + step, target)
            result = newton(system, extrapolate(system, history, trial), loads, trial, s, origin=q)
            iters = result.iterations
            stats["newton_iterations"] += iters
            level_iters += iters
            q_new, why = result.state, result.reason
            ratio = _motion_ratio(system, q, q_new, s) if q_new is not None else math.inf
            if ratio <= 1.0 and s.check_stability and _unstable(system, result.tangent):
                q_new, ratio, why = None, math.inf, ("converged to an unstable equilibrium "
                                                     "(past a limit point?)")
            if ratio > 1.0:
                if q_new is not None:
                    why = "step too large"
                step *= 0.5
                stats["step_cuts"] += 1
                if step < min_step:
                    raise fail(f"step cutting failed ({why})", lam)
                continue
            q, lam = q_new, trial
            history = [*history[-2:], (q, lam)]
            stats["substeps"] += 1
            if stats["substeps"] > s.max_substeps:
                raise fail(f"more than {s.max_substeps} load sub-steps", lam)
            if iters <= s.fast_iterations and ratio < 0.5:
                step = min(2.0 * step, spacing)
        record(q, target, level_iters)
    lp.seconds = time.perf_counter() - t0
    lp.stats = stats
    return lp
