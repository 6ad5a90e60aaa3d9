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
from typing import Protocol, Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from geometry import Force, LoadCase, Mechanism, Moment

from .loadpath import LoadPath
from .rigid import rigid_points


DENSE_LIMIT = 96  # above ~100, multithreaded LAPACK stalls on a loaded 2-core machine (measured)


class Connector(Protocol):
    """A flexure model between two bodies.

    Its local coordinate vector is ``[pose_a (3), pose_b (3), internal
    (n_internal)]`` with ``(a, b) = bodies``.
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
                 ) -> tuple[float, np.ndarray, np.ndarray | sp.spmatrix]:
        """Energy (N mm), gradient (6 + n) and Hessian ((6 + n) square, dense or sparse)."""
        ...

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Deformed centre line as points (m, 2), mm (for plots)."""
        ...


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
    1e-8 is of order 1e-16.
    ``max_rotation_step`` (rad) and ``max_translation_step`` (fraction of the
    mechanism size) bound how far any body may move in one sub-step, so the
    stepping follows soft stretches of the path instead of leaping over them.
    ``check_stability`` rejects a sub-step whose equilibrium is unstable
    (load control cannot pass a limit point; use arc-length continuation).
    """

    force_tol: float = 1e-10
    step_tol: float = 1e-8
    max_iterations: int = 25
    max_cuts: int = 40
    max_substeps: int = 20000
    max_rotation_step: float = 0.25
    max_translation_step: float = 0.05
    fast_iterations: int = 5
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
        self._dense_pattern = {}
        self._csc_structure = None
        self.n_multipliers = sum(getattr(c, "n_multipliers", 0) for c in self.connectors)

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
            return np.array([*self.reference[body], 0.0])
        k = self.body_index[body]
        return q[3 * k:3 * k + 3]

    def _local(self, q: np.ndarray, c: Connector, idx: np.ndarray):
        return self.pose(q, c.bodies[0]), self.pose(q, c.bodies[1]), q[idx[6:]]

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
    def _pattern(self, k: int, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Scatter pattern of connector k's dense local Hessian (computed once).

        Returns global rows, global cols and the mask of local entries kept
        (entries of ground dofs are dropped).
        """
        if k not in self._dense_pattern:
            idx = self._local_to_global[k]
            rows, cols = np.repeat(idx, n), np.tile(idx, n)
            keep = (rows >= 0) & (cols >= 0)
            self._dense_pattern[k] = (rows[keep], cols[keep], keep)
        return self._dense_pattern[k]

    def assemble(self, q: np.ndarray, loads: _Loads, factor: float,
                 ) -> tuple[float, np.ndarray, np.ndarray | sp.csc_matrix]:
        """Total potential (N mm), its gradient and Hessian at state q and load factor.

        The Hessian is a dense array for small systems (at most ``DENSE_LIMIT``
        unknowns, where LAPACK beats sparse overheads) and CSC otherwise.
        """
        dense = self.n_dofs <= DENSE_LIMIT
        energy = 0.0
        grad = np.zeros(self.n_dofs)
        K = np.zeros((self.n_dofs, self.n_dofs)) if dense else None
        rows, cols, vals = [], [], []
        for k, (c, idx) in enumerate(zip(self.connectors, self._local_to_global)):
            e, g, h = c.evaluate(*self._local(q, c, idx))
            energy += e
            keep = idx >= 0
            grad[idx[keep]] += g[keep]          # a connector's dofs are distinct
            if dense:
                h = h.toarray() if sp.issparse(h) else np.asarray(h)
                r, cc, m = self._pattern(k, idx.size)
                K[r, cc] += h.ravel()[m]
            elif sp.issparse(h):
                h = h.tocoo()
                r, cc = idx[h.row], idx[h.col]
                m = (r >= 0) & (cc >= 0)
                rows.append(r[m]), cols.append(cc[m]), vals.append(h.data[m])
            else:
                r, cc, m = self._pattern(k, idx.size)
                rows.append(r), cols.append(cc), vals.append(np.asarray(h).ravel()[m])
        # dead forces at material points and moments: potential -factor * work
        for dofs, f, rel in zip(loads.dofs, loads.forces, loads.rels):
            if dofs[0] < 0:
                continue
            x, jac, d2 = rigid_points(q[dofs], rel[None])
            energy -= factor * f @ x[0]
            grad[dofs] -= factor * jac[0].T @ f
            if dense:
                K[dofs[2], dofs[2]] -= factor * f @ d2[0]
            else:
                rows.append([dofs[2]]), cols.append([dofs[2]]), vals.append([-factor * f @ d2[0]])
        for dof, m in zip(loads.moment_dofs, loads.moments):
            if dof >= 0:
                energy -= factor * m * q[dof]
                grad[dof] -= factor * m
        if not dense:
            K = self._csc(np.concatenate(rows), np.concatenate(cols), np.concatenate(vals))
        return energy, grad, K

    def _csc(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray) -> sp.csc_matrix:
        """Sum COO triplets into CSC, reusing the structure while the pattern is unchanged.

        Connectors return the same sparsity pattern at every call, so the
        sorting and duplicate summation of a COO -> CSC conversion is done once;
        afterwards one ``bincount`` scatters the values (checked: a changed
        pattern rebuilds the structure).
        """
        cached = self._csc_structure
        if cached is None or cached[0].shape != rows.shape or not (
                np.array_equal(cached[0], rows) and np.array_equal(cached[1], cols)):
            n = self.n_dofs
            uniq, inverse = np.unique(cols.astype(np.int64) * n + rows, return_inverse=True)
            indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)
            cached = (rows, cols, inverse.ravel(), (uniq % n).astype(np.int32), indptr)
            self._csc_structure = cached
        _, _, inverse, indices, indptr = cached
        data = np.bincount(inverse, weights=vals, minlength=indices.size)
        return sp.csc_matrix((data, indices, indptr), shape=(self.n_dofs, self.n_dofs))

    def reaction(self, q: np.ndarray) -> np.ndarray:
        """Force (N) and moment (N mm, about the ground's reference point) the ground exerts."""
        total = np.zeros(3)
        g_name = self.mechanism.ground
        for c, idx in zip(self.connectors, self._local_to_global):
            if g_name not in c.bodies:
                continue
            _, g, _ = c.evaluate(*self._local(q, c, idx))
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

    def scaled(self, v: np.ndarray) -> np.ndarray:
        """Dimensionless version of a coordinate vector (lengths / size, angles as is)."""
        return np.where(self.is_rotation, v, v / self.size)


