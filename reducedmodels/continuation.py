"""Arc-length continuation (Riks / Crisfield) for paths with limit points.

Load control (:func:`reducedmodels.core.solve_path`) cannot pass a limit
point: beyond the largest load on the path there is no nearby equilibrium
and Newton fails. Arc-length continuation makes the load factor lambda an
unknown and adds one constraint on the size of each step,

    <dq, dq> + psi^2 dlambda^2 = dl^2,

where dq and dlambda are the increments from the last converged point and
<u, v> = mean(u_s v_s) over all coordinates scaled as in
:meth:`System.scaled` (lengths / mechanism size, angles in rad), so dl is
dimensionless and does not grow with the number of unknowns. psi = 0
(default) is Crisfield's cylindrical method, psi > 0 the spherical one.
Along the path the load may rise and fall; every converged point is kept.

Each corrector iteration solves K [dq_R, dq_F] = [-g, f] with one
factorisation (g: out-of-balance force, f: load vector at unit factor), sets
dq = dq_R + dlambda dq_F and takes dlambda from the quadratic constraint,
choosing the root whose new increment makes the smallest angle with the
previous one (Crisfield 1981; Crisfield 1991, Sect. 9.3). The first
predictor is the tangent K^-1 f, every later one the secant of the last
converged step, which continues through limit points in the direction of
travel. The arc length is halved when a step fails (no convergence, no real
root, a body moving more than the bounds of :class:`SolverSettings`, or a
corrector that converged back onto the path already traced) and
grown by 1.5 after easy steps (at most ``fast_iterations`` Newton iterations,
no cut), up to ``max_growth`` times its initial value.

Units: mm, N, N mm, rad; load factors are dimensionless.
"""

from __future__ import annotations

import math
import time
from typing import Callable

import numpy as np

from geometry import LoadCase

from .core import SolverError, System
from .loadpath import LoadPath
from .rigid import rigid_points


def load_vector(system: System, q: np.ndarray, loads) -> np.ndarray:
    """External generalised force at unit load factor in state q (N, N mm).

    Minus the derivative of the total-potential gradient with respect to the
    load factor: dead forces at material points (J^T F, J the point's
    Jacobian in the current pose) and moments on rotations.
    """
    f = np.zeros(system.n_dofs)
    for dofs, force, rel in zip(loads.dofs, loads.forces, loads.rels):
        if dofs[0] < 0:
            continue
        _, jac, _ = rigid_points(q[dofs], rel[None])
        f[dofs] += jac[0].T @ force
    for dof, m in zip(loads.moment_dofs, loads.moments):
        if dof >= 0:
            f[dof] += m
    return f


class _Path:
    """The arc-length inner product and the per-step safeguards of one System."""

    def __init__(self, system: System, loads, psi: float):
        self.system, self.loads, self.psi = system, loads, psi
        self.settings = system.settings
        self.f_scale = np.where(system.is_rotation, 1.0 / system.size, 1.0)
        self.n_bodies = len(system.body_index)

    def dot(self, u: np.ndarray, v: np.ndarray) -> float:
        """<u, v>: mean product of the scaled coordinates (dimensionless)."""
        return float(np.mean(self.system.scaled(u) * self.system.scaled(v)))

    def residual(self, g: np.ndarray) -> float:
        """Largest out-of-balance force relative to the full-load scale (as in the core)."""
        return float(np.abs(g * self.f_scale).max(initial=0.0)) / self.loads.scale

    def moved_too_far(self, dq: np.ndarray) -> bool:
        """True if a body turns or travels more than the SolverSettings bounds in one step."""
        d = np.abs(dq[:3 * self.n_bodies]).reshape(-1, 3)
        if d.size == 0:
            return False
        s = self.settings
        return bool(d[:, 2].max() > s.max_rotation_step
                    or np.hypot(d[:, 0], d[:, 1]).max() > s.max_translation_step * self.system.size)

    def correct(self, q0: np.ndarray, lam0: float, dq: np.ndarray, dlam: float, arc: float | None
                ) -> tuple[np.ndarray | None, float, int, str]:
        """Newton corrector from the predictor (q0 + dq, lam0 + dlam).

        With ``arc`` given, lambda is an unknown and every iterate satisfies
        the arc-length constraint of radius ``arc``; with ``arc=None`` the
        load factor stays fixed (plain Newton). Returns (state or None,
        load factor, iterations, reason for failure).
        """
        s, psi2 = self.settings, self.psi**2
        res0, res = None, math.inf
        for it in range(s.max_iterations + 1):
            q, lam = q0 + dq, lam0 + dlam
            try:
                _, g, K = self.system.assemble(q, self.loads, lam)
            except (ValueError, FloatingPointError) as exc:   # a connector refused the state
                return None, lam, it, f"invalid state ({exc})"
            res = self.residual(g)
            if not math.isfinite(res):
                return None, lam, it, "non-finite residual"
            if res <= s.force_tol:
                return q, lam, it, ""
            res0 = res if res0 is None else res0
            if res > 1e8 * max(res0, 1.0):
                return None, lam, it, f"diverging residual {res:.3g}"
            if it == s.max_iterations:
                break
            try:
                if arc is None:
                    d_r, d_f = K.solve(-g), np.zeros_like(g)
                else:
                    sol = K.solve(np.column_stack([-g, load_vector(self.system, q, self.loads)]))
                    d_r, d_f = sol[:, 0], sol[:, 1]
            except (RuntimeError, np.linalg.LinAlgError) as exc:
                return None, lam, it, f"singular tangent ({exc})"
            if not (np.all(np.isfinite(d_r)) and np.all(np.isfinite(d_f))):
                return None, lam, it, "singular tangent"
            dl = 0.0
            if arc is not None:
                base = dq + d_r
                a = self.dot(d_f, d_f) + psi2
                b = 2.0 * (self.dot(base, d_f) + psi2 * dlam)
                c = self.dot(base, base) + psi2 * dlam**2 - arc**2
                disc = b * b - 4.0 * a * c
                if disc < 0.0:
                    return None, lam, it, "arc-length constraint has no real root"
                root = math.sqrt(disc)
                # the root that keeps the increment closest to the previous one
                roots = ((-b + root) / (2.0 * a), (-b - root) / (2.0 * a))
                dl = max(roots, key=lambda r: (self.dot(base + r * d_f, dq)
                                               + psi2 * (dlam + r) * dlam))
            step = d_r + dl * d_f
            dq, dlam = dq + step, dlam + dl
            if max(float(np.abs(self.system.scaled(step)).max(initial=0.0)), abs(dl)) <= s.step_tol:
                q, lam = q0 + dq, lam0 + dlam
                return q, lam, it + 1, ""
        return None, lam0 + dlam, s.max_iterations, (
            f"no convergence in {s.max_iterations} iterations (residual {res:.3g})")


