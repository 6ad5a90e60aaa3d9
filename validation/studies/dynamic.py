"""``flexval run --dynamic``: time histories of one model on one load case.

The System is the static one (gravity included) with the masses of
:mod:`flexval.reducedmodels.core.inertia`; the load follows the case's time law
(:mod:`flexval.geometry.timelaw`) or, without one, the paper's Eq. 15 ramp over the
first 80 % of ``--duration`` (:data:`DEFAULT_LAW` when no duration is given: from 0 to
t1 = 1 s, a run of 1.25 t1, as a time law without ``end_time`` gives). Damping is
Rayleigh's, given directly or as a damping ratio that holds exactly at the two lowest
natural frequencies at rest. The paper's "damping adjusted to minimise dynamic effects"
is, in these terms, a ratio near 1 (critical damping of the two lowest modes).
Units: s, mm, rad, Hz.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.geometry.errors import COMMAND_LINE
from flexval.geometry.timelaw import TimeLaw
from flexval.reducedmodels.analyses.dynamics import (
    DynamicSettings,
    Rayleigh,
    iteration_seconds,
    solve_dynamic,
)
from flexval.reducedmodels.analyses.modes import natural_modes
from flexval.reducedmodels.catalogue import ModelSpec
from flexval.reducedmodels.core.loadpath import LoadPath
from flexval.reducedmodels.core.settings import SolverError

from .modes import modal_system

DEFAULT_RAMP_FRACTION = 0.8
"""Without a time law in the scene, the Eq. 15 ramp ends at this fraction of the duration."""
DEFAULT_LAW = TimeLaw()
"""A load case without a time law, run without ``--duration``: the Eq. 15 ramp from 0 to
t1 = 1 s (the time-law fields' defaults), for 1.25 t1 (its default duration), so that the
ramp spans :data:`DEFAULT_RAMP_FRACTION` of the run as with a given duration."""
MIN_DURATION = DynamicSettings().min_step / DynamicSettings().first_step
"""Shortest run (s): its first step (``first_step`` of the duration) is the smallest allowed."""


def time_law(case: LoadCase, duration: float | None, source: str) -> tuple[TimeLaw, float]:
    """The case's time law and the run's duration (s); ``--duration`` overrides the end time.

    Without a time law: :data:`DEFAULT_LAW` and its duration (1.25 s), or, given a
    duration T, the Eq. 15 ramp from 0 to 0.8 T.

    ``source`` names the scene file in the error raised for a time law too short to run."""
    if duration is not None and not (math.isfinite(duration) and MIN_DURATION <= duration <= 1e6):
        raise SceneError(
            COMMAND_LINE,
            "--duration",
            duration,
            f"must be a time in s from {MIN_DURATION:g} to 1e6 (the first time "
            "step of a shorter run falls below the integrator's smallest)",
        )
    law = case.time_law
    if law is None:
        if duration is None:
            return DEFAULT_LAW, DEFAULT_LAW.duration
        return TimeLaw("eq15", 0.0, DEFAULT_RAMP_FRACTION * duration), duration
    if duration is None:
        duration = law.duration
        if duration < MIN_DURATION:
            field, value = (
                ("end_time", law.end_time) if law.end_time is not None else ("t1", law.t1)
            )
            raise SceneError(
                source,
                f"load_cases.{case.name}.{field}",
                value,
                f"gives a run of {duration:g} s, shorter than {MIN_DURATION:g} s: "
                "its first time step would fall below the integrator's smallest",
            )
    return law, duration


def damping_of(system, ratio: float | None, rayleigh: tuple[float, float] | None) -> Rayleigh:
    """Rayleigh damping from ``(alpha, beta)`` or from a damping ratio at the two lowest
    natural frequencies at rest (mass-proportional only with a single mode)."""
    if rayleigh is not None:
        alpha, beta = rayleigh
        if not (math.isfinite(alpha) and math.isfinite(beta) and alpha >= 0.0 and beta >= 0.0):
            raise SceneError(
                COMMAND_LINE,
                "--rayleigh",
                list(rayleigh),
                "alpha (1/s) and beta (s) must be finite and not negative",
            )
        return Rayleigh(alpha, beta)
    if not ratio:
        return Rayleigh()
    if not (math.isfinite(ratio) and 0.0 < ratio <= 10.0):
        raise SceneError(COMMAND_LINE, "--damping-ratio", ratio, "must be from 0 to 10")
    f = natural_modes(system, count=2).frequencies_hz
    if f.size < 2:
        return Rayleigh(4.0 * math.pi * ratio * f[0], 0.0)
    return Rayleigh.from_ratio(ratio, f[0], f[1])


def check_options(rho_inf: float, error_tol: float) -> None:
    """Refuse (SceneError naming the option) a spectral radius outside [0, 1] or an error
    tolerance outside [1e-14, 0.1]."""
    if not 0.0 <= rho_inf <= 1.0:
        raise SceneError(COMMAND_LINE, "--rho-inf", rho_inf, "must be from 0 to 1")
    if not 1e-14 <= error_tol <= 0.1:  # NaN fails too
        raise SceneError(COMMAND_LINE, "--error-tol", error_tol, "must be from 1e-14 to 0.1")


def run_dynamic(
    scene: Scene,
    spec: ModelSpec,
    case: LoadCase,
    duration: float | None = None,
    damping_ratio: float | None = None,
    rayleigh: tuple[float, float] | None = None,
    rho_inf: float = 0.9,
    record_poses: bool = False,
    error_tol: float = DynamicSettings().error_tol,
) -> LoadPath:
    """Integrate ``case`` of ``scene`` with model ``spec`` in time (see the module docstring).

    ``error_tol`` bounds each step's local displacement error (scaled: lengths
    over the mechanism size, angles in rad; :class:`DynamicSettings`): the
    global error of a history falls about 3-5 times per decade of it.

    Raises
    ------
    SceneError
        Bad options or a massless body.
    flexval.reducedmodels.core.settings.SolverError
        If the time stepping fails; carries the history so far.
    """
    check_options(rho_inf, error_tol)
    law, end = time_law(case, duration, scene.source)
    system = modal_system(scene, spec)
    lp = solve_dynamic(
        system,
        case,
        law,
        end,
        damping_of(system, damping_ratio, rayleigh),
        DynamicSettings(rho_inf=rho_inf, error_tol=error_tol),
        model=spec.id,
        scene=scene.name,
        record_poses=record_poses,
    )
    return lp


STEPS_FIT = (5.03, 0.229, -0.256)
"""(a, b, c) of the accepted time steps of a run, a (T f1)^b error_tol^c (T the duration in
s, f1 the lowest natural frequency at rest in Hz), at least :func:`fewest_steps`: fitted by
least squares on log steps over 104 runs of open_chain (density 1.24e-9 and 1.24e-8 t/mm^3:
f1 21.6 and 6.8 Hz), beam:20 and dcmm:1, cases f- and m+, durations 0.25 to 5 s, error_tol
1e-4 to 1e-6, undamped and at damping ratio 1. Estimate over measured steps: median 1.18,
0.21 to 3.34, within a factor 2 for 63 runs and 3 for 89 (the undamped f- runs oscillate
most and take up to 5 times the steps of a quasi-static m+ of the same duration: the
estimate cannot see how much a load excites the modes)."""
ITERATIONS_PER_STEP = 3.0
"""Newton iterations per accepted step, rejected steps' included: median 3.03 (2.0 to 6.4)
over the runs of :data:`STEPS_FIT`."""
PROGRESS_UNITS = 20
"""Progress lines of a long dynamic run: one each time it reaches another 1/20 of its
duration."""


def fewest_steps(settings: DynamicSettings) -> float:
    """Accepted steps of a run that takes the largest step (``max_step`` of the duration)
    from its first (``first_step``), doubling."""
    return 1.0 / settings.max_step + math.log2(settings.max_step / settings.first_step)


def estimate_steps(duration: float, frequency: float, error_tol: float) -> float:
    """Accepted time steps of a run of ``duration`` (s) of a mechanism whose lowest natural
    frequency at rest is ``frequency`` (Hz), at ``error_tol`` (:data:`STEPS_FIT`)."""
    a, b, c = STEPS_FIT
    return max(fewest_steps(DynamicSettings()), a * (duration * frequency) ** b * error_tol**c)


@dataclass(frozen=True)
class DynamicEstimate:
    """What a dynamic run is estimated to take: accepted ``steps``, wall time ``seconds``
    (steps x :data:`ITERATIONS_PER_STEP` x ``iteration`` s) and the lowest natural
    ``frequency`` at rest (Hz) and ``duration`` (s) it was estimated from."""

    steps: float
    seconds: float
    iteration: float
    frequency: float
    duration: float


def estimate_dynamic(
    scene: Scene,
    spec: ModelSpec,
    case: LoadCase,
    duration: float | None = None,
    error_tol: float = DynamicSettings().error_tol,
    rho_inf: float = 0.9,
) -> DynamicEstimate | None:
    """Estimate :func:`run_dynamic` of ``spec`` on ``case`` before running it: the lowest
    natural frequency at rest (one mode) and one Newton iteration of a step, timed; None when
    the mechanism has no equilibrium at rest (the run says why).

    Raises
    ------
    SceneError
        As :func:`run_dynamic` does for bad options or a massless body.
    """
    check_options(rho_inf, error_tol)
    _, end = time_law(case, duration, scene.source)
    system = modal_system(scene, spec)
    try:
        frequency = float(natural_modes(system, count=1).frequencies_hz[0])
    except SolverError:
        return None
    settings = DynamicSettings(rho_inf=rho_inf, error_tol=error_tol)
    steps = estimate_steps(end, frequency, error_tol)
    once = iteration_seconds(system, case, end, settings)
    return DynamicEstimate(steps, steps * ITERATIONS_PER_STEP * once, once, frequency, end)


def describe(estimates: list[tuple[str, str, DynamicEstimate]]) -> str:
    """One line: the total estimated time of the runs ``(model, case, estimate)`` and the
    longest's steps, duration and lowest natural frequency."""
    from ..resources import duration as text

    total = sum(e.seconds for _, _, e in estimates)
    model, case, e = max(estimates, key=lambda x: x[2].seconds)
    return (
        f"estimate: about {text(total)} of time stepping (the longest: {model} on {case}, "
        f"about {e.steps:,.0f} steps over {e.duration:g} s, lowest mode {e.frequency:.4g} Hz "
        f"at rest, {1e3 * e.iteration:.2g} ms an iteration)"
    )


@contextmanager
def time_progress(paths: int, enabled: bool) -> Iterator[None]:
    """Within the block, a :class:`~flexval.validation.studies.campaign.Progress` line on stderr
    each
    time a dynamic run reaches another 1/:data:`PROGRESS_UNITS` of its duration, of
    ``paths`` runs in all: the model, the case, the time reached over the duration, the time
    so far and about how long the rest takes at that rate. Nothing when not ``enabled``; the
    runs are the same either way (the observer only reads them)."""
    if not enabled:
        yield
        return
    from flexval.reducedmodels.core.recorder import observing

    from .campaign import Progress

    bar = Progress(paths * PROGRESS_UNITS, lines=True)
    shown: dict[int, int] = {}

    def show(lp: LoadPath) -> None:
        if not lp.time:
            return
        end = lp.settings["duration"]
        reached = min(PROGRESS_UNITS, int(PROGRESS_UNITS * lp.time[-1] / end * (1 + 1e-12)))
        while shown.get(id(lp), 0) < reached:
            shown[id(lp)] = shown.get(id(lp), 0) + 1
            bar.step(f"{lp.model} on {lp.load_case}: t {lp.time[-1]:.4g} of {end:.4g} s")

    with observing(show):
        yield