def _newton(system: System, q: np.ndarray, loads: _Loads, factor: float,
            settings: SolverSettings) -> tuple[np.ndarray | None, int, str]:
    """Newton-Raphson at a fixed load factor; returns (state or None, iterations, reason)."""
    f_scale = np.where(system.is_rotation, 1.0 / system.size, 1.0)
    res0 = None
    for it in range(settings.max_iterations + 1):
        try:
            _, g, K = system.assemble(q, loads, factor)
        except (ValueError, FloatingPointError) as exc:   # a connector refused the state
            return None, it, f"invalid state ({exc})"
        res = float(np.abs(g * f_scale).max(initial=0.0)) / loads.scale
        if not np.isfinite(res):
            return None, it, "non-finite residual"
        if res <= settings.force_tol:
            return q, it, ""
        res0 = res if res0 is None else res0
        if res > 1e8 * max(res0, 1.0):
            return None, it, f"diverging residual {res:.3g}"
        if it == settings.max_iterations:
            break
        try:
            du = np.linalg.solve(K, -g) if isinstance(K, np.ndarray) else spla.spsolve(K, -g)
        except (RuntimeError, np.linalg.LinAlgError) as exc:  # singular factor
            return None, it, f"singular tangent ({exc})"
        if not np.all(np.isfinite(du)):
            return None, it, "singular tangent"
        q = q + du
        if float(np.abs(system.scaled(du)).max(initial=0.0)) <= settings.step_tol:
            return q, it + 1, ""
    return None, settings.max_iterations, f"no convergence in {settings.max_iterations} iterations (residual {res:.3g})"