def solve_arclength(system: System, case: LoadCase, max_load_factor: float = 1.0,
                    n_steps: int = 20, *, model: str = "", scene: str = "", psi: float = 0.0,
                    max_steps: int | None = None, max_growth: float = 10.0,
                    stop: Callable[[LoadPath], bool] | None = None,
                    record_poses: bool = False) -> LoadPath:
    """Trace the equilibrium path of ``case`` by arc-length continuation.

    Parameters
    ----------
    system : System
    case : LoadCase
        The load pattern; load factor 1 is its full value.
    max_load_factor : float
        The path ends when the load factor first reaches this value (> 0);
        the last point is then solved at exactly this factor.
    n_steps : int
        Sets the initial arc length: the tangent at rest would reach
        ``max_load_factor`` in ``n_steps`` steps (>= 1).
    model : str
        Model id; the result's model is ``model + ":arclength"``.
    scene : str
        Scene name recorded in the result.
    psi : float
        Load-factor weight of the constraint (0: cylindrical arc length).
    max_steps : int, optional
        Most converged steps before giving up (default ``100 * n_steps``).
    max_growth : float
        Largest arc length as a multiple of the initial one.
    stop : callable, optional
        ``stop(path) -> bool`` called after every converged point; True ends
        the path there as a success (e.g. once past a limit point).
    record_poses : bool
        Also record every body's pose at each point.

    Returns
    -------
    LoadPath
        Every converged point in the order traced, from rest (load may rise
        and fall). ``stats`` holds ``newton_iterations``, ``step_cuts``,
        ``substeps`` (converged steps), per-point ``iterations``,
        ``limit_points`` (indices of local extrema of the load) and the final
        ``arc_length``.

    Raises
    ------
    SolverError
        When step cutting cannot save a step or ``max_steps`` is exceeded;
        carries the last converged load factor and the path so far.
    ValueError
        If ``max_load_factor`` is not positive and finite or ``n_steps < 1``.
    """
    if not (max_load_factor > 0.0 and math.isfinite(max_load_factor)):
        raise ValueError(f"max_load_factor must be positive and finite, got {max_load_factor}")
    if n_steps < 1:
        raise ValueError(f"n_steps must be >= 1, got {n_steps}")
    t0 = time.perf_counter()
    s = system.settings
    loads = system.loads(case)
    walker = _Path(system, loads, psi)
    max_steps = 100 * n_steps if max_steps is None else max_steps
    name = f"{model or 'model'}:arclength"
    lp = LoadPath(model=name, load_case=case.name, load=[], dx=[], dy=[], rotation=[],
                  seconds=0.0, scene=scene, load_unit=case.unit,
                  settings={"max_load_factor": max_load_factor, "n_steps": n_steps, "psi": psi},
                  poses={b: [] for b in system.mechanism.bodies} if record_poses else None)
    stats = {"unknowns": system.n_dofs, "newton_iterations": 0, "step_cuts": 0, "substeps": 0,
             "iterations": [], "limit_points": []}
    lp.stats = stats
    lams: list[float] = []

    def record(qk: np.ndarray, lam: float, iters: int) -> None:
        dx, dy, rot = system.target(qk)
        lp.load.append(lam * case.magnitude)
        lp.dx.append(dx), lp.dy.append(dy), lp.rotation.append(rot)
        stats["iterations"].append(iters)
        lams.append(lam)
        if len(lams) >= 3 and (lams[-2] - lams[-3]) * (lams[-1] - lams[-2]) < 0.0:
            stats["limit_points"].append(len(lams) - 2)
        if lp.poses is not None:
            for b in system.mechanism.bodies:
                lp.poses[b].append(system.pose(qk, b).tolist())

    def finish(converged: bool) -> LoadPath:
        lp.converged = converged
        lp.seconds = time.perf_counter() - t0
        return lp

    def fail(msg: str, lam: float) -> SolverError:
        stats["failure"] = msg
        finish(False)
        return SolverError(f"{name} on load case '{case.name}': {msg}; last converged load "
                           f"{lam * case.magnitude:.6g} {case.unit} (load factor {lam:.6g})",
                           lam, lp)

    q, lam, iters, why = walker.correct(system.initial_state(), 0.0, np.zeros(system.n_dofs),
                                        0.0, None)
    if q is None:
        raise fail(why, 0.0)
    stats["newton_iterations"] += iters
    record(q, 0.0, iters)

    # first predictor: the tangent at rest, sized so a linear path takes n_steps steps
    _, _, K = system.assemble(q, loads, 0.0)
    try:
        tangent = K.solve(load_vector(system, q, loads))
    except (RuntimeError, np.linalg.LinAlgError) as exc:
        raise fail(f"singular tangent at rest ({exc})", 0.0) from None
    if not np.all(np.isfinite(tangent)):
        raise fail("singular tangent at rest", 0.0)
    dlam0 = max_load_factor / n_steps
    arc0 = dlam0 * math.sqrt(walker.dot(tangent, tangent) + psi**2)
    if not arc0 > 0.0:
        raise fail("the load does not move the mechanism", 0.0)
    arc, arc_max, arc_min = arc0, max_growth * arc0, arc0 * 0.5**s.max_cuts
    direction = (tangent, 1.0)        # unscaled (dq, dlambda) of the last converged step
    steps, cut = 0, False
    while True:
        dq_dir, dlam_dir = direction
        norm = math.sqrt(walker.dot(dq_dir, dq_dir) + psi**2 * dlam_dir**2)
        dq, dlam = dq_dir * (arc / norm), dlam_dir * (arc / norm)
        q_new, lam_new, iters, why = walker.correct(q, lam, dq, dlam, arc)
        stats["newton_iterations"] += iters
        if q_new is not None and walker.moved_too_far(q_new - q):
            q_new, why = None, "step too large"
        elif q_new is not None and (walker.dot(q_new - q, dq_dir)
                                    + psi**2 * (lam_new - lam) * dlam_dir) <= 0.0:
            q_new, why = None, "the corrector turned back along the path"
        landing, iters2 = None, 0
        if q_new is not None and lam_new >= max_load_factor > lam:
            # crossed the end: solve at exactly max_load_factor from the interpolated state
            t = (max_load_factor - lam) / (lam_new - lam)
            landing, _, iters2, why = walker.correct(q, max_load_factor, t * (q_new - q), 0.0,
                                                     None)
            stats["newton_iterations"] += iters2
            if landing is None:
                q_new = None
        if q_new is None:
            arc *= 0.5
            cut = True
            stats["step_cuts"] += 1
            if arc < arc_min:
                raise fail(f"arc-length cutting failed ({why})", lam)
            continue
        steps += 1
        stats["substeps"] = steps
        if landing is not None:
            record(landing, max_load_factor, iters + iters2)
            stats["arc_length"] = arc
            return finish(True)
        direction = (q_new - q, lam_new - lam)
        q, lam = q_new, lam_new
        record(q, lam, iters)
        stats["arc_length"] = arc
        if stop is not None and stop(lp):
            return finish(True)
        if steps >= max_steps:
            peak = max(lams)
            raise fail(f"load factor {max_load_factor:g} not reached in {max_steps} steps "
                       f"(largest load on the path {peak * case.magnitude:.6g} {case.unit})", lam)
        if iters <= s.fast_iterations and not cut:
            arc = min(1.5 * arc, arc_max)
        cut = False


def limit_loads(path: LoadPath) -> list[float]:
    """Loads at the limit points of a traced path, refined between the traced points.

    For each local extremum of the load in ``path.stats['limit_points']`` a
    parabola through it and its two neighbours, as a function of the
    distance travelled by the target point (mm), gives the extremum's value
    (N or N mm); the error of the discrete extremum, O(step), becomes
    O(step^3).
    """
    load = np.asarray(path.load)
    travel = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(path.dx), np.diff(path.dy)))])
    out = []
    for k in path.stats.get("limit_points", []):
        t, p = travel[k - 1:k + 2], load[k - 1:k + 2]
        if not (t[0] < t[1] < t[2]):
            out.append(float(p[1]))
            continue
        c2, c1, c0 = np.polyfit(t - t[1], p, 2)
        out.append(float(c0 - c1**2 / (4.0 * c2)) if c2 != 0.0 else float(p[1]))
    return out
