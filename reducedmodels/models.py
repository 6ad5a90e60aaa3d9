"""Build and run the reduced models by name: ``beam:N``, ``prbm``, ``dcmm:N``, ``ee``.

Only the requested model is built (lazy imports keep ``flexval info`` and a
DCMM run free of the beam and PRBM code paths).
"""

from __future__ import annotations

import time

import numpy as np

from geometry import LoadCase, Mechanism, ModelSpec, SceneError
from geometry.kinematics import rigid_points

from .core import SolverSettings, System
from .loadpath import LoadPath
from .recorder import solve_path

REDUCED_FAMILIES = ("beam", "prbm", "dcmm", "ee")


def _connector(mechanism: Mechanism, flexure, spec: ModelSpec, options: dict):
    """One flexure's connector for model ``spec`` (only the requested model is imported)."""
    if spec.family in ("dcmm", "ee"):
        from .dcmm import DcmmConnector

        n = spec.resolution if spec.family == "dcmm" else 1
        return DcmmConnector(flexure, mechanism, n, **options)
    if spec.family == "beam":
        from .beam import BeamConnector

        return BeamConnector(flexure, mechanism, spec.resolution, **options)
    if spec.family == "prbm":
        from .prbm import PrbmConnector

        return PrbmConnector(flexure, mechanism, **options)
    raise ValueError(f"'{spec.id}' is not a reduced model; expected one of {REDUCED_FAMILIES}")


def build_system(mechanism: Mechanism, spec: ModelSpec,
                 settings: SolverSettings | None = None, **options) -> System:
    """The multibody System of ``mechanism`` with every flexure modelled as ``spec``.

    Pins (``mechanism.pins``) are added as exact Lagrange-multiplier joints
    (:class:`reducedmodels.joints.PinConnector`) whatever the model.

    ``options`` are passed to the connector (e.g. ``shear=True`` for beams,
    ``frame="follower"`` for DCMM).

    Raises
    ------
    SceneError
        If the model cannot represent a flexure (e.g. a PRBM arc angle outside
        its fitted table); the field names the flexure.
    """
    conns = []
    for f in mechanism.flexures:
        try:
            conns.append(_connector(mechanism, f, spec, options))
        except ValueError as exc:      # the model cannot represent this flexure
            raise SceneError(mechanism.source, f"flexures.{f.name}", spec.id, str(exc)) from None
    if mechanism.pins:
        from .joints import pin_connectors

        conns += pin_connectors(mechanism)
    return System(mechanism, conns, settings or SolverSettings())


def solve_linear(system: System, case: LoadCase, levels: int | None = None, model: str = "ee",
                 scene: str = "") -> LoadPath:
    """Linear response at the undeformed configuration (the EE prediction).

    Solves K0 dq = lambda f with the elastic tangent K0 at rest (no load
    stiffness, no large-rotation terms) and reports the linearised target
    displacement J dq; it is proportional to the load.
    """
    t0 = time.perf_counter()
    loads = system.loads(case)
    q0 = system.initial_state()
    _, g_unit, _ = system.assemble(q0, loads, 1.0)   # g = grad E(q0) - f = -f at rest
    _, g_zero, K0 = system.assemble(q0, loads, 0.0)
    dq = K0.solve(g_zero - g_unit)
    mech = system.mechanism
    tdofs = system.pose_dofs(mech.target_body)
    rel = mech.target_point - system.reference[mech.target_body]
    _, jac, _ = rigid_points(np.array([*system.reference[mech.target_body], 0.0]), rel[None])
    unit = jac[0] @ dq[tdofs]
    rot = float(dq[tdofs[2]])
    lam = case.factors(levels)
    return LoadPath(model=model, load_case=case.name, load=list(lam * case.magnitude),
                    dx=list(lam * unit[0]), dy=list(lam * unit[1]), rotation=list(lam * rot),
                    seconds=time.perf_counter() - t0, converged=True,
                    stats={"unknowns": system.n_dofs, "newton_iterations": 0, "step_cuts": 0,
                           "substeps": 0},
                    settings={}, scene=scene, load_unit=case.unit)


def run_reduced(mechanism: Mechanism, spec: ModelSpec, case: LoadCase, levels: int | None = None,
                scene: str = "", record_poses: bool = False, record_shapes: bool = False,
                record_reactions: bool = False, **options) -> LoadPath:
    """Build the model ``spec`` and trace ``case`` (wall time includes the build).

    Raises
    ------
    core.SolverError
        If the path cannot be followed to full load.
    """
    t0 = time.perf_counter()
    system = build_system(mechanism, spec, **options)
    if spec.family == "ee":
        lp = solve_linear(system, case, levels, model=spec.id, scene=scene)
    else:
        lp = solve_path(system, case, levels, model=spec.id, settings=dict(options), scene=scene,
                        record_poses=record_poses, record_shapes=record_shapes,
                        record_reactions=record_reactions)
    lp.seconds = time.perf_counter() - t0
    return lp
