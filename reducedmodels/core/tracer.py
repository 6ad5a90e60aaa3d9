"""The one path tracer: a generator of converged states along a load path.

:func:`trace` solves the first point at a fixed load factor from rest and
then asks a *stepping strategy* for one step after the other: the strategy
proposes a step problem and a predictor, the one Newton iteration
(:func:`flexval.reducedmodels.core.newton.solve`) corrects it, the strategy reviews
the result (step bounds, stability, ...), and the tracer either cuts the
step or accepts it and, when the strategy says the point is one to report,
yields it as a :class:`PathPoint`. The caller records what it needs (the
way scikit-fem's ``natural_jfnk`` yields ``(mu, sol)``): see
:class:`flexval.reducedmodels.core.recorder.PathRecorder`. Two strategies exist:
:class:`LoadControl` (requested load levels, adaptive sub-steps) and
:class:`flexval.reducedmodels.core.continuation.ArcLength` (Riks/Crisfield continuation).

Counts of Newton iterations, step cuts and accepted sub-steps are kept here,
once, and travel with every point and every failure.

Units: mm, N, N mm, rad; load factors are dimensionless.
"""

from __future__ import annotations

import dataclasses
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .bifurcation import BIFURCATION_RTOL, classify
from .loads import Loads
from .newton import FixedLoad, NewtonResult, StepProblem, StepRefused, solve
from .tangent import Tangent

if TYPE_CHECKING:
    from .batchsystem import BatchSystem
    from .system import System

BIFURCATION_PROBE = 0.02
"""How far beyond a suspected bifurcation (relative load factor) load control probes for
the equilibrium that a bifurcation leaves and a limit point does not: far enough that the
state's round-off along the critical mode (residual over a vanishing eigenvalue) is small
beside the step along the path."""

PREDICTOR_STATES = 5
"""Converged states the load-control predictor extrapolates through (a quartic).

Measured on the built-in scenes' 36 reduced-model paths (dcmm:1-3, prbm,
beam:20, beam:100, 6 cases; first sub-step along the tangent): 2020 Newton
iterations with 3 states (quadratic), 1795 with 4, 1736 with 5, 1718 with 6
(but more on beam:100's paths, whose step cuts leave uneven spacings);
continuum:1, open chain f-: 188, 165, 157 iterations with 3, 4, 5 states.
With the slope at the last state as well (models whose connectors do not
predict their own coordinates: dcmm, prbm), 1736 -> 1538 over the 36 paths
(1566 with 4 states and the slope). End values agree to 3e-8 mm and rad.
Beams with their chains closed by bending and the slope in their chord
predictor: 1150, 1118, 1116 over the 36 paths with 4, 5, 6 states (6: prbm
117 -> 119)."""

UNSTABLE = "converged to an unstable equilibrium (past a limit point?)"
"""Why load control refuses a step that converged where the stability rule counts a negative
eigenvalue (:meth:`System.unstable`)."""

Solve = Callable[[StepProblem, np.ndarray, "np.ndarray | None"], NewtonResult]
"""solve(problem, guess, origin): the tracer's counted call of the one Newton iteration."""

Newton = Callable[..., NewtonResult]
"""newton(problem, guess, settings, origin): one Newton solve of a step problem."""


@dataclasses.dataclass
class Counters:
    """Work done so far along a path (all counts; in a batch, Newton iterations per copy)."""

    newton_iterations: int | np.ndarray = 0
    step_cuts: int = 0
    substeps: int = 0

    def copy(self) -> Counters:
        """The counts now, as a new object (``dataclasses.replace`` costs four times more)."""
        return Counters(self.newton_iterations, self.step_cuts, self.substeps)


