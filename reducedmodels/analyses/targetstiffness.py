"""The stiffness of a mechanism at its target: what a designer asks of a stage first.

The tangent K of the whole System at an equilibrium (rest, or a loaded state,
the loads' own stiffness included) says how every coordinate answers a small
extra load. Condensed onto the target body's three pose coordinates, every
other coordinate free to follow, it is the 3 x 3 stiffness a probe at the
target would measure. The compliance is the cheaper way there: C = E^T K^-1 E,
E the unit loads on the target's pose, three solves with the tangent's
factorisation whatever the model (a beam chain, a PRBM with pins and
multipliers, the continuum's meshes), then C is moved from the body's
reference point to the target point and inverted. No second solver: the
tangent is the one the Newton iteration factorises.

Units: the stiffness maps (dx mm, dy mm, rotation rad) to (Fx N, Fy N, M N mm):
N/mm, N/rad and N mm/rad in its blocks; the compliance is its inverse.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.loads import Loads
from ..core.settings import SolverError
from ..core.system import System


@dataclass(frozen=True)
class TargetStiffness:
    """The 3 x 3 stiffness and compliance at the target point of a state.

    Attributes
    ----------
    stiffness : array (3, 3)
        (Fx N, Fy N, M N mm) per (dx mm, dy mm, rotation rad) of the target point and
        body, every other coordinate of the mechanism free.
    compliance : array (3, 3)
        Its inverse: (dx, dy, rotation) per (Fx, Fy, M) (mm/N, mm/(N mm) = rad/N, rad/(N mm)).
    point : array (2,)
        Where the target point is in that state, mm.
    stable : bool or None
        Whether the state is stable (the tangent positive definite), None where the model
        cannot judge it.
    rigid : array (k, 3) or None
        The directions along which the model is rigid at the target (the compliance's
        zero directions, each (dx, dy, rotation) with its largest entry 1), where
        ``stiffness`` is None; else None.
    """

    stiffness: np.ndarray | None
    compliance: np.ndarray
    point: np.ndarray
    stable: bool | None
    rigid: np.ndarray | None = None


def target_stiffness(
    system: System, q: np.ndarray, loads: Loads, factor: float = 0.0
) -> TargetStiffness:
    """The stiffness at the target point of ``system`` in state ``q`` under ``loads`` at
    load ``factor`` (0 at rest).

    Raises
    ------
    SolverError
        Where the tangent is singular: the mechanism can move at no cost (a free
        mechanism, or a state at a limit or bifurcation point).
    """
    mech = system.mechanism
    dofs = system.pose_dofs(mech.target_body)
    _, _, tangent = system.assemble(q, loads, factor)
    unit = np.zeros((system.n_dofs, 3))
    unit[dofs, [0, 1, 2]] = 1.0
    try:
        moved = np.column_stack([tangent.solve(unit[:, k]) for k in range(3)])
    except (np.linalg.LinAlgError, RuntimeError, ValueError) as exc:
        raise SolverError(
            f"the tangent is singular at {factor:g} of the load ({exc}): the mechanism "
            "moves there at no cost, and has no stiffness at its target",
            factor,
        ) from None
    at_reference = moved[dofs]
    if not np.isfinite(at_reference).all():
        raise SolverError(
            f"the tangent is singular at {factor:g} of the load: the mechanism moves there "
            "at no cost, and has no stiffness at its target",
            factor,
        )
    at_reference = 0.5 * (at_reference + at_reference.T)  # K is symmetric: round-off only
    x, y, _ = system.pose(q, mech.target_body).tolist()
    rx, ry = system.target_arm(q)
    # the point moves by (dx - ry dtheta, dy + rx dtheta); a load there is (F, M + r x F)
    # at the reference point: C_point = T C_reference T^T
    transport = np.array([[1.0, 0.0, -ry], [0.0, 1.0, rx], [0.0, 0.0, 1.0]])
    compliance = transport @ at_reference @ transport.T
    stiffness, rigid = _inverse(compliance)
    return TargetStiffness(
        stiffness,
        compliance,
        np.array([x + rx, y + ry]),
        None if not system.judges_stability() else not system.unstable(tangent),
        rigid,
    )


RIGID_RATIO = 1e-12
"""A compliance eigenvalue below this fraction of the largest is a rigid direction (the
round-off of three solves with a factorised tangent is ~1e-15 of it)."""


def _inverse(compliance: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(stiffness, None), or (None, the rigid directions) where the compliance has zero
    directions: a model rigid that way at the target (the PRBM's inextensible links along a
    straight leaf) has no finite stiffness."""
    values, vectors = np.linalg.eigh(compliance)
    rigid = values <= RIGID_RATIO * abs(values).max()
    if rigid.any():
        directions = vectors[:, rigid].T
        directions /= np.abs(directions).max(axis=1, keepdims=True)
        largest = np.argmax(np.abs(directions), axis=1)
        directions *= np.sign(directions[np.arange(len(directions)), largest])[:, None]
        return None, directions
    stiffness = np.linalg.inv(compliance)
    return 0.5 * (stiffness + stiffness.T), None
