"""``flexval stiffness``: the 3 x 3 stiffness at a mechanism's target, at rest or under load.

The System is built exactly as for ``flexval run``; a loaded state is traced by
the same core (:func:`flexval.reducedmodels.analyses.modes.equilibrium`) to a fraction
of a load case, and the tangent there is condensed onto the target
(:func:`flexval.reducedmodels.analyses.targetstiffness.target_stiffness`): the primary
stiffness of a stage, its off-axis ratios and how a preload changes them, in
every family. Units: N/mm, N/rad, N mm/rad; compliances their inverses.
"""

from __future__ import annotations

import math

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.geometry.errors import COMMAND_LINE
from flexval.reducedmodels.analyses.modes import equilibrium, scaled_case
from flexval.reducedmodels.analyses.targetstiffness import TargetStiffness, target_stiffness
from flexval.reducedmodels.catalogue import LINEAR, ModelSpec
from flexval.reducedmodels.core.drives import refuse_prescribed_motion
from flexval.reducedmodels.models import build_system

MOTIONS = ("dx", "dy", "rotation")
"""The target's coordinates, in the order of the matrices' rows and columns."""
UNITS = {
    "stiffness": [["N/mm", "N/mm", "N/rad"], ["N/mm", "N/mm", "N/rad"], ["N", "N", "N mm/rad"]],
    "compliance": [
        ["mm/N", "mm/N", "mm/(N mm)"],
        ["mm/N", "mm/N", "mm/(N mm)"],
        ["rad/N", "rad/N", "rad/(N mm)"],
    ],
}
"""The unit of each entry: the stiffness maps (dx mm, dy mm, rotation rad) to (Fx N, Fy N,
M N mm), the compliance back."""


def run_stiffness(
    scene: Scene, spec: ModelSpec, case: LoadCase | None, fraction: float
) -> tuple[object, TargetStiffness, bool]:
    """The System, the target stiffness about the equilibrium at ``fraction`` of ``case``
    (None or 0: at rest, under the weights if any) and whether the model is linear (its
    stiffness is that at rest at every load).

    Raises
    ------
    SceneError
        A bad ``--at``.
    flexval.reducedmodels.core.settings.SolverError
        If the equilibrium cannot be reached, or its tangent is singular.
    """
    if not 0.0 <= fraction <= 1.0 or not math.isfinite(fraction):
        raise SceneError(
            COMMAND_LINE, "--at", fraction, "must be a load fraction from 0 (at rest) to 1"
        )
    if fraction:
        refuse_prescribed_motion(case, COMMAND_LINE, "--load-case", "stiffness about a preload")
    system = build_system(scene.mechanism, spec)
    linear = spec.model_family.has(LINEAR)
    if linear or case is None or fraction == 0.0:
        rest = scaled_case(system, None, 0.0)
        q = system.initial_state() if linear else equilibrium(system, rest)
        return system, target_stiffness(system, q, system.loads(rest), 0.0), linear
    q = equilibrium(system, scaled_case(system, case, fraction))
    return system, target_stiffness(system, q, system.loads(case), fraction), False


def stiffness_record(
    scene: Scene, spec: ModelSpec, case: LoadCase | None, fraction: float, found: TargetStiffness
) -> dict:
    """The JSON record: where, the stiffness and the compliance (rows and columns dx, dy,
    rotation) with their units, and whether the state is stable; where the model is rigid
    at the target, the stiffness is null and ``rigid_directions`` say along what."""
    return {
        "scene": scene.name,
        "model": spec.id,
        "load_case": None if case is None else case.name,
        "at": fraction if case is not None else 0.0,
        "body": scene.mechanism.target_body,
        "point_mm": found.point.tolist(),
        "coordinates": list(MOTIONS),
        "stiffness": None if found.stiffness is None else found.stiffness.tolist(),
        "compliance": found.compliance.tolist(),
        "rigid_directions": None if found.rigid is None else found.rigid.tolist(),
        "units": UNITS,
        "stable": found.stable,
    }
