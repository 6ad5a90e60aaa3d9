"""``flexval run --dynamic``: time histories of one model on one load case.

The System is the static one (gravity included) with the masses of
:mod:`flexval.reducedmodels.inertia`; the load follows the case's time law
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

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.geometry.timelaw import TimeLaw
from flexval.reducedmodels.catalogue import ModelSpec
from flexval.reducedmodels.dynamics import DynamicSettings, Rayleigh, solve_dynamic
from flexval.reducedmodels.loadpath import LoadPath
from flexval.reducedmodels.modes import natural_modes

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
            "<command line>",
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
                "<command line>",
                "--rayleigh",
                list(rayleigh),
                "alpha (1/s) and beta (s) must be finite and not negative",
            )
        return Rayleigh(alpha, beta)
    if not ratio:
        return Rayleigh()
    if not (math.isfinite(ratio) and 0.0 < ratio <= 10.0):
        raise SceneError("<command line>", "--damping-ratio", ratio, "must be from 0 to 10")
    f = natural_modes(system, count=2).frequencies_hz
    if f.size < 2:
        return Rayleigh(4.0 * math.pi * ratio * f[0], 0.0)
    return Rayleigh.from_ratio(ratio, f[0], f[1])


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
    flexval.reducedmodels.core.SolverError
        If the time stepping fails; carries the history so far.
    """
    if not 0.0 <= rho_inf <= 1.0:
        raise SceneError("<command line>", "--rho-inf", rho_inf, "must be from 0 to 1")
    if not 1e-14 <= error_tol <= 0.1:  # NaN fails too
        raise SceneError("<command line>", "--error-tol", error_tol, "must be from 1e-14 to 0.1")
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
