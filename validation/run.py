"""Run any requested model on a scene: the one dispatcher behind ``flexval run``.

The model's family in the catalogue (:mod:`flexval.reducedmodels.catalogue`) runs it:
reduced models from :mod:`reducedmodels`, the continuum reference from
:mod:`flexval.validation.continuum`; every one returns a :class:`reducedmodels.LoadPath`.
Only what is requested is built.
"""

from __future__ import annotations

from flexval.geometry import LoadCase, Scene
from flexval.reducedmodels import LoadPath, ModelSpec, PluginFailure, SolverError
from flexval.reducedmodels.catalogue import plugin_of


def run_model(
    scene: Scene,
    spec: ModelSpec | str,
    case: LoadCase | str,
    levels: int | None = None,
    record_poses: bool = False,
    record_shapes: bool = False,
    **extra,
) -> LoadPath:
    """Trace ``case`` of ``scene`` with model ``spec``.

    Parameters
    ----------
    scene : Scene
    spec : ModelSpec or str
        The model, or its id (``"beam:100"``, ``"continuum:1[3d]"``).
    case : LoadCase or str
        The load case, or its name in the scene.
    levels : int, optional
        Number of equally spaced load levels (default: the load case's).
    record_poses, record_shapes : bool
        Also record every body's pose / the deformed flexures at each level
        (where the model has them).
    extra
        Output keywords of the family's capabilities (``vtu_dir``, ``png``)
        or Python options overriding the spec's.

    Raises
    ------
    reducedmodels.SolverError
        If the solver cannot reach the full load (carries the load reached); its
        :class:`~flexval.reducedmodels.core.settings.PluginFailure` for a plug-in family's code
        that raises anything else (naming its package): never a traceback.
    SceneError
        For an unknown model id or load-case name (naming it).
    """
    if isinstance(spec, str):
        from flexval.reducedmodels.catalogue import parse_model

        spec = parse_model(spec)
    if isinstance(case, str):
        case = scene.load_case(case)

    def run() -> LoadPath:
        return spec.model_family.trace(
            scene.mechanism,
            spec,
            case,
            levels=levels,
            scene=scene.name,
            record_poses=record_poses,
            record_shapes=record_shapes,
            **extra,
        )

    package = plugin_of(spec.family)
    if package is None:
        return run()
    try:
        return run()
    except SolverError:
        raise
    except Exception as exc:
        raise PluginFailure(
            f"{spec.id} on load case {case.name!r}: the model family of plug-in package "
            f"{package!r} raised {type(exc).__name__}: {exc}",
            0.0,
        ) from None
