"""Arc-length continuation (Riks / Crisfield) for paths with limit points.

Load control (:func:`flexval.reducedmodels.core.system.solve_path`) cannot pass a limit
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

The corrector is the core's one Newton iteration
(:func:`flexval.reducedmodels.core.newton.solve`, with all its safeguards) on the
bordered problem :class:`ArcLengthStep`; the stepping is the strategy
:class:`ArcLength` of the one path tracer (:func:`flexval.reducedmodels.core.tracer.trace`).

Units: mm, N, N mm, rad; load factors are dimensionless.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from flexval.geometry import LoadCase

from .bifurcation import BIFURCATION_RTOL, classify
from .loadpath import LoadPath
from .loads import Loads
from .newton import FixedLoad, NewtonResult, StepProblem, StepRefused
from .recorder import PathRecorder
from .system import System
from .tangent import Tangent
from .tracer import PathPoint, Solve, Stepping, Verdict, trace


def arc_dot(system: System, u: np.ndarray, v: np.ndarray) -> float:
    """<u, v>: mean product of the scaled coordinates (dimensionless, see System.scaled)."""
    return float(np.mean(system.scaled(u) * system.scaled(v)))


class ArcLengthStep(StepProblem):
    """Equilibrium bordered by the arc-length constraint: lambda is an unknown.

    Every iterate (q, lambda) from the predictor on satisfies
    <q - q0, q - q0> + psi^2 (lambda - lambda0)^2 = arc^2 about the last
    converged point (q0, lambda0).
    """

    def __init__(
        self,
        system: System,
        loads: Loads,
        factor: float,
        origin: np.ndarray,
        origin_factor: float,
        arc: float,
        psi: float,
    ):
        super().__init__(system, loads, factor)
        self.q0, self.lam0, self.arc, self.psi = origin, origin_factor, arc, psi

    def correction(self, q: np.ndarray, g: np.ndarray, K: Tangent) -> tuple[np.ndarray, float]:
        """Crisfield's correction: K [dq_R, dq_F] = [-g, f], dlambda from the constraint."""
        system, psi2 = self.system, self.psi**2
        sol = K.solve(np.column_stack([-g, self.loads.vector(q)]))
        d_r, d_f = sol[:, 0], sol[:, 1]
        dq, dlam = q - self.q0, self.factor - self.lam0
        base = dq + d_r
        a = arc_dot(system, d_f, d_f) + psi2
        b = 2.0 * (arc_dot(system, base, d_f) + psi2 * dlam)
        c = arc_dot(system, base, base) + psi2 * dlam**2 - self.arc**2
        disc = b * b - 4.0 * a * c
        if disc < 0.0:
            raise StepRefused("arc-length constraint has no real root")
        root = math.sqrt(disc)
        # the root that keeps the increment closest to the previous one
        roots = ((-b + root) / (2.0 * a), (-b - root) / (2.0 * a))
        dl = max(
            roots, key=lambda r: arc_dot(system, base + r * d_f, dq) + psi2 * (dlam + r) * dlam
        )
        return d_r + dl * d_f, dl