@dataclasses.dataclass(frozen=True)
class PathPoint:
    """One converged state the tracer yields.

    Attributes
    ----------
    state : array (n_dofs,)
        The system's coordinates (mm, rad; see :class:`flexval.reducedmodels.core.system.System`).
    factor : float
        Load factor (dimensionless; 1 is the load case's full value).
    iterations : int
        Newton iterations spent since the previous point (failed attempts included).
    tangent : Tangent or None
        Tangent at (or one correction before) the state, for stability
        (:meth:`System.unstable`) or a further solve.
    step : float
        Size of the step that reached the point (load-factor increment, or
        arc length; 0 for the first point).
    counters : Counters
        Totals along the path up to this point.
    bifurcations : tuple of float
        Load factors of the bifurcation points located since the previous
        point (see :mod:`flexval.reducedmodels.core.bifurcation`).
    unstable : int or None
        How many more negative eigenvalues the tangent has here than at the path's first
        point (0: as stable as at rest; > 0: an equilibrium the load case's control
        cannot hold), where the stepping judges it (:meth:`Stepping.unstable`); else None.
    """

    state: np.ndarray
    factor: float
    iterations: int
    tangent: Tangent | None
    step: float
    counters: Counters
    bifurcations: tuple[float, ...] = ()
    unstable: int | None = None


class TraceFailure(Exception):
    """The tracer cannot continue; carries the reason, the last converged factor and the counts.

    ``bifurcations`` are the load factors of the bifurcation points located
    since the last reported point; ``bifurcation`` is the load factor of the
    one that stopped the path (load control beyond it finds only unstable
    equilibria), or None.
    """

    def __init__(
        self,
        reason: str,
        factor: float,
        counters: Counters,
        bifurcations: Sequence[float] = (),
        bifurcation: float | None = None,
    ):
        super().__init__(reason)
        self.reason, self.factor, self.counters = reason, factor, counters
        self.bifurcations, self.bifurcation = tuple(bifurcations), bifurcation


class Verdict(NamedTuple):
    """A stepping strategy's review of one Newton solve.

    ``state`` None means the step is refused (``reason`` says why) and will
    be cut; ``fast`` says the step was easy enough to grow the next one;
    ``bifurcations`` are the load factors of bifurcation points located in
    the step.
    """

    state: np.ndarray | None
    factor: float
    reason: str
    tangent: Tangent | None
    fast: bool
    bifurcations: tuple[float, ...] = ()


class Stepping(ABC):
    """A stepping strategy of :func:`trace`: how steps are proposed, judged, cut and grown.

    Attributes
    ----------
    first_factor : float
        Load factor of the first point, solved from rest at fixed load.
    cut_name : str
        What is cut, for messages (``"step"``, ``"arc-length"``).
    factor : float
        Load factor of the last accepted state (set by :meth:`begin`).
    """

    first_factor: float
    cut_name: str
    factor: float

    @abstractmethod
    def begin(self, system: System, loads: Loads, point: PathPoint) -> None:
        """Start from the first converged point (raise StepRefused if the path cannot start)."""

    @abstractmethod
    def finished(self) -> bool:
        """True once the path has reached its end."""

    @abstractmethod
    def attempt(self) -> tuple[StepProblem, np.ndarray, np.ndarray]:
        """The next step: (problem, predicted state, origin for the excursion check)."""

    @abstractmethod
    def review(self, result: NewtonResult, solve: Solve) -> Verdict:
        """Accept or refuse a Newton result (``solve`` for any further counted solve)."""

    @abstractmethod
    def cut(self) -> bool:
        """Shrink the step after a refusal; False when it cannot shrink further."""

    @abstractmethod
    def advance(self, verdict: Verdict) -> float | None:
        """Accept the reviewed state; the load factor to report it at, or None (not reported)."""

    @abstractmethod
    def step_size(self) -> float:
        """Size of the step last accepted (load factor or arc length)."""

    def exhausted(self, counters: Counters) -> str | None:
        """Why the path must stop now although unfinished (a step budget), or None."""
        return None

    def stopped_by_bifurcation(self, solve: Solve) -> float | None:
        """The load factor of a bifurcation that the last refused steps could not pass, or None.

        ``solve`` is the tracer's counted Newton solve, for any probe.
        """
        return None

    def unstable(self) -> int | None:
        """How many more negative eigenvalues the last accepted state's tangent has than the
        first point's, or None where this stepping does not count them (load control
        refuses an unstable state instead of reporting it)."""
        return None


