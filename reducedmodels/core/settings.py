"""What a solve is asked for and how it fails: the solver's settings and its errors.

Units: those stated per setting (load factors and scaled corrections are
dimensionless).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from flexval.geometry.loads import MAX_LOAD_SUBSTEPS

if TYPE_CHECKING:
    from .loadpath import LoadPath


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


class PluginFailure(SolverError):
    """A plug-in family's own code raised while it ran a model (not a load it could not
    reach): the message names the plug-in package and what it raised. A command that
    judges models (``flexval gate``) stops on it instead of scoring the model."""


@dataclass
class SolverSettings:
    """Newton and load-stepping parameters (dimensionless unless stated).

    ``force_tol`` is relative to the full-load magnitude, ``step_tol`` is the
    scaled correction (translations / mechanism size, rotations in rad): since
    Newton converges quadratically, the error left after a correction of
    1e-8 is of order 1e-16. ``error_tol`` bounds the error left after a
    correction as estimated from the contraction of the last two (see
    :func:`flexval.reducedmodels.core.newton.solve`); 1e-10 keeps equilibrium
    to ~1e-8 of the load even on stiff (axial) modes.
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
    max_substeps: int = MAX_LOAD_SUBSTEPS
    max_rotation_step: float = 0.25
    max_translation_step: float = 0.05
    fast_iterations: int = 5
    max_excursion: float = 4.0
    max_stall: int = 5
    check_stability: bool = True
