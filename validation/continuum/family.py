"""The continuum reference as a model family of the catalogue (``continuum[:LEVEL][[options]]``).

Declared in the catalogue by name
(:data:`flexval.reducedmodels.catalogue.BUILT_IN_FAMILIES`), imported the
first time the catalogue is asked for a family; the solver code (:mod:`.run`,
:mod:`.connector`, scikit-fem) is imported only when a continuum model runs.
"""

from __future__ import annotations

from flexval.geometry import LoadCase, Mechanism, SceneError
from flexval.geometry.errors import COMMAND_LINE
from flexval.geometry.mesh import MAX_LEVEL
from flexval.reducedmodels import LoadPath
from flexval.reducedmodels.catalogue import (
    ARCLENGTH,
    DISPLACEMENT,
    FIELDS,
    REFERENCE,
    Family,
    ModelSpec,
    Option,
    Resolution,
    register,
)

from .cost import path_cost
from .level import DEFAULT_LEVEL
from .material import LAWS, PLANES


def run(
    mechanism: Mechanism,
    spec: ModelSpec,
    case: LoadCase,
    levels: int | None = None,
    scene: str = "",
    record_poses: bool = False,
    record_shapes: bool = False,
    record_reactions: bool = False,
    **extra,
) -> LoadPath:
    """Trace ``case`` with the continuum model ``spec`` (see :func:`.run.run_continuum`).

    ``record_reactions`` is accepted for a uniform runner signature and not
    recorded; ``extra`` are ``vtu_dir`` and ``png``
    (:data:`~flexval.reducedmodels.catalogue.FIELDS`) or options overriding the
    spec's. The result carries the spec's canonical id.
    """
    from .run import run_continuum

    if spec.kwargs.get("three_d") and extra.get("png"):
        raise SceneError(COMMAND_LINE, "model", spec.id, "the 3D continuum draws no PNG")
    return run_continuum(
        mechanism,
        case,
        level=spec.resolution,
        levels=levels,
        scene=scene,
        record_poses=record_poses,
        record_shapes=record_shapes,
        model=spec.id,
        **{**spec.kwargs, **extra},
    )


def system(mechanism: Mechanism, spec: ModelSpec, settings=None, **options):
    """The multibody System of ``mechanism`` with every flexure meshed as ``spec`` says
    (for arc-length traces; see :func:`.run.build_system`)."""
    from .run import build_system

    return build_system(mechanism, spec.resolution, settings=settings, **{**spec.kwargs, **options})


CONTINUUM = register(
    Family(
        "continuum",
        "flexures meshed as 2D solids (Gmsh, quadratic quadrilaterals), geometrically "
        "nonlinear hyperelastic, scikit-fem; the end faces follow the rigid bodies exactly",
        run,
        Resolution(
            "LEVEL",
            "mesh level: 0 is the coarsest, each level halves the element size",
            DEFAULT_LEVEL,
            0,
            MAX_LEVEL,
            False,
            (0, 3),
        ),
        (
            Option.choice(
                "law",
                "hyperelastic law: Saint Venant-Kirchhoff or compressible neo-Hookean",
                LAWS,
                "svk",
            ),
            Option.choice(
                "plane",
                "plane stress (free out-of-plane faces) or plane strain (no "
                "out-of-plane strain); a wide flexure (depth b >> thickness h) lies between",
                PLANES,
                "stress",
            ),
            Option.flag(
                "3d",
                "the flexures as 3D solids (27-node Lagrange hexahedra through half the "
                "depth b, mid-plane symmetry, free faces z = +-b/2): no plane assumption",
                keyword="three_d",
            ),
        ),
        frozenset({FIELDS, REFERENCE, ARCLENGTH, DISPLACEMENT}),
        system,
        path_cost,
        exclusive=(("3d", "plane"),),
    )
)
