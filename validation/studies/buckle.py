"""``flexval buckle``: linearised buckling of one model about an equilibrium, beside its path.

The System is built exactly as for ``flexval run``; the equilibrium at a
fraction of a load case is traced by the same core
(:func:`flexval.reducedmodels.analyses.modes.equilibrium`), the critical load factors
and modes come from :func:`flexval.reducedmodels.analyses.buckling.critical_factors`,
and the nonlinear answer, the bifurcation or limit load plain load control
stops at (:func:`flexval.validation.run.run_model`), is reported beside them.
Units: loads in N or N mm, load factors dimensionless, modes in mm and rad.
"""

from __future__ import annotations

import math

import numpy as np

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.geometry.errors import COMMAND_LINE
from flexval.reducedmodels.analyses.buckling import Buckling, critical_factors
from flexval.reducedmodels.analyses.modes import equilibrium, scaled_case
from flexval.reducedmodels.catalogue import LINEAR, ModelSpec
from flexval.reducedmodels.core.settings import SolverError


def run_buckle(
    scene: Scene, spec: ModelSpec, case: LoadCase, fraction: float, count: int
) -> tuple[object, Buckling]:
    """The System and the ``count`` lowest critical load factors of ``case`` about the
    equilibrium at ``fraction`` of it (0: the rest state).

    Raises
    ------
    SceneError
        Bad ``--at`` or ``--count``, or a linear model (no geometric stiffness).
    flexval.reducedmodels.core.settings.SolverError
        If the equilibrium cannot be reached, or its tangent is singular.
    """
    from flexval.reducedmodels.core.drives import refuse_prescribed_motion
    from flexval.reducedmodels.models import build_system

    refuse_prescribed_motion(case, COMMAND_LINE, "--load-case", "buckle")
    if not 0.0 <= fraction < 1.0 or not math.isfinite(fraction):
        raise SceneError(
            COMMAND_LINE, "--at", fraction, "must be a load fraction from 0 (at rest) up to 1"
        )
    if not 1 <= count <= 100:
        raise SceneError(COMMAND_LINE, "--count", count, "must be from 1 to 100")
    if spec.model_family.has(LINEAR):
        raise SceneError(
            COMMAND_LINE,
            "--model",
            spec.id,
            "is linear: it has no geometric stiffness and so no critical load "
            "(use a nonlinear model: beam, dcmm, prbm, continuum)",
        )
    system = build_system(scene.mechanism, spec)
    q = equilibrium(system, scaled_case(system, case, fraction))
    try:
        found = critical_factors(system, q, system.loads(case), fraction, count)
    except (np.linalg.LinAlgError, RuntimeError) as exc:
        raise SolverError(
            f"{spec.id} on load case '{case.name}': the tangent at {fraction:g} of the load "
            f"is singular ({exc}): the state is itself critical",
            fraction,
        ) from None
    return system, found


def buckle_record(
    scene: Scene, spec: ModelSpec, case: LoadCase, system, found: Buckling, path: dict
) -> dict:
    """The JSON record: critical loads (N or N mm) and factors, each mode's body motions
    (dx, dy, dtheta of each moving body's reference point, mm and rad), and the path's own
    answer (``path``: :func:`path_stop`)."""
    return {
        "scene": scene.name,
        "model": spec.id,
        "load_case": case.name,
        "load_unit": case.unit,
        "at": found.at,
        "critical_factors": found.factors.tolist(),
        "critical_loads": (found.factors * case.magnitude).tolist(),
        "mode_shapes": [
            {b: shape[system.pose_dofs(b)].tolist() for b in system.mechanism.moving_bodies}
            for shape in found.shapes
        ],
        "load_control": path,
        "linearisation_holds": linearisation_holds(found, path, case),
    }


def linearisation_holds(found: Buckling, path: dict, case: LoadCase) -> bool:
    """False where plain load control (``path``, :func:`path_stop`) passes the lowest
    critical load stably (no bifurcation there, and it reaches beyond it): the path's
    deformation before that load is too large for the linearisation about the state."""
    if not found.factors.size:
        return True
    lowest = float(found.factors[0]) * abs(case.magnitude)
    if path["kind"] == "bifurcation":
        return True
    reached = abs(case.magnitude) if path["kind"] == "none" else abs(path["load"])
    return reached < lowest


def path_stop(scene: Scene, spec: ModelSpec, case: LoadCase) -> dict:
    """Where plain load control of ``case`` stops: ``{"kind": "bifurcation" | "failure" |
    "none", "load": N or N mm or None, "reason": str}``."""
    from ..run import run_model

    try:
        path = run_model(scene, spec, case)
    except SolverError as exc:
        found = exc.path.bifurcations if exc.path is not None and exc.path.bifurcations else []
        if found:
            return {"kind": "bifurcation", "load": found[-1]["load"], "reason": str(exc)}
        return {
            "kind": "failure",
            "load": exc.load_factor * case.magnitude,
            "reason": str(exc),
        }
    if path.bifurcations:
        return {"kind": "bifurcation", "load": path.bifurcations[0]["load"], "reason": ""}
    return {"kind": "none", "load": None, "reason": "full load reached, stable"}
