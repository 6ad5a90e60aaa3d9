"""Time integration of the multibody System: generalised-alpha on the core's one Newton.

Equations of motion (mm, N, t, s):

    M(q) a + c(q, v) + D v + grad Pi(q, lambda(t)) = 0,

with grad Pi the System's gradient (elastic forces, weights, load case at the
load factor lambda(t) of the time law), M and c the mass matrix and
convective forces of :class:`flexval.reducedmodels.core.inertia.MassModel`, and Rayleigh
damping D = alpha M + beta K(q), K the tangent at the same state q as every
other force (equilibrium at t_(n+1)): K frozen at the start of the step would
make the damping force first-order in h. Coordinates without mass (Lagrange
multipliers, massless internal coordinates) keep static rows.

Integrator: generalised-alpha in the form of Arnold and Bruls (2007, Multibody
Syst. Dyn. 18:185), its parameters those of Chung and Hulbert (1993) for the
spectral radius rho_inf at infinite frequency (second order, unconditionally
stable; rho_inf = 1 has no numerical dissipation). Each step is one
:func:`flexval.reducedmodels.core.newton.solve` on :class:`DynamicStep`, whose
effective tangent is summed in the System's tangent storage and factorised like
the static tangent; the steps adapt to the local error estimate of Zienkiewicz
and Xie (1991) against ``error_tol``. The update, the effective tangent and the
step control are in the documentation's models page, "Mass and dynamics".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexval.geometry import LoadCase
from flexval.geometry.timelaw import TimeLaw

from ..core.inertia import MassModel
from ..core.loadpath import LoadPath
from ..core.loads import Loads
from ..core.newton import FixedLoad, StepProblem, solve
from ..core.recorder import notify
from ..core.settings import SolverError
from ..core.system import System
from ..core.tangent import Tangent
from ..kernels.clock import path_clock
from .modes import refuse_massless_bodies


@dataclass(frozen=True)
class Rayleigh:
    """Rayleigh damping D = alpha M + beta K: alpha in 1/s, beta in s."""

    alpha: float = 0.0
    beta: float = 0.0

    @classmethod
    def from_ratio(cls, ratio: float, f1: float, f2: float) -> Rayleigh:
        """The damping ratio ``ratio`` at the two frequencies f1 < f2 (Hz), exactly.

        zeta(omega) = alpha / (2 omega) + beta omega / 2; between f1 and f2 it
        is a little below ``ratio``, outside it grows.
        """
        w1, w2 = 2.0 * math.pi * f1, 2.0 * math.pi * f2
        return cls(2.0 * ratio * w1 * w2 / (w1 + w2), 2.0 * ratio / (w1 + w2))


@dataclass(frozen=True)
class GeneralizedAlpha:
    """Chung-Hulbert parameters from the spectral radius at infinite frequency,
    rho_inf in [0, 1]."""

    rho_inf: float = 0.9

    @property
    def am(self) -> float:
        return (2.0 * self.rho_inf - 1.0) / (self.rho_inf + 1.0)

    @property
    def af(self) -> float:
        return self.rho_inf / (self.rho_inf + 1.0)

    @property
    def gamma(self) -> float:
        return 0.5 + self.af - self.am

    @property
    def beta(self) -> float:
        return 0.25 * (self.gamma + 0.5) ** 2


@dataclass
class DynamicSettings:
    """Time-stepping parameters.

    ``error_tol`` bounds the estimated local displacement error per step
    (scaled: lengths / mechanism size, angles in rad); ``first_step`` and
    ``max_step`` are fractions of the duration; ``min_step`` (s) ends a run
    that cannot proceed.
    """

    rho_inf: float = 0.9
    error_tol: float = 1e-5
    first_step: float = 1e-3
    max_step: float = 0.02
    min_step: float = 1e-12
    max_steps: int = 200_000
    adaptive: bool = True


DAMPING_DERIVATIVE_STEP = 1e-7
"""Scaled size (lengths over the mechanism size, angles in rad) of the forward difference along
v that gives the damping force's derivative beta dK(q)[v] (see :class:`DynamicStep`): the
Jacobian it leaves is off by about this fraction, far below what slows Newton, and K's
round-off (1e-16 of its size) stays 1e-9 of the difference."""


class _SparseEffectiveTangent:
    """K + c_d D + c_m M factorised by SuperLU (a mass matrix the tangent storage cannot hold)."""

    def __init__(self, matrix: sp.csc_matrix):
        self._lu = spla.splu(matrix)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return self._lu.solve(rhs)


class DynamicStep(StepProblem):
    """One generalised-alpha step from (q_n, v_n, a_n, A_n) over h at load factor lambda(t_(n+1)).

    Its residual is the out-of-balance force including inertia and damping;
    its tangent the effective one, K + c_d D + c_m M plus the derivative of
    the damping force beta K(q) v along the motion, beta dK(q)[v] (a forward
    difference of the tangent along v, :data:`DAMPING_DERIVATIVE_STEP`):
    without it a strongly damped run took 10 to 18 Newton iterations per
    step. The derivatives of M(q) and c(q, v) are left out (they change
    Newton's rate, not its answer). The mass matrix is summed into the
    System's tangent storage when that can hold it (always on the built-in
    models: the masses sit on coordinates the connectors couple already), so
    the effective tangent is factorised like the static one (banded beams:
    the compiled banded Cholesky); otherwise it becomes a scipy matrix.
    """

    def __init__(
        self,
        system: System,
        loads: Loads,
        factor: float,
        mass: MassModel,
        state: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        h: float,
        scheme: GeneralizedAlpha,
        damping: Rayleigh,
    ):
        super().__init__(system, loads, factor)
        self.mass, self.h, self.scheme, self.damping = mass, h, scheme, damping
        self.q0, self.v0, self.a0, self.A0 = state
        b, g = scheme.beta, scheme.gamma
        self.c_m = (1.0 - scheme.am) / ((1.0 - scheme.af) * b * h * h)
        self.c_d = g / (b * h)

    def kinematics(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Velocity, acceleration and algorithmic acceleration at iterate q (mm/s, mm/s^2)."""
        s, h = self.scheme, self.h
        A = (q - self.q0 - h * self.v0 - h * h * (0.5 - s.beta) * self.A0) / (s.beta * h * h)
        v = self.v0 + h * ((1.0 - s.gamma) * self.A0 + s.gamma * A)
        a = ((1.0 - s.am) * A + s.am * self.A0 - s.af * self.a0) / (1.0 - s.af)
        return v, a, A

    def assemble(self, q: np.ndarray) -> tuple[np.ndarray, Tangent | _SparseEffectiveTangent]:
        """Out-of-balance force with inertia and damping (N, N mm) and the effective tangent."""
        system, layout = self.system, self.system.layout
        _, g, stiffness = system.assemble_storage(q, self.loads, self.factor)
        v, a, _ = self.kinematics(q)
        alpha, beta = self.damping.alpha, self.damping.beta
        r = g + self.mass.convective(q, v) + beta * layout.product(stiffness, v)
        # K's part of the effective tangent: (1 + c_d beta) K + beta dK[v]
        effective = (1.0 + self.c_d * beta) * stiffness
        speed = float(np.abs(system.scaled(v)).max(initial=0.0))
        if beta and speed:
            eps = DAMPING_DERIVATIVE_STEP / speed
            moved = system.assemble_storage(q + eps * v, self.loads, self.factor)[2]
            effective += (beta / eps) * (moved - stiffness)
        rows, cols, values = self.mass.entries(q)
        slots = layout.slots_of(rows, cols)
        c_mass = self.c_m + self.c_d * alpha
        if slots is None:
            M = sp.csr_matrix((values, (rows, cols)), shape=(system.n_dofs, system.n_dofs))
            r += M @ (a + alpha * v)
            k = sp.csc_matrix(layout.tangent(effective).toarray())
            return r, _SparseEffectiveTangent((k + c_mass * M).tocsc())  # no copy if CSC
        kept = slots >= 0  # a symmetric band: the upper mirror holds the value
        mass = np.bincount(slots[kept], weights=values[kept], minlength=layout.size)
        r += layout.product(mass, a + alpha * v)
        effective += c_mass * mass
        return r, layout.tangent(effective)

    def correction(self, q: np.ndarray, g: np.ndarray, K) -> tuple[np.ndarray, float]:
        return K.solve(-g), 0.0


