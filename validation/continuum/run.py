"""Run the continuum reference on a mechanism: one ContinuumConnector per flexure.

The rigid bodies and all meshed flexures are solved together by the
multibody core (the path tracer :func:`reducedmodels.trace` with load
control, Newton with the exact tangent and adaptive load stepping), so open
and closed chains need no special code and the result is the same
:class:`reducedmodels.LoadPath` as for the reduced models (model id
``continuum:LEVEL``). The VTU and PNG outputs come from the last state the
tracer yields (full load).

Convergence: the residual of a meshed flexure cannot fall below the
round-off of its nodal positions (stiffness x |u| x 1e-16, e.g. 2e-7 of the
tiny open-chain loads), so the core's relative force criterion (1e-10) is
not met and Newton stops on its step criterion (scaled correction below
1e-10, reached quadratically; the correction's own floor is ~1e-14).
"""

from __future__ import annotations

import time
from pathlib import Path

from flexval.geometry import LoadCase, Mechanism
from flexval.geometry.mesh import ASPECT_RATIO, ELEMENT_ORDER, MESH_VERSION
from flexval.reducedmodels import LoadControl, LoadPath, PathRecorder, SolverSettings, System, trace
from flexval.reducedmodels.core.inertia import with_weights
from flexval.reducedmodels.core.threads import limit_threads
from flexval.reducedmodels.core.validity import merge_reasons, strain_reasons

from .connector import ContinuumConnector
from .level import DEFAULT_LEVEL


def build_system(
    mechanism: Mechanism,
    level: int,
    law: str = "svk",
    plane: str = "stress",
    settings: SolverSettings | None = None,
    three_d: bool = False,
) -> System:
    """The multibody System with every flexure meshed at ``level`` (pins and a drive as exact
    constraints).

    ``three_d``: the flexures as 3D solids of half their depth
    (:class:`.connector3d.Continuum3DConnector`; ``plane`` is not used).
    """
    from flexval.reducedmodels.core.drives import constraint_connectors

    if three_d:
        from .connector3d import Continuum3DConnector

        conns = [Continuum3DConnector(f, mechanism, level, law=law) for f in mechanism.flexures]
    else:
        conns = [
            ContinuumConnector(f, mechanism, level, law=law, plane=plane)
            for f in mechanism.flexures
        ]
    conns += constraint_connectors(mechanism)
    return System(mechanism, with_weights(mechanism, conns), settings or SolverSettings())


def run_continuum(
    mechanism: Mechanism,
    case: LoadCase,
    level: int | None = None,
    levels: int | None = None,
    scene: str = "",
    record_shapes: bool = False,
    law: str = "svk",
    plane: str = "stress",
    vtu_dir: str | Path | None = None,
    png: str | Path | None = None,
    model: str | None = None,
    three_d: bool = False,
    record_poses: bool = False,
) -> LoadPath:
    """Trace ``case`` with the continuum model (wall time includes meshing and set-up).

    Parameters
    ----------
    mechanism : Mechanism
    case : LoadCase
    level : int, optional
        Mesh level (default :data:`DEFAULT_LEVEL`).
    levels : int, optional
        Number of load levels (default: the load case's).
    scene : str
        Scene name recorded in the result.
    record_shapes : bool
        Record the deformed centre lines (and section forces) at every level.
    record_poses : bool
        Record every body's pose at every level.
    law : {'svk', 'neo-hookean'}
        Hyperelastic law (Saint Venant-Kirchhoff by default).
    plane : {'stress', 'strain'}
        Plane stress (default) or plane strain.
    vtu_dir : path, optional
        Write the deformed flexures at full load as VTU (displacement,
        Green-Lagrange strain, von Mises and fibre Cauchy stress) into this folder.
    png : path, optional
        Draw the deformed mechanism at full load, its flexures coloured by the
        fibre stress (:func:`.output.render_png`), into this file (with or
        without ``vtu_dir``).
    model : str, optional
        Model id of the result and of the VTU file's name (default
        ``continuum:LEVEL``; the catalogue passes the canonical id with its
        options, so variants of one level do not overwrite each other's file).
    three_d : bool
        The flexures as 3D solids (:mod:`.connector3d`) instead of plane ones;
        the VTU holds their hexahedra and displacements (:mod:`.output3d`);
        no PNG, no fibre stress of the continuum's own (the section
        resultants and their peak stress are recorded).

    Raises
    ------
    reducedmodels.SolverError
        If the path cannot be followed to full load.
    ValueError
        If ``three_d`` is asked together with ``png``.
    """
    if three_d and png is not None:
        raise ValueError("the 3D continuum draws no PNG picture")
    limit_threads()  # a per-process cost (threadpoolctl's library scan), not the model's
    t0 = time.perf_counter()
    level = DEFAULT_LEVEL if level is None else int(level)
    system = build_system(mechanism, level, law, plane, three_d=three_d)
    model = model or f"continuum:{level}"
    settings = {
        "level": level,
        "law": law,
        "plane": plane,
        "element_order": ELEMENT_ORDER,
        "aspect_ratio": ASPECT_RATIO,
        "mesh_version": MESH_VERSION,
    }
    if three_d:
        from flexval.geometry.extrude import layers

        settings.update(plane="3d", layers=layers(level), element_order_3d=27)
    from .fibre import fibre_stresses, notch_peaks

    recorder = PathRecorder(
        system,
        case,
        model,
        scene,
        settings,
        record_poses=record_poses,
        record_shapes=record_shapes,
    )
    notches: dict[str, list] = {}
    spent = [0.0]  # s in notch_peaks: a recovery of the stress, not the model's solve

    def with_notch_peaks(points):
        """The traced points, each notch hinge's fibre peak at every level noted on the way
        (the true peak that sets a notch's first yield:
        :mod:`flexval.validation.studies.yieldpoint`)."""
        for point in points:
            start = time.perf_counter()
            for name, peak in notch_peaks(system, point.state).items():
                notches.setdefault(name, []).append(peak)
            spent[0] += time.perf_counter() - start
            yield point

    lp, full_load = recorder.run(
        with_notch_peaks(trace(system, system.loads(case), LoadControl(case.factors(levels))))
    )
    lp.seconds = time.perf_counter() - t0 - spent[0]
    lp.fibre_stress = fibre_stresses(system, full_load.state)
    for name, peaks in notches.items():
        lp.fibre_stress[name]["path_stress"] = [p[0] for p in peaks]
        lp.fibre_stress[name]["path_at"] = [p[1] for p in peaks]
    varying = {f.name for f in mechanism.flexures if not f.section.is_uniform}
    lp.valid, lp.validity = merge_reasons(
        lp.valid,
        lp.validity,
        strain_reasons(lp, mechanism.material.youngs_modulus, varying),
    )
    if vtu_dir is not None:
        from ..outputs import output_path
        from .output import write_vtu
        from .output3d import write_vtu_3d

        stem = f"{scene + '_' if scene else ''}{case.name}_{model.replace(':', '')}"
        (write_vtu_3d if three_d else write_vtu)(
            output_path(Path(vtu_dir), stem, ".vtu"),
            system.connectors,
            system.local_states(full_load.state),
        )
    if png is not None:
        from .output import render_png

        render_png(png, system, full_load.state, case, f"{scene} {case.name} {model}")
    return lp