def trace(
    system: System,
    loads: Loads,
    stepping: Stepping,
    newton: Newton = solve,
    resume: Counters | None = None,
) -> Iterator[PathPoint]:
    """Yield the converged points of the path ``stepping`` follows under ``loads``.

    ``newton`` is the Newton solve of a step problem: :func:`solve`, which
    a batch of copies traced together (:mod:`flexval.reducedmodels.core.batch`)
    calls with the copies still in the batch; the iteration counts are then
    one per copy (the counters carry them as arrays). With ``resume`` (the
    counts at a reported point) the path goes on from that point, where
    ``stepping`` stands already (a batch's copies that leave it go on from the
    last point they shared,
    :func:`flexval.reducedmodels.core.batch.trace_batch`): nothing is solved first
    and that point is not yielded again.

    Raises
    ------
    TraceFailure
        When the first point does not converge, when step cutting cannot
        save a step, or when the strategy's budget is exhausted; carries the
        last converged load factor and the counts.
    """
    settings = system.settings
    counters = Counters() if resume is None else resume.copy()

    def counted(
        problem: StepProblem, guess: np.ndarray, origin: np.ndarray | None = None
    ) -> NewtonResult:
        result = newton(problem, guess, settings, origin)
        # a new object, not in place: a batch's counts are an array the points keep
        counters.newton_iterations = counters.newton_iterations + result.iterations
        return result

    if resume is None:
        first = counted(FixedLoad(system, loads, stepping.first_factor), system.initial_state())
        if first.state is None:
            raise TraceFailure(first.reason, 0.0, counters)
        point = PathPoint(
            first.state, first.factor, first.iterations, first.tangent, 0.0, counters.copy()
        )
        try:
            stepping.begin(system, loads, point)
        except StepRefused as exc:
            raise TraceFailure(str(exc), point.factor, counters) from None
        yield point
    spent, found = 0, ()
    while not stepping.finished():
        problem, guess, origin = stepping.attempt()
        before = counters.newton_iterations
        verdict = stepping.review(counted(problem, guess, origin), counted)
        spent += counters.newton_iterations - before
        if verdict.state is None:
            counters.step_cuts += 1
            if not stepping.cut():
                raise TraceFailure(
                    f"{stepping.cut_name} cutting failed ({verdict.reason})",
                    stepping.factor,
                    counters,
                    found,
                    stepping.stopped_by_bifurcation(counted),
                )
            continue
        counters.substeps += 1
        found += verdict.bifurcations
        reported = stepping.advance(verdict)
        if reported is not None:
            yield PathPoint(
                verdict.state,
                reported,
                spent,
                verdict.tangent,
                stepping.step_size(),
                counters.copy(),
                found,
                stepping.unstable(),
            )
            spent, found = 0, ()
        why = stepping.exhausted(counters)
        if why is not None:
            raise TraceFailure(why, stepping.factor, counters, found)


