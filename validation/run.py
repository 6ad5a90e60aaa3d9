"""Run any requested model on a scene: the one dispatcher behind ``flexval run``.

Reduced models come from :mod:`reducedmodels`, the continuum reference from
:mod:`validation.continuum`; both return a :class:`reducedmodels.LoadPath`.
Only what is requested is built.
"""

from __future__ import annotations

from geometry import LoadCase, ModelSpec, Scene
from reducedmodels import LoadPath, run_reduced


def run_model(scene: Scene, spec: ModelSpec, case: LoadCase, levels: int | None = None,
              record_poses: bool = False, record_shapes: bool = False, **options) -> LoadPath:
    """Trace ``case`` of ``scene`` with model ``spec``.

    Parameters
    ----------
    levels : int, optional
        Number of equally spaced load levels (default: the load case's).
    record_poses, record_shapes : bool
        Also record every body's pose / the deformed flexures at each level.

    Raises
    ------
    reducedmodels.SolverError
        If the solver cannot reach the full load (carries the load reached).
    """
    if spec.family == "continuum":
        from .continuum import run_continuum

        return run_continuum(scene.mechanism, case, level=spec.resolution, levels=levels,
                             scene=scene.name, record_shapes=record_shapes, **options)
    return run_reduced(scene.mechanism, spec, case, levels, scene=scene.name,
                       record_poses=record_poses, record_shapes=record_shapes, **options)
