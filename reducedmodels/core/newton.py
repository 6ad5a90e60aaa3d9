"""The one Newton iteration of the core, with all its safeguards, on a "step problem".

A step problem says what one step solves: its residual and tangent at an
iterate and the correction they give. :class:`FixedLoad` is equilibrium at
a fixed load factor (load control, and the first and last points of arc
length); :class:`flexval.reducedmodels.core.continuation.ArcLengthStep` borders it with
the arc-length constraint and makes the load factor an unknown. An
implicit time step is a third: its residual adds inertia and its tangent
the mass matrix over the time step squared, and :func:`solve` needs no
change. The same :func:`solve` runs one path or every copy of a batch at once.

Units: mm, N, N mm, rad; load factors are dimensionless.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .loads import Loads
from .tangent import Tangent

if TYPE_CHECKING:
    from .settings import SolverSettings
    from .system import System


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


DIVERGENCE = 1e8
"""Growth of the residual over max(first residual, 1) taken as divergence."""


class StepRefused(Exception):
    """A step problem cannot give a correction at this iterate (the message says why)."""


class StepProblem(ABC):
    """What one Newton solve is about: residual, tangent and correction at an iterate.

    Attributes
    ----------
    system : System
    loads : Loads
    factor : float
        The load factor of the current iterate (dimensionless); a problem
        whose correction moves it (arc length) updates it through the second
        value :meth:`correction` returns.
    """

    def __init__(self, system: System, loads: Loads, factor: float):
        self.system, self.loads, self.factor = system, loads, factor

    def assemble(self, q: np.ndarray) -> tuple[np.ndarray, Tangent]:
        """Out-of-balance force (gradient of the total potential, N and N mm) and tangent at q.

        Raises ValueError or FloatingPointError if a connector refuses the state.
        """
        _, g, K = self.system.assemble(q, self.loads, self.factor)
        return g, K

    def residual(self, g: np.ndarray) -> float:
        """Size of the out-of-balance force relative to the load scale (dimensionless)."""
        return self.system.residual(g, self.loads)

    @abstractmethod
    def correction(self, q: np.ndarray, g: np.ndarray, K: Tangent) -> tuple[np.ndarray, float]:
        """Newton correction (du, dfactor) at iterate q with gradient g and tangent K.

        Raises
        ------
        StepRefused
            When no correction exists (e.g. no real root of a constraint).
        RuntimeError, numpy.linalg.LinAlgError
            When the tangent is singular.
        """


class FixedLoad(StepProblem):
    """Equilibrium at a fixed load factor: du = -K^-1 g."""

    def correction(self, q: np.ndarray, g: np.ndarray, K: Tangent) -> tuple[np.ndarray, float]:
        """The plain Newton correction; the load factor stays."""
        return K.solve(-g), 0.0


class NewtonResult(NamedTuple):
    """Outcome of :func:`solve`.

    ``state`` is None on failure, with ``reason`` saying why; ``factor`` is
    the load factor of the last iterate. ``tangent`` is the tangent at the
    last assembled iterate: at the converged state when the residual test
    ended the iteration, else one correction before it (close enough to
    judge stability: its eigenvalues differ by O(|du|)).

    For a batch of copies (``active`` given to :func:`solve`), ``state``
    holds every copy's coordinates: a converged copy's converged state, a
    failed or inactive copy's from where the solve started (``origin``, or
    the guess); None only when no copy converged. ``iterations`` is then one
    count per copy, as its own solve gives it, ``failed`` marks the copies
    that did not converge, ``reasons`` says why per copy (``reason`` is the
    first failed copy's), and ``storage`` holds every copy's tangent values
    as the copy's own solve would return its tangent (a copy that stopped
    early keeps the values of its last assembly, those that took no part as
    the batch kept them); ``tangent`` wraps it. The three are None for a
    single path.
    """

    state: np.ndarray | None
    factor: float
    iterations: int | np.ndarray
    reason: str
    tangent: Tangent | None
    failed: np.ndarray | None = None
    reasons: list[str] | None = None
    storage: np.ndarray | None = None


# --- the rules of the iteration, for one path or every copy of a batch alike ---------------
# Each takes scalars or per-copy arrays (``lesser``: min, or numpy.minimum for arrays), so
# the single path's loop and the batch's apply the same tests with the same constants and
# give the same messages.


def _invalid(detail: object) -> str:
    """Why: a connector refused the iterate."""
    return f"invalid state ({detail})"


NON_FINITE = "non-finite residual"
LEFT_BOUNDS = "iterates left the sub-step's bounds"
SINGULAR = "singular tangent"


def _singular(detail: object) -> str:
    """Why: the tangent could not be factorised."""
    return f"{SINGULAR} ({detail})"


def _diverging(res, first):
    """The residual has grown ``DIVERGENCE`` times over max(first residual, 1)."""
    return (res > DIVERGENCE * first) & (res > DIVERGENCE)


def _diverging_reason(res: float) -> str:
    return f"diverging residual {res:.3g}"


def _stalled_reason(stalled: int, best: float) -> str:
    return f"stalled (no lower residual in {stalled} iterations, best {best:.3g})"


def _unconverged_reason(iterations: int, res: float) -> str:
    return f"no convergence in {iterations} iterations (residual {res:.3g})"


def _settled(step, last_step, res, first, settings: SolverSettings, lesser=min):
    """The correction test: the correction is below ``step_tol``, or the error it leaves,
    |du_k| min(1, |du_k| / |du_(k-1)|), is below ``error_tol`` once the iteration is seen
    to contract (residual below ``CONTRACTION_EVIDENCE`` of the first; ``last_step`` NaN:
    no earlier correction)."""
    contracting = (last_step == last_step) & (res <= CONTRACTION_EVIDENCE * first)
    estimate = step * lesser(1.0, step / last_step)
    return (step <= settings.step_tol) | (contracting & (estimate <= settings.error_tol))


def solve(
    problem: StepProblem,
    q: np.ndarray,
    settings: SolverSettings,
    origin: np.ndarray | None = None,
    active: np.ndarray | None = None,
) -> NewtonResult:
    """Newton-Raphson with the exact tangent on ``problem`` from the iterate q.

    Converged when the residual is below ``force_tol`` (relative to the load
    scale), when the last correction (scaled coordinates, and the load
    factor's change) is below ``step_tol``, or when the error it leaves,
    estimated from the contraction of the last two corrections as |du_k|
    min(1, |du_k| / |du_(k-1)|) (an over-estimate under quadratic
    convergence), is below ``error_tol``. The estimate is trusted only once
    the iteration is seen to contract (the residual has fallen below
    ``CONTRACTION_EVIDENCE`` of its first value): a stiff membrane mode can
    carry a large force on a tiny correction before Newton has found its
    basin. So the iteration stops as soon as the answer is known, instead of
    spending one more assembly and solve to prove it.

    Newton that has lost its way is abandoned early, since cutting the step
    is cheaper than letting it wander to ``max_iterations``: when a connector
    refuses an iterate (invalid state), when the residual is not finite or
    grows ``DIVERGENCE`` times, when it has not improved on its best value
    for ``max_stall`` iterations, or, with ``origin`` (the state where the
    step started), when an iterate moves a body more than ``max_excursion``
    times the step bounds away from it.

    Corrections larger than ``system.update_threshold`` (``NONLINEAR_UPDATE``
    unless a connector asks for less) go through :meth:`System.update` (the
    connectors' own nonlinear updates).

    With ``active`` (bool per copy), ``problem.system`` is a
    :class:`flexval.reducedmodels.core.batch.BatchSystem` of independent copies
    and every test above is made per copy, on the copy's own residual,
    correction and body motions (see :func:`_solve_copies`); the copies not
    active are frozen throughout. Without it, the one path is solved by the
    same rules on plain floats: a batch's per-copy bookkeeping costs more
    than a small model's whole iteration (1.6 to 3.3 times the path's time,
    measured on the open chain's reduced models).
    """
    if active is None:
        return _solve_path(problem, q, settings, origin)
    return _solve_copies(problem, q, settings, origin, active)


def _solve_path(
    problem: StepProblem, q: np.ndarray, settings: SolverSettings, origin: np.ndarray | None
) -> NewtonResult:
    """:func:`solve` of one path."""
    system = problem.system
    force_tol, max_iterations, max_stall = (
        settings.force_tol,
        settings.max_iterations,
        settings.max_stall,
    )
    update_threshold = system.update_threshold
    first, best, stalled, last_step, res = None, math.inf, 0, math.nan, math.inf
    for it in range(max_iterations + 1):
        try:
            g, K = problem.assemble(q)
        except (ValueError, FloatingPointError) as exc:  # a connector refused the state
            return NewtonResult(None, problem.factor, it, _invalid(exc), None)
        res = problem.residual(g)
        if not math.isfinite(res):
            return NewtonResult(None, problem.factor, it, NON_FINITE, None)
        if res <= force_tol:
            return NewtonResult(q, problem.factor, it, "", K)
        first = res if first is None else first
        if _diverging(res, first):
            return NewtonResult(None, problem.factor, it, _diverging_reason(res), None)
        best, stalled = (res, 0) if res < best else (best, stalled + 1)
        if stalled >= max_stall:
            return NewtonResult(None, problem.factor, it, _stalled_reason(stalled, best), None)
        if it == max_iterations:
            break
        try:
            du, dfactor = problem.correction(q, g, K)
        except (RuntimeError, np.linalg.LinAlgError) as exc:  # singular factor
            return NewtonResult(None, problem.factor, it, _singular(exc), None)
        except StepRefused as exc:
            return NewtonResult(None, problem.factor, it, str(exc), None)
        step = float(np.maximum.reduce(np.abs(system.scaled(du)), initial=0.0))
        if not (math.isfinite(step) and math.isfinite(dfactor)):
            return NewtonResult(None, problem.factor, it, SINGULAR, None)
        step = max(step, abs(dfactor))
        q = system.update(q, du) if step > update_threshold else q + du
        problem.factor += dfactor
        if _settled(step, last_step, res, first, settings):
            return NewtonResult(q, problem.factor, it + 1, "", K)
        last_step = step
        if (
            origin is not None
            and step > EXCURSION_CHECK
            and system.motion_ratio(origin, q) > settings.max_excursion
        ):
            return NewtonResult(None, problem.factor, it + 1, LEFT_BOUNDS, None)
    return NewtonResult(
        None, problem.factor, max_iterations, _unconverged_reason(max_iterations, res), None
    )


def _solve_copies(
    problem: StepProblem,
    q: np.ndarray,
    settings: SolverSettings,
    origin: np.ndarray | None,
    active: np.ndarray,
) -> NewtonResult:
    """:func:`solve` on every active copy of a batch at once, each copy as if alone.

    ``problem.system`` is a :class:`flexval.reducedmodels.core.batch.BatchSystem`:
    independent copies, so its tangent is block-diagonal and one assembly and
    one factorisation serve all copies. A copy that meets a test stops there
    (converged or failed) and takes no further part: its coordinates stay,
    its block of the tangent keeps the values of its last assembly (so its
    correction is zero and the factorisation unchanged), and its iteration
    count is the one its own solve gives. The iteration ends when no copy is
    left; its length is the largest count. A failed copy's coordinates go
    back to ``origin`` (or the guess), a state its connectors accept. The
    copies not ``active`` are frozen throughout (their tangent block as
    :attr:`BatchSystem.kept` holds it).
    """
    system = problem.system
    loads, factor = problem.loads, problem.factor
    force_tol, max_iterations, max_stall = (
        settings.force_tol,
        settings.max_iterations,
        settings.max_stall,
    )
    copies, dof_copy = system.n_copies, system.dof_copy
    fallback = (q if origin is None else origin).copy()
    running = np.asarray(active, bool).copy()
    failed = np.zeros(copies, bool)
    iterations = np.zeros(copies, np.int64)
    reasons = [""] * copies
    first = np.full(copies, np.nan)
    best = np.full(copies, np.inf)
    stalled = np.zeros(copies, np.int64)
    last_step = np.full(copies, np.nan)
    # every copy's tangent values as its solve leaves them: the batch's (never changed in
    # place) until a copy stops, then a copy of them, or this assembly's if all stop at once
    kept = system.kept
    q = q.copy()

    def stop(mask: np.ndarray, count: int, why: str | None) -> None:
        """Copies ``mask`` stop at iteration ``count``: failed (``why``) or converged (None)."""
        idx = np.flatnonzero(mask)
        if idx.size == 0:
            return
        running[idx] = False
        iterations[idx] = count
        if why is not None:
            failed[idx] = True
            for k in idx.tolist():
                reasons[k] = why
            back = mask[dof_copy]
            q[back] = fallback[back]

    def stop_each(mask: np.ndarray, count: int, why: Callable[..., str], *values) -> None:
        """Copies ``mask`` fail at iteration ``count``, copy k for ``why(*(v[k] for v in
        values))``."""
        for k in np.flatnonzero(mask).tolist():
            stop(np.arange(copies) == k, count, why(*(v[k] for v in values)))

    def keep(mask: np.ndarray, storage: np.ndarray) -> None:
        """Copies ``mask`` stop with ``storage``'s tangent values (all: ``storage`` itself,
        which no iteration changes after it)."""
        nonlocal kept
        if mask.all():
            kept = storage
        elif mask.any():
            if kept is system.kept:
                kept = kept.copy()
            system.copy_blocks(kept, storage, mask)

    # the last solve's storage and tangent (factorised): every copy's own if all stop after it
    solved: tuple | None = None
    res = np.full(copies, np.inf)
    for it in range(max_iterations + 1):
        if not running.any():
            break
        assembled = None
        while assembled is None and running.any():
            try:
                assembled = system.assemble_storage(q, loads, factor)
            except (ValueError, FloatingPointError):  # some copy's connector refused its state
                refused = system.refusals(q, loads, factor, running)
                for k, why in refused.items():
                    stop(np.arange(copies) == k, it, _invalid(why))
                if not refused:  # not one copy alone: judge none of them
                    stop(running, it, _invalid("refused in the batch"))
        if assembled is None:
            break
        _, g, storage = assembled
        if not running.all():  # the copies that stopped: their kept values
            system.copy_blocks(storage, kept, ~running)
        res = np.where(running, system.copy_residuals(g, loads), res)
        stop(running & ~np.isfinite(res), it, NON_FINITE)
        done = running & (res <= force_tol)
        keep(done, storage)  # their tangent: this assembly's
        stop(done, it, None)
        fresh = running & np.isnan(first)
        first[fresh] = res[fresh]
        stop_each(running & _diverging(res, first), it, _diverging_reason, res)
        improved = running & (res < best)
        best[improved] = res[improved]
        stalled = np.where(improved, 0, stalled + running)
        stop_each(running & (stalled >= max_stall), it, _stalled_reason, stalled, best)
        if it == max_iterations or not running.any():
            break
        everyone = running.all()
        moving = None if everyone else running[dof_copy]
        try:
            solved = (storage, system.layout.tangent(storage))
            du = solved[1].solve(-g if everyone else np.where(moving, -g, 0.0))
        except (RuntimeError, np.linalg.LinAlgError) as exc:  # singular factor
            stop(running, it, _singular(exc))
            break
        step = system.copy_steps(du)
        stop(running & ~np.isfinite(step), it, SINGULAR)
        everyone = running.all()
        if not everyone:
            moving = running[dof_copy]
            du[~moving] = 0.0
        nonlinear = running & (step > system.update_threshold)
        q_new = q + du
        if nonlinear.all():
            q_new = system.update(q, du)
        elif nonlinear.any():
            chosen = nonlinear[dof_copy]
            q_new[chosen] = system.update(q, du)[chosen]
        if everyone:
            q = q_new
        else:
            q[moving] = q_new[moving]
        with np.errstate(divide="ignore", invalid="ignore"):
            small = running & _settled(step, last_step, res, first, settings, np.minimum)
        keep(small, storage)
        stop(small, it + 1, None)
        last_step = np.where(running, step, last_step)
        if origin is not None:
            wide = running & (step > EXCURSION_CHECK)
            if wide.any():
                far = wide & (system.motion_ratios(origin, q) > settings.max_excursion)
                stop(far, it + 1, LEFT_BOUNDS)
    stop_each(running, max_iterations, partial(_unconverged_reason, max_iterations), res)
    converged = np.asarray(active, bool) & ~failed
    reason = reasons[int(np.argmax(failed))] if failed.any() else ""  # the first failed copy's
    return NewtonResult(
        q if converged.any() else None,
        factor,
        iterations,
        reason,
        solved[1] if solved is not None and solved[0] is kept else system.layout.tangent(kept),
        failed,
        reasons,
        kept,
    )