def solve_dynamic(
    system: System,
    case: LoadCase,
    law: TimeLaw,
    duration: float,
    damping: Rayleigh = Rayleigh(),
    settings: DynamicSettings | None = None,
    model: str = "",
    scene: str = "",
    record_poses: bool = False,
    initial_velocity: np.ndarray | None = None,
) -> LoadPath:
    """Integrate from rest (the equilibrium at lambda(0), gravity included) to ``duration`` (s).

    Every accepted step is recorded: ``time`` (s), ``load`` (lambda(t) times
    the case's value), the target's ``dx``, ``dy``, ``rotation`` and, on
    request, every body's pose. ``stats`` adds ``steps``, ``rejected_steps``
    and the energy balance at the end (N mm): ``kinetic_energy`` and
    ``potential_change``, the total potential (strain energy, weights and
    the load case at the current factor) at the end minus at the start.

    Raises
    ------
    SceneError
        If a moving body has no mass.
    SolverError
        If a step fails below ``min_step``; carries the path so far.
    """
    t_start = path_clock()
    s = settings or DynamicSettings()
    scheme = GeneralizedAlpha(s.rho_inf)
    mass = MassModel(system)
    massless = mass.massless()
    refuse_massless_bodies(system, massless, "a dynamic run")
    # the step error is measured on the rigid bodies' motion (what a run reports); the
    # flexures' internal high modes are left to the numerical dissipation (rho_inf < 1)
    bodies = np.zeros(system.n_dofs, bool)
    bodies[: 3 * len(system.body_index)] = True
    loads = system.loads(case)
    path = LoadPath(
        model=model,
        load_case=case.name,
        load=[],
        dx=[],
        dy=[],
        rotation=[],
        seconds=0.0,
        scene=scene,
        load_unit=case.unit,
        time=[],
        poses={b: [] for b in system.mechanism.bodies} if record_poses else None,
        settings={
            "rho_inf": s.rho_inf,
            "error_tol": s.error_tol,
            "rayleigh_alpha": damping.alpha,
            "rayleigh_beta": damping.beta,
            "ramp": law.ramp,
            "t0": law.t0,
            "t1": law.t1,
            "duration": duration,
        },
    )
    stats = {"unknowns": system.n_dofs, "steps": 0, "rejected_steps": 0, "newton_iterations": 0}

    def record(t: float, q: np.ndarray) -> None:
        dx, dy, rot = system.target(q)
        path.time.append(t)
        path.load.append(law(t) * case.magnitude)
        path.dx.append(dx), path.dy.append(dy), path.rotation.append(rot)
        if path.poses is not None:
            for b in system.mechanism.bodies:
                path.poses[b].append(system.pose(q, b).tolist())
        notify(path)

    def fail(message: str, t: float) -> SolverError:
        stats["failure"] = message
        path.converged, path.stats = False, stats
        path.seconds = path_clock() - t_start
        return SolverError(
            f"{model or 'model'} dynamic run on '{case.name}': {message}; "
            f"reached t = {t:.6g} s of {duration:.6g} s",
            law(t),
            path,
        )

    first = solve(FixedLoad(system, loads, law(0.0)), system.initial_state(), system.settings)
    if first.state is None:
        raise fail(f"no initial equilibrium ({first.reason})", 0.0)
    q = first.state
    potential_start = system.assemble(q, loads, law(0.0))[0]
    v = np.zeros(system.n_dofs) if initial_velocity is None else np.asarray(initial_velocity, float)
    a = np.zeros(system.n_dofs)
    A = a.copy()
    t, h, rejected = 0.0, s.first_step * duration, False
    record(t, q)
    while t < duration * (1.0 - 1e-12):
        h = min(h, s.max_step * duration, duration - t)
        step = DynamicStep(system, loads, law(t + h), mass, (q, v, a, A), h, scheme, damping)
        guess = q + h * v + h * h * (0.5 - scheme.beta) * A + h * h * scheme.beta * A
        result = solve(step, guess, system.settings)
        stats["newton_iterations"] += result.iterations
        error = math.inf
        if result.state is not None:
            v_new, a_new, A_new = step.kinematics(result.state)
            change = system.scaled(h * h * abs(scheme.beta - 1.0 / 6.0) * (A_new - A))
            error = float(np.abs(change[bodies]).max(initial=0.0)) if s.adaptive else 0.0
        if error > s.error_tol:
            stats["rejected_steps"] += 1
            rejected = True
            h *= (
                0.5
                if not math.isfinite(error)
                else max(0.2, 0.9 * (s.error_tol / error) ** (1 / 3))
            )
            if h < s.min_step:
                raise fail(
                    f"time step below {s.min_step:g} s "
                    f"({result.reason or 'local error too large'})",
                    t,
                )
            continue
        q, v, a, A, t = result.state, v_new, a_new, A_new, t + h
        stats["steps"] += 1
        if stats["steps"] > s.max_steps:
            raise fail(f"more than {s.max_steps} time steps", t)
        record(t, q)
        if s.adaptive:  # no growth right after a rejection: it would only be rejected again
            grow = 1.0 if rejected else 2.0
            h *= min(grow, max(0.5, 0.9 * (s.error_tol / max(error, 1e-300)) ** (1 / 3)))
        rejected = False
    stats["kinetic_energy"] = mass.kinetic_energy(q, v)
    stats["potential_change"] = system.assemble(q, loads, law(t))[0] - potential_start
    path.stats = stats
    path.seconds = path_clock() - t_start
    return path


def iteration_seconds(
    system: System,
    case: LoadCase,
    duration: float,
    settings: DynamicSettings | None = None,
    damping: Rayleigh = Rayleigh(),
    repeats: int = 3,
) -> float:
    """Wall time of one Newton iteration of a time step (s): the effective residual and
    tangent of a first step at rest, assembled and solved ``repeats`` times, the fastest
    (for estimates of a run's time; nothing is integrated)."""
    s = settings or DynamicSettings()
    q = system.initial_state()
    zero = np.zeros(system.n_dofs)
    step = DynamicStep(
        system,
        system.loads(case),
        0.0,
        MassModel(system),
        (q, zero, zero, zero),
        s.first_step * duration,
        GeneralizedAlpha(s.rho_inf),
        damping,
    )
    best = math.inf
    for _ in range(repeats):
        t0 = path_clock()
        r, K = step.assemble(q)
        step.correction(q, r, K)
        best = min(best, path_clock() - t0)
    return best