class ArcLength(Stepping):
    """Arc-length continuation as a stepping strategy of
    :func:`flexval.reducedmodels.core.tracer.trace`.

    Parameters
    ----------
    max_load_factor : float
        The path ends when the load factor first reaches this value; the
        last point is then solved at exactly this factor.
    n_steps : int
        Sets the initial arc length: the tangent at rest would reach
        ``max_load_factor`` in ``n_steps`` steps.
    psi : float
        Load-factor weight of the constraint (0: cylindrical arc length).
    max_steps : int
        Most converged steps.
    max_growth : float
        Largest arc length as a multiple of the initial one.
    branch_switch : bool
        At the first bifurcation point, leave the traced branch for the one
        that crosses it (see :meth:`review`).

    Every converged step is reported. A step across which the tangent's
    number of negative eigenvalues (:meth:`System.instability`, every
    negative one counted however small) changes is
    bisected on the arc length until the load factors on either side of the
    change agree to :data:`~flexval.reducedmodels.core.bifurcation.BIFURCATION_RTOL`;
    when the load does not turn there (it moves the same way from the step's
    start through the bracket to its end) and the critical mode is not the
    path's slope (:func:`~flexval.reducedmodels.core.bifurcation.classify`), the
    crossing is a bifurcation point, reported with the step
    (``Verdict.bifurcations``: the bracket's middle).
    """

    cut_name = "arc-length"
    first_factor = 0.0

    def __init__(
        self,
        max_load_factor: float,
        n_steps: int,
        psi: float,
        max_steps: int,
        max_growth: float,
        branch_switch: bool = False,
    ):
        self.max_load_factor, self.n_steps, self.psi = max_load_factor, n_steps, psi
        self.max_steps, self.max_growth = max_steps, max_growth
        self.branch_switch = branch_switch

    def begin(self, system: System, loads: Loads, point: PathPoint) -> None:
        """Size the first step from the tangent at rest."""
        self.system, self.loads, self.settings = system, loads, system.settings
        self.q, self.factor, self.peak = point.state, point.factor, point.factor
        try:
            tangent = point.tangent.solve(loads.vector(self.q))
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise StepRefused(f"singular tangent at rest ({exc})") from None
        if not np.all(np.isfinite(tangent)):
            raise StepRefused("singular tangent at rest")
        dlam0 = self.max_load_factor / self.n_steps
        arc0 = dlam0 * math.sqrt(arc_dot(system, tangent, tangent) + self.psi**2)
        if not arc0 > 0.0:
            raise StepRefused("the load does not move the mechanism")
        self.arc, self.arc_max = arc0, self.max_growth * arc0
        self.arc_min = arc0 * 0.5**self.settings.max_cuts
        self.direction = (tangent, 1.0)  # unscaled (dq, dlambda) of the last converged step
        self.was_cut = self.landed = self.switched = False
        self.count = self.next_count = system.instability(point.tangent)
        self.rest_count = self.count

    def finished(self) -> bool:
        """True once the path has landed on ``max_load_factor``."""
        return self.landed

    def attempt(self) -> tuple[StepProblem, np.ndarray, np.ndarray]:
        """The secant (first: tangent) predictor of length ``arc`` and its bordered corrector."""
        dq_dir, dlam_dir = self.direction
        norm = math.sqrt(arc_dot(self.system, dq_dir, dq_dir) + self.psi**2 * dlam_dir**2)
        dq, dlam = dq_dir * (self.arc / norm), dlam_dir * (self.arc / norm)
        problem = ArcLengthStep(
            self.system, self.loads, self.factor + dlam, self.q, self.factor, self.arc, self.psi
        )
        return problem, self.q + dq, self.q

    def review(self, result: NewtonResult, solve: Solve) -> Verdict:
        """Refuse a step beyond the bounds or back along the path; land on the end factor."""
        q_new, lam_new, why = result.state, result.factor, result.reason
        q, lam = self.q, self.factor
        dq_dir, dlam_dir = self.direction
        if q_new is not None and self.system.motion_ratio(q, q_new) > 1.0:
            q_new, why = None, "step too large"
        elif (
            q_new is not None
            and (arc_dot(self.system, q_new - q, dq_dir) + self.psi**2 * (lam_new - lam) * dlam_dir)
            <= 0.0
        ):
            q_new, why = None, "the corrector turned back along the path"
        if q_new is None:
            return Verdict(None, lam, why, None, False)
        fast = result.iterations <= self.settings.fast_iterations
        self.step_taken = (q_new - q, lam_new - lam)
        if lam_new >= self.max_load_factor > lam:
            # crossed the end: solve at exactly max_load_factor from the interpolated state
            t = (self.max_load_factor - lam) / (lam_new - lam)
            landing = solve(
                FixedLoad(self.system, self.loads, self.max_load_factor), q + t * (q_new - q), q
            )
            if landing.state is None:
                return Verdict(None, lam, landing.reason, None, False)
            self.landed = True
            verdict = Verdict(landing.state, self.max_load_factor, "", landing.tangent, fast)
        else:
            verdict = Verdict(q_new, lam_new, "", result.tangent, fast)
        return self._watch(verdict, solve)

    def _watch(self, verdict: Verdict, solve: Solve) -> Verdict:
        """Locate a bifurcation inside the step, if the inertia changes across it without a turn.

        With ``branch_switch``, the first one found replaces the step's end
        by the state just before it and points the next step along the
        critical mode (the direction of the crossing branch), sized to half
        the step bounds; the arc-length limits are re-based on that size.
        """
        count = self.system.instability(verdict.tangent)
        self.next_count = count
        if count is None or self.count is None or count == self.count:
            return verdict
        located = self._locate(verdict, self.count, solve)
        if located is None:
            return verdict
        factor, (q_lo, lam_lo, tangent_lo), mode = located
        if not self.branch_switch or self.switched:
            return verdict._replace(bifurcations=(factor,))
        self.switched, self.landed = True, False
        self.next_count = self.count
        step = self.system.scaled(mode)
        unit = mode / math.sqrt(float(np.mean(step * step)))  # arc-length norm 1
        probe = 1e-6
        ratio = self.system.motion_ratio(q_lo, self.system.update(q_lo, probe * unit)) / probe
        if ratio > 0.0:
            self.arc = 0.5 / ratio
            self.arc_max = max(self.arc_max, self.max_growth * self.arc)
            self.arc_min = min(self.arc_min, self.arc * 0.5**self.settings.max_cuts)
        self.step_taken = (unit, 0.0)
        return Verdict(q_lo, lam_lo, "", tangent_lo, False, (factor,))

    def _locate(
        self, verdict: Verdict, before: int, solve: Solve
    ) -> tuple[float, tuple[np.ndarray, float, Tangent | None], np.ndarray] | None:
        """Bisect the step on the arc length to the change of inertia; None unless a bifurcation.

        Returns the bifurcation's load factor (the bracket's middle), the
        converged state, factor and tangent just before it, and the critical
        mode (unit, unscaled coordinates) just after it.
        """
        system, loads, psi = self.system, self.loads, self.psi
        q0, lam0 = self.q, self.factor
        dq, dlam = verdict.state - q0, verdict.factor - lam0
        length = math.sqrt(arc_dot(system, dq, dq) + psi**2 * dlam**2)
        lo, hi = (q0, lam0, None), (verdict.state, verdict.factor, verdict.tangent)
        t_lo, t_hi = 0.0, 1.0
        while abs(hi[1] - lo[1]) > BIFURCATION_RTOL * max(abs(hi[1]), abs(lo[1])):
            t = 0.5 * (t_lo + t_hi)
            if t_hi - t_lo < 1e-12:
                break
            problem = ArcLengthStep(system, loads, lam0 + t * dlam, q0, lam0, t * length, psi)
            result = solve(problem, q0 + t * dq, q0)
            if result.state is None:
                break
            tangent = FixedLoad(system, loads, result.factor).assemble(result.state)[1]
            count = system.instability(tangent)
            if count is None:
                break
            if count == before:
                lo, t_lo = (result.state, result.factor, tangent), t
            else:
                hi, t_hi = (result.state, result.factor, tangent), t
        sense = np.sign(dlam)
        ordered = sense != 0.0 and (
            sense * (lo[1] - lam0) >= 0.0
            and sense * (hi[1] - lo[1]) > 0.0
            and sense * (verdict.factor - hi[1]) >= 0.0
        )
        if not ordered:
            return None  # the load turns inside the bracket: a limit point
        if hi[2] is None:
            hi = (hi[0], hi[1], FixedLoad(system, loads, hi[1]).assemble(hi[0])[1])
        # the whole step's direction: the bracket's is swamped by round-off along the mode
        split, mode = classify(system, hi[2], verdict.state - q0)
        if not split:
            return None
        if lo[2] is None:
            lo = (lo[0], lo[1], FixedLoad(system, loads, lo[1]).assemble(lo[0])[1])
        return 0.5 * (lo[1] + hi[1]), lo, mode

    def cut(self) -> bool:
        """Halve the arc length."""
        self.arc *= 0.5
        self.was_cut = True
        return self.arc >= self.arc_min

    def advance(self, verdict: Verdict) -> float | None:
        """Take the step; grow the arc length after an easy, uncut one. Every step is reported."""
        self.direction = self.step_taken
        self.count = self.next_count
        self.q, self.factor = verdict.state, verdict.factor
        self.peak = max(self.peak, self.factor)
        self.taken_arc = self.arc
        if not self.landed and verdict.fast and not self.was_cut:
            self.arc = min(1.5 * self.arc, self.arc_max)
        self.was_cut = False
        return self.factor

    def step_size(self) -> float:
        """Arc length of the step last accepted (dimensionless)."""
        return self.taken_arc

    def unstable(self) -> int | None:
        """The last accepted state's negative eigenvalues beyond the first point's (the
        count the bifurcation watch keeps), or None where either was not counted."""
        if self.count is None or self.rest_count is None:
            return None
        return max(self.count - self.rest_count, 0)

    def exhausted(self, counters) -> str | None:
        """More than ``max_steps`` converged steps without reaching the end."""
        if self.landed or counters.substeps < self.max_steps:
            return None
        return (
            f"load factor {self.max_load_factor:g} not reached in {self.max_steps} steps "
            f"(largest load factor on the path {self.peak:.6g})"
        )


