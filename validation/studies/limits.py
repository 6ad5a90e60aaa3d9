"""Limit loads: arc-length traces of any model and the limit points they pass.

Load control stops at a limit point (the largest load on the path); arc-length
continuation (:func:`flexval.reducedmodels.core.continuation.solve_arclength`) passes it.
:func:`trace_arclength` traces a load case of a scene with any model whose
family can be assembled as a :class:`reducedmodels.System` (catalogue
capability :data:`~flexval.reducedmodels.catalogue.ARCLENGTH`: every nonlinear reduced
model and the continuum), and :func:`limit_points` lists where the load turns.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.geometry.errors import COMMAND_LINE
from flexval.reducedmodels import LoadPath, ModelSpec, SolverError, SolverSettings
from flexval.reducedmodels.catalogue import ARCLENGTH, families
from flexval.reducedmodels.core.continuation import limit_loads, solve_arclength

ARCLENGTH_SETTINGS = SolverSettings(max_translation_step=0.01, max_rotation_step=0.05)
"""Step bounds of arc-length traces (1 % of the mechanism size, 0.05 rad per step): fine
enough that the parabola through a limit point's neighbours gives its load to ~1e-5."""

DEFAULT_STEPS = 20
"""The tangent at rest would reach the end of the trace in this many steps (initial arc length)."""


def trace_arclength(
    scene: Scene,
    spec: ModelSpec,
    case: LoadCase,
    max_load_factor: float = 1.0,
    n_steps: int = DEFAULT_STEPS,
    record_poses: bool = False,
    record_shapes: bool = False,
    branch_switch: bool = False,
) -> LoadPath:
    """Trace ``case`` with ``spec`` by arc-length continuation up to ``max_load_factor``.

    Parameters
    ----------
    scene : Scene
    spec : ModelSpec
        A model whose family has the ARCLENGTH capability.
    case : LoadCase
        Load factor 1 is its full value.
    max_load_factor : float
        Where the trace ends (> 0): the first time the load factor reaches it.
    n_steps : int
        Sets the initial arc length (see ``solve_arclength``).
    record_poses : bool
        Also record every body's pose at each point.
    record_shapes : bool
        Also record every flexure's shape and section forces at each point.
    branch_switch : bool
        At the first bifurcation point, follow the crossing branch (see
        :class:`flexval.reducedmodels.core.continuation.ArcLength`).

    Returns
    -------
    LoadPath
        Model ``<id>:arclength``; every converged point in the order traced
        (the load may rise and fall), ``limit_points`` (see :func:`limit_points`)
        and ``bifurcations``.

    Raises
    ------
    SceneError
        If the model cannot be traced by arc length.
    reducedmodels.SolverError
        If the trace fails; its partial path carries the limit points passed.
    """
    check_arclength(spec)
    family = spec.model_family
    system = family.system(family.loaded(scene.mechanism, case), spec, ARCLENGTH_SETTINGS)
    try:
        lp = solve_arclength(
            system,
            case,
            max_load_factor,
            n_steps,
            model=spec.id,
            scene=scene.name,
            max_steps=100 * n_steps,
            record_poses=record_poses,
            record_shapes=record_shapes,
            branch_switch=branch_switch,
        )
    except SolverError as exc:
        if exc.path is not None:
            exc.path.limit_points = limit_points(exc.path)
        raise
    lp.limit_points = limit_points(lp)
    return lp


def check_arclength(spec: ModelSpec) -> None:
    """Raise SceneError (naming ``--arclength`` and the model) unless ``spec`` can be traced."""
    if not spec.model_family.has(ARCLENGTH):
        able = [f.name for f in families() if f.has(ARCLENGTH)]
        raise SceneError(
            COMMAND_LINE,
            "--arclength",
            spec.id,
            f"arc-length continuation needs a model assembled as a nonlinear "
            f"system; families that have it: {able}",
        )


def limit_points(path: LoadPath) -> list[dict]:
    """The limit points of an arc-length path: where the load turns.

    Each is ``{"index", "load", "traced_load", "dx", "dy", "rotation"}``:
    the index of the traced point nearest to it, the load refined by the
    parabola through it and its neighbours
    (:func:`flexval.reducedmodels.core.continuation.limit_loads`,
    N or N mm), the largest (or smallest) traced load, and the target's
    displacement (mm) and rotation (rad) at that traced point.
    """
    indices = path.stats.get("limit_points", [])
    return [
        {
            "index": k,
            "load": load,
            "traced_load": path.load[k],
            "dx": path.dx[k],
            "dy": path.dy[k],
            "rotation": path.rotation[k],
        }
        for k, load in zip(indices, limit_loads(path))
    ]