def negative_pivots(K: np.ndarray | sp.csc_matrix) -> int | None:
    """Number of negative eigenvalues of the symmetric tangent K (Sylvester's inertia).

    Dense: from the eigenvalues. Sparse: the signs of the pivots of a
    symmetric-mode LU with diagonal pivoting (an LDL^T under a symmetric
    permutation). Returns None when that factorisation breaks down (a zero
    pivot), in which case stability is not judged. Values below 1e-12 of the
    largest in magnitude count as round-off, not as negative.
    """
    if isinstance(K, np.ndarray):
        ev = np.linalg.eigvalsh(K)
        return int(np.sum(ev < -1e-12 * np.abs(ev).max(initial=0.0)))
    try:
        lu = spla.splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError:
        return None
    d = lu.U.diagonal()
    return int(np.sum(d < -1e-12 * np.abs(d).max(initial=0.0)))


def _unstable(system: System, q: np.ndarray, loads: _Loads, factor: float) -> bool:
    """True if the equilibrium q has more negative tangent eigenvalues than multipliers.

    Large saddle-point systems (sparse, with multipliers) are not judged: a
    diagonal-pivot LDL^T breaks down on the multipliers' zero diagonal.
    """
    _, _, K = system.assemble(q, loads, factor)
    if not isinstance(K, np.ndarray) and system.n_multipliers:
        return False
    neg = negative_pivots(K)
    return neg is not None and neg > system.n_multipliers


def _motion_ratio(system: System, q0: np.ndarray, q1: np.ndarray, s: SolverSettings) -> float:
    """Largest body motion of a sub-step relative to its bound (> 1: too far)."""
    dq = np.abs(q1 - q0)[: 3 * len(system.body_index)].reshape(-1, 3)
    if dq.size == 0:
        return 0.0
    return float(max(dq[:, 2].max() / s.max_rotation_step,
                     np.hypot(dq[:, 0], dq[:, 1]).max()
                     / (s.max_translation_step * system.size)))


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
            for c, idx in zip(system.connectors, system._local_to_global):
                lp.shapes[c.name].append(c.shape(*system._local(qk, c, idx)).tolist())

    def fail(msg: str, lam: float) -> SolverError:
        stats["failure"] = msg
        lp.converged, lp.stats = False, stats
        lp.seconds = time.perf_counter() - t0
        return SolverError(f"{model or 'model'} on load case '{case.name}': {msg}; last converged "
                           f"load {lam * case.magnitude:.6g} {case.unit} "
                           f"({100 * lam:.2f} % of full load)", lam, lp)

    q_new, iters, why = _newton(system, q, loads, factors[0], s)
    if q_new is None:
        raise fail(why, 0.0)
    q, lam, prev = q_new, factors[0], None
    stats["newton_iterations"] += iters
    record(q, lam, iters)
    spacing = factors[1] - factors[0] if len(factors) > 1 else 1.0
    step = spacing
    min_step = spacing * 0.5 ** s.max_cuts
    for target in factors[1:]:
        level_iters = 0
        while lam < target - 1e-14 * spacing:
            trial = min(lam + step, target)
            # secant predictor from the previous converged sub-step
            guess = q if prev is None else q + (trial - lam) / (lam - prev[1]) * (q - prev[0])
            q_new, iters, why = _newton(system, guess, loads, trial, s)
            if q_new is None and prev is not None:
                q_new, iters2, why = _newton(system, q, loads, trial, s)
                iters += iters2
            stats["newton_iterations"] += iters
            level_iters += iters
            ratio = _motion_ratio(system, q, q_new, s) if q_new is not None else math.inf
            if ratio <= 1.0 and s.check_stability and _unstable(system, q_new, loads, trial):
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
            prev = (q, lam)
            q, lam = q_new, trial
            stats["substeps"] += 1
            if stats["substeps"] > s.max_substeps:
                raise fail(f"more than {s.max_substeps} load sub-steps", lam)
            if iters <= s.fast_iterations and ratio < 0.5:
                step = min(2.0 * step, spacing)
        record(q, target, level_iters)
    lp.seconds = time.perf_counter() - t0
    lp.stats = stats
    return lp