class LoadControl(Stepping):
    """Load control through requested load factors with adaptive sub-steps.

    Between two requested factors the load factor advances in sub-steps
    that are halved when Newton fails, a body moves more than the bounds of
    :class:`~flexval.reducedmodels.core.settings.SolverSettings` or (with ``check_stability``)
    the equilibrium reached is unstable, and doubled (up to the spacing of
    the requested factors) after easy steps. Each sub-step starts from the
    extrapolation of the last ``PREDICTOR_STATES`` converged states
    (:meth:`System.predict`), the first from the tangent at rest (the
    solution of the linearised problem, K^-1 f times the step, through the
    connectors' own update; from the rest state alone there is nothing to
    extrapolate). Unless a connector predicts its own internal coordinates
    without it (:attr:`System.predicts_with_slope`: beams use it, the
    continuum does not), the extrapolation also matches the slope K^-1 f at
    the last state (one back-substitution with its tangent, factorised
    already); a sub-step whose prediction already moves a
    body beyond the bounds is halved before any Newton iteration is spent
    on it (it would be refused after its solve, or its iterates would
    leave the bounds: on the open chain's f- soft stretch such attempts
    cost 4 to 17 iterations each). Only the requested factors are reported.

    A batch of copies (``batch``, traced by
    :func:`flexval.reducedmodels.core.batch.trace_batch`) is load-controlled by
    the same decisions, taken for every copy still in the batch on its own
    measures: where the copies disagree the larger group goes on and the
    smaller leaves the batch (:attr:`active` false): its coordinates stay at
    its last accepted state and its tangent block as it was there, and
    ``trace_batch`` takes it on from the last reported level
    (:meth:`snapshot`, :meth:`resume`). A single path takes each decision on
    plain floats (a batch's per-copy bookkeeping would cost a small model
    more than its path).

    Parameters
    ----------
    factors : sequence of float
        Increasing load factors to report, the first solved from rest.
    batch : BatchSystem, optional
        The copies traced together (None: one path).
    """

    cut_name = "step"

    def __init__(self, factors: Sequence[float], batch: BatchSystem | None = None):
        self.factors = [float(f) for f in factors]
        self.first_factor = self.factors[0]
        self.batch = batch
        #: which copies are still in the batch (None: one path)
        self.active = None if batch is None else np.ones(batch.n_copies, bool)
        self.last: NewtonResult | None = None  # the last Newton solve of :meth:`newton`
        self._kept_next: np.ndarray | None = None  # a batch's tangent values, once accepted

    def begin(self, system: System, loads: Loads, point: PathPoint) -> None:
        """Start at the first requested factor (refused at rest where double precision does
        not resolve the System, :meth:`System.resolves`); a batch's copies whose first
        solve failed leave it."""
        if self.batch is not None and self.last is not None:
            self.leave(self.last.failed)
            self._keep(self.last.storage)
        if point.factor == 0.0 and not system.resolves(point.tangent):
            raise StepRefused(
                "the tangent at rest is not positive definite in double precision: the model's "
                "resolution is beyond what the arithmetic resolves (use fewer elements), or the "
                "unloaded mechanism is unstable under its own weight"
            )
        self.system, self.loads, self.settings = system, loads, system.settings
        self.q, self.factor = point.state, point.factor
        self.tangent = point.tangent  # at the last accepted state, to classify a bifurcation
        self.level = (self.q, self.factor)  # the state at the last requested factor reached
        self.unstable_above: float | None = None  # least factor refused as unstable
        self.history = [(self.q, self.factor)]  # converged (state, factor) for the predictor
        # what the connectors' own predictors keep of each state, computed once per state
        self.past = [system.remembered(self.q)] if system.predicts_internal else None
        self.slope = self._slope(point.tangent)
        f = self.factors
        self.spacing = f[1] - f[0] if len(f) > 1 else 1.0
        self.step = self.last_step = self.spacing
        self.min_step = self.spacing * 0.5**self.settings.max_cuts
        self.targets = iter(f[1:])
        self.target = next(self.targets, None)

    def finished(self) -> bool:
        """True after the last requested factor."""
        return self.target is None

    def attempt(self) -> tuple[StepProblem, np.ndarray, np.ndarray]:
        """Fixed load at the next sub-step (never past the next requested factor).

        The sub-step is halved (down to the smallest allowed) while the
        prediction moves a body beyond the step bounds (:meth:`_too_far`).
        """
        while True:
            trial = min(self.factor + self.step, self.target)
            guess = self._predict(trial)
            if 0.5 * self.step < self.min_step or not self._too_far(guess):
                break
            self.step *= 0.5
        if self.active is not None:  # the copies that left keep their state
            still = ~self.active[self.batch.dof_copy]
            guess[still] = self.q[still]
        self.last_step = trial - self.factor
        return FixedLoad(self.system, self.loads, trial), guess, self.q

    def _too_far(self, guess: np.ndarray) -> bool:
        """Whether the predicted state moves a body beyond the step bounds (a batch: the
        verdict of the larger group of its copies; the others leave)."""
        if self.active is None:
            return not self.system.motion_ratio(self.q, guess) <= 1.0
        return self._split_vote(self.batch.motion_ratios(self.q, guess) > 1.0)

    def _slope(self, tangent: Tangent | None) -> np.ndarray | None:
        """dq/dfactor at the last state, K^-1 f (mm, rad), or None when K cannot give it."""
        if tangent is None:
            return None
        try:
            slope = tangent.solve(self.loads.vector(self.q))
        except (RuntimeError, np.linalg.LinAlgError):  # singular: Newton will say so
            return None
        return slope if np.isfinite(slope).all() else None

    def _predict(self, factor: float) -> np.ndarray:
        """Predicted state at ``factor``: along the first tangent, then by extrapolation."""
        if len(self.history) == 1 and self.slope is not None:
            return self.system.update(self.q, self.slope * (factor - self.factor))
        return self.system.predict(self.history, factor, self.past, self.slope)

    def review(self, result: NewtonResult, solve: Solve) -> Verdict:
        """Refuse non-convergence, a step beyond the bounds and (optionally) instability (a
        batch: :meth:`_review_copies`)."""
        if self.active is not None:
            return self._review_copies(result)
        q_new, why = result.state, result.reason
        ratio = self.system.motion_ratio(self.q, q_new) if q_new is not None else math.inf
        if ratio <= 1.0 and self.settings.check_stability and self.system.unstable(result.tangent):
            q_new, ratio, why = None, math.inf, self.unstable_at(result.factor)
        if ratio > 1.0:
            return Verdict(
                None, result.factor, why if q_new is None else "step too large", None, False
            )
        return Verdict(
            q_new,
            result.factor,
            "",
            result.tangent,
            result.iterations <= self.settings.fast_iterations and ratio < 0.5,
        )

    def _review_copies(self, result: NewtonResult) -> Verdict:
        """:meth:`review` of every copy of a batch; the majority's verdict, the others
        leave."""
        batch, active = self.batch, self.active  # active: changed in place by the votes
        ratios = np.full(batch.n_copies, np.inf)
        ok = active & ~result.failed
        if result.state is not None and ok.any():
            ratios = np.where(ok, batch.motion_ratios(self.q, result.state), np.inf)
        within = ok & (ratios <= 1.0)
        unstable = np.zeros(batch.n_copies, bool)
        if within.any() and self.settings.check_stability:
            unstable = batch.copy_unstable(result.state, result.tangent, result.factor, within)
            within &= ~unstable
        refused = active & ~within
        accepted = self._split_vote(within)
        if not accepted:  # the copies left all refused this step: one path's reason
            k = int(np.flatnonzero(refused)[0])
            why = (
                result.reasons[k]
                if result.failed[k]
                else self.unstable_at(result.factor)
                if unstable[k]
                else "step too large"
            )
            return Verdict(None, result.factor, why, None, False)
        easy = result.iterations <= self.settings.fast_iterations
        fast = self._split_vote(easy & (ratios < 0.5))
        state = result.state.copy()
        still = ~self.active[batch.dof_copy]
        state[still] = self.q[still]
        storage, tangent = result.storage, result.tangent  # factorised by the stability check
        if not self.active.all():
            storage = storage.copy()
            batch.copy_blocks(storage, batch.kept, ~self.active)
            tangent = batch.layout.tangent(storage)
        self._kept_next = storage
        return Verdict(state, result.factor, "", tangent, fast)

    def unstable_at(self, factor: float) -> str:
        """Record an unstable equilibrium converged at load ``factor`` (the least one bounds
        the bracket :meth:`stopped_by_bifurcation` closes); the reason its step is refused.
        A batch's copies take the same decision (one place for a path and a batch)."""
        if self.unstable_above is None or factor < self.unstable_above:
            self.unstable_above = factor
        return UNSTABLE

    def cut(self) -> bool:
        """Halve the sub-step; False once the smallest is passed, or once the last stable state
        and the least unstable one are within ``BIFURCATION_RTOL`` of each other (a crossing
        located: closer, Newton's near-singular steps may leave the path for a crossing
        branch)."""
        self.step *= 0.5
        above = self.unstable_above
        if above is not None and above - self.factor <= BIFURCATION_RTOL * max(
            abs(above), self.spacing
        ):
            return False
        return self.step >= self.min_step

    def advance(self, verdict: Verdict) -> float | None:
        """Take the state; report it at the requested factor once that is reached.

        What the predictor keeps of the state (history, slope) is computed
        only if the path goes on after it. A batch's accepted tangent values become its
        copies' kept ones.
        """
        if self._kept_next is not None:
            self._keep(self._kept_next)
        self.q, self.factor, self.tangent = verdict.state, verdict.factor, verdict.tangent
        if self.unstable_above is not None and self.factor >= self.unstable_above:
            self.unstable_above = None  # that unstable state lay on another branch
        if verdict.fast:
            self.step = min(2.0 * self.step, self.spacing)
        reached = None
        if not self.factor < self.target - 1e-14 * self.spacing:
            reached, self.target = self.target, next(self.targets, None)
            self.level = (self.q, self.factor)
        if self.target is not None:
            self.slope = self._slope(verdict.tangent) if self.system.predicts_with_slope else None
            self.history = [*self.history[1 - PREDICTOR_STATES :], (self.q, self.factor)]
            if self.past is not None:
                self.past = [*self.past[1 - PREDICTOR_STATES :], self.system.remembered(self.q)]
        return reached

    def step_size(self) -> float:
        """Load-factor increment of the last accepted sub-step."""
        return self.last_step

    def stopped_by_bifurcation(self, solve: Solve) -> float | None:
        """The bifurcation between the last stable state and the nearest unstable one, if it is one.

        When step cutting fails after an unstable equilibrium was converged
        within the step bounds, an eigenvalue crossed zero between the last
        accepted factor and the least factor refused as unstable. That bracket
        is closed by bisection on the load factor (:meth:`_bracket`, the one
        stability rule at each state) and the path is probed
        :data:`BIFURCATION_PROBE` (relative) beyond it: a bifurcation leaves
        an equilibrium there, within the step bounds, unstable, reached from
        the stable state along a direction that is not the critical mode of
        the last stable tangent
        (:func:`~flexval.reducedmodels.core.bifurcation.classify`); a limit point
        leaves none. Returns the bracket's middle, or None. A batch of several
        copies that cannot go on hands its copies to batches of one instead (None).
        """
        if self.batch is not None and self.batch.n_copies != 1:
            return None
        above, system = self.unstable_above, self.system
        if above is None or self.tangent is None:
            return None
        lo, hi = self._bracket(solve, above)
        trial = self.factor + BIFURCATION_PROBE * max(abs(self.factor), self.spacing)
        q_level, factor_level = self.level  # a linear guess: the sub-steps near the crossing
        span = self.factor - factor_level  # are too close together to extrapolate through
        guess = (
            self.q if span <= 0.0 else self.q + (self.q - q_level) * ((trial - self.factor) / span)
        )
        probe = solve(FixedLoad(system, self.loads, trial), guess, self.q)
        if probe.state is None or system.motion_ratio(self.q, probe.state) > 1.0:
            return None
        if not system.unstable(probe.tangent):
            return None
        try:
            split, _ = classify(system, self.tangent, probe.state - self.q)
        except (ValueError, RuntimeError, np.linalg.LinAlgError):
            return None
        return 0.5 * (lo + hi) if split else None

    def _bracket(self, solve: Solve, above: float) -> tuple[float, float]:
        """The load factors (stable, unstable) closing on a change of inertia, to
        ``BIFURCATION_RTOL``.

        Bisection from the last stable state to ``above``, each middle solved
        from the linearised guess at the stable end (its slope K^-1 f); a
        middle that does not converge ends it with the bracket so far.
        """
        system, loads = self.system, self.loads
        lo, q_lo, hi = self.factor, self.q, above
        slope = self._slope(self.tangent)
        while hi - lo > BIFURCATION_RTOL * max(abs(hi), abs(lo)):
            mid = 0.5 * (lo + hi)
            guess = q_lo if slope is None else system.update(q_lo, slope * (mid - lo))
            result = solve(FixedLoad(system, loads, mid), guess, q_lo)
            if result.state is None or system.motion_ratio(q_lo, result.state) > 1.0:
                break
            count = system.instability(system.assemble(result.state, loads, mid)[2])
            if count is None:
                break
            if count > 0:
                hi = mid
            else:
                lo, q_lo = mid, result.state
        return lo, hi

    def exhausted(self, counters: Counters) -> str | None:
        """More sub-steps than ``max_substeps``."""
        limit = self.settings.max_substeps
        return f"more than {limit} load sub-steps" if counters.substeps > limit else None

    def snapshot(self) -> dict:
        """What load control carries from a reported point on (:meth:`resume` starts there).

        Taken where the tracer yields a point: every value here is replaced, never changed in
        place, as the path goes on, so the snapshot holds without a copy.
        """
        return {name: self.__dict__[name] for name in CARRIED}

    def resume(self, carried: dict, take: np.ndarray, loads: Loads) -> None:
        """Stand where a batch that these copies left stood at a reported point.

        ``carried`` is that batch's :meth:`snapshot`, ``take`` the index in its numbering
        of each of this batch's unknowns, ``loads`` this batch's. Every value of a copy is
        its own (the batch's arithmetic is each copy's), so the copies go on as their solo
        runs do from that point; what the connectors' predictors keep of each state is
        taken anew.
        """
        batch = self.batch
        self.system, self.loads, self.settings = batch, loads, batch.settings
        self.__dict__.update(carried)
        self.q = carried["q"][take]
        self.tangent = None  # a bifurcation is judged from the copy's own start
        self.level = (carried["level"][0][take], carried["level"][1])
        self.history = [(q[take], f) for q, f in carried["history"]]
        self.past = (
            [batch.remembered(q) for q, _ in self.history] if batch.predicts_internal else None
        )
        self.slope = None if carried["slope"] is None else carried["slope"][take]
        self.targets = iter([f for f in self.factors if f > self.target])

    def newton(self, problem: StepProblem, guess: np.ndarray, settings, origin=None):
        """The one Newton solve (:func:`~flexval.reducedmodels.core.newton.solve`), on the
        copies still in the batch where there is one."""
        self.last = solve(problem, guess, settings, origin, self.active)
        return self.last

    def leave(self, mask: np.ndarray) -> None:
        """Copies ``mask`` leave the batch (to be traced alone)."""
        self.active &= ~mask

    def _split_vote(self, yes: np.ndarray) -> bool:
        """The decision of the larger group of the active copies (ties: yes); the rest leave."""
        among = self.active
        ayes = int(np.count_nonzero(yes & among))
        noes = int(np.count_nonzero(among)) - ayes
        decision = ayes >= noes
        self.leave(among & (yes != decision))
        return decision

    def _keep(self, storage: np.ndarray) -> None:
        """Take the active copies' tangent values from ``storage`` as their accepted ones.

        :attr:`BatchSystem.kept` is replaced, never changed in place (a Newton solve and
        the accepted tangent may hold it): ``storage`` itself when every copy is active.
        """
        batch = self.batch
        if self.active.all():
            batch.kept = storage
        elif self.active.any():
            kept = batch.kept.copy()
            batch.copy_blocks(kept, storage, self.active)
            batch.kept = kept


CARRIED = (
    "q",
    "factor",
    "level",
    "unstable_above",
    "history",
    "slope",
    "spacing",
    "step",
    "last_step",
    "min_step",
    "target",
)
"""The attributes of :class:`LoadControl` that go from one reported point
to the next: the accepted state and factor, the predictor's states and slope, the step."""