def solve_arclength(
    system: System,
    case: LoadCase,
    max_load_factor: float = 1.0,
    n_steps: int = 20,
    *,
    model: str = "",
    scene: str = "",
    psi: float = 0.0,
    max_steps: int | None = None,
    max_growth: float = 10.0,
    stop: Callable[[LoadPath], bool] | None = None,
    record_poses: bool = False,
    record_shapes: bool = False,
    branch_switch: bool = False,
) -> LoadPath:
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
    record_shapes : bool
        Also record every connector's shape and section forces at each point.
    branch_switch : bool
        Follow the branch that crosses the path at its first bifurcation
        point (:class:`ArcLength`).

    Returns
    -------
    LoadPath
        Every converged point in the order traced, from rest (load may rise
        and fall). ``stats`` holds ``newton_iterations``, ``step_cuts``,
        ``substeps`` (converged steps), per-point ``iterations`` (Newton
        iterations since the previous point, failed attempts included),
        ``limit_points`` (indices of local extrema of the load) and the final
        ``arc_length``; ``bifurcations`` the bifurcation points passed
        (``{"load", "fraction"}``, N or N mm and load factor).

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
    max_steps = 100 * n_steps if max_steps is None else max_steps
    recorder = PathRecorder(
        system,
        case,
        f"{model or 'model'}:arclength",
        scene,
        {"max_load_factor": max_load_factor, "n_steps": n_steps, "psi": psi}
        | ({"branch_switch": True} if branch_switch else {}),
        record_poses=record_poses,
        record_shapes=record_shapes,
        limit_points=True,
    )
    stepping = ArcLength(max_load_factor, n_steps, psi, max_steps, max_growth, branch_switch)
    path, last = recorder.run(trace(system, system.loads(case), stepping), stop)
    path.stats["arc_length"] = last.step
    return path


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
        t, p = travel[k - 1 : k + 2], load[k - 1 : k + 2]
        if not (t[0] < t[1] < t[2]):
            out.append(float(p[1]))
            continue
        c2, c1, c0 = np.polyfit(t - t[1], p, 2)
        out.append(float(c0 - c1**2 / (4.0 * c2)) if c2 != 0.0 else float(p[1]))
    return out
