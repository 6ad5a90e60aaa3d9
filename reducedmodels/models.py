"""Build and run the reduced models of a :class:`flexval.reducedmodels.catalogue.ModelSpec`.

The family-independent pieces: a System with one connector per flexure (and
exact joints for the pins), load-control tracing of a nonlinear model and
the linear response of the EE. Which connector a family uses, and which of
these runners, is registered in :mod:`flexval.reducedmodels.families`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from flexval.geometry import Flexure, LoadCase, Mechanism, SceneError

from .catalogue import ModelSpec
from .core.connector import Connector
from .core.inertia import with_weights
from .core.linearbatch import rotation_verdicts
from .core.loadpath import LoadPath
from .core.loads import Loads
from .core.peaks import record_stress
from .core.recorder import append_section_forces, solve_path
from .core.redundancy import redundant_connectors
from .core.restnumbering import RestNumbering
from .core.sections import SectionForces
from .core.settings import SolverSettings
from .core.system import System, connector_groups
from .core.validity import linear_sway_verdicts, merge_reasons, strain_reasons
from .kernels.clock import path_clock
from .notchcorrection import NotchFactors, corrected_material, factors_of

#: ``make(flexure, mechanism, spec, **options) -> Connector`` of one flexure
ConnectorFactory = Callable[..., Any]


def flexure_connectors(
    mechanism: Mechanism, spec: ModelSpec, make: ConnectorFactory, options: dict
) -> list:
    """The connectors a System of ``mechanism`` joins: one ``make(...)`` per flexure, pins, weights.

    With the option ``plate`` (a true ``options["plate"]``) the flexures take the
    material's plane-strain constants (:meth:`~flexval.geometry.Material.plane_strain`).
    With ``width`` each flexure takes its own bending modulus E r, r the
    ratio of its depth's anticlastic curvature
    (:func:`flexval.geometry.anticlastic.flexure_ratio`), with the same shear
    modulus (:func:`~flexval.geometry.anticlastic.effective_material`): 1 on a
    straight uniform flexure, tending to ``plate``'s constants as the depth grows
    (the catalogue refuses an id giving both).
    A notch hinge takes its calibrated bending and shear compliance
    (:mod:`flexval.reducedmodels.notchcorrection`: the continuum's, where beam
    theory's ∫ ds/EI is 1-50 % stiff) unless ``eb`` (plain Euler-Bernoulli) is given.
    Pins (``mechanism.pins``) are added as exact Lagrange-multiplier joints
    (:class:`flexval.reducedmodels.core.joints.PinConnector`) whatever the model, and so is
    a prescribed motion (``mechanism.drive``, :mod:`flexval.reducedmodels.core.drives`). With
    ``[gravity]`` in the scene, the weights of the flexures and bodies are
    dead loads in the potential (:func:`flexval.reducedmodels.core.inertia.with_weights`).

    Raises
    ------
    SceneError
        If the model cannot represent a flexure (``make`` raises ValueError,
        e.g. a PRBM arc angle outside its fitted table); the field names the
        flexure.
    """
    options = dict(options)
    plate, width = options.pop("plate", False), options.pop("width", False)
    plain = options.pop("eb", False)
    flexible = mechanism  # the plate option: the flexures' constants of a wide section
    if plate:
        flexible = dataclasses.replace(mechanism, material=mechanism.material.plane_strain())
    conns = []
    for f in mechanism.flexures:
        try:
            own = _of_its_depth(mechanism, f) if width else flexible
            factors = None if plain else _notch_factors(mechanism, f)
            if factors is not None:
                own = dataclasses.replace(own, material=corrected_material(own.material, factors))
            conns.append(make(f, own, spec, **options))
            if factors is not None:
                conns[-1].surface_stress = factors.surface_stress
        except ValueError as exc:  # the model cannot represent this flexure
            raise SceneError(mechanism.source, f"flexures.{f.name}", spec.id, str(exc)) from None
    if mechanism.pins or mechanism.drive is not None:
        from .core.drives import constraint_connectors

        conns += constraint_connectors(mechanism)
    redundant = redundant_connectors(mechanism, conns)
    if redundant:
        raise SceneError(
            mechanism.source,
            f"flexures.{redundant[0]}",
            spec.id,
            f"{spec.family} holds {', '.join(map(repr, redundant))} rigid along directions "
            "that lock one motion more than once (straight leaves of the PRBM are "
            "inextensible: a guide of more than two parallel leaves, or leaves on one line): "
            "how they share a load along it is statically indeterminate in this model, so "
            "its forces, stresses and solves are undefined; model them with beam:N or "
            "dcmm:N, which carry the leaves' axial stiffness",
        )
    return with_weights(mechanism, conns)


def _notch_factors(mechanism: Mechanism, flexure: Flexure) -> NotchFactors | None:
    """The calibrated factors of ``flexure`` if it is a notch hinge
    (:func:`flexval.reducedmodels.notchcorrection.factors_of`), else None."""
    if flexure.section.profile is None or flexure.section.profile.kind != "notch":
        return None
    return factors_of(flexure, mechanism.material.poisson_ratio)


def _of_its_depth(mechanism: Mechanism, flexure: Flexure) -> Mechanism:
    """``mechanism`` with the material of ``flexure``'s own depth (the option ``width``).

    The connectors read the material from the mechanism they are given, so
    each flexure gets a copy carrying its own; a flexure whose ratio is 1 (a
    tapered straight one) gets the mechanism itself.
    """
    from flexval.geometry.anticlastic import effective_material, flexure_ratio

    material = mechanism.material
    own = effective_material(material, flexure_ratio(flexure, material.poisson_ratio))
    return mechanism if own is material else dataclasses.replace(mechanism, material=own)


def connector_system(
    mechanism: Mechanism,
    spec: ModelSpec,
    make: ConnectorFactory,
    settings: SolverSettings | None,
    options: dict,
) -> System:
    """The System of ``mechanism`` joining its :func:`flexure_connectors` (``make`` per flexure).

    Raises
    ------
    SceneError
        If the model cannot represent a flexure.
    """
    return System(
        mechanism, flexure_connectors(mechanism, spec, make, options), settings or SolverSettings()
    )


def build_system(
    mechanism: Mechanism, spec: ModelSpec, settings: SolverSettings | None = None, **options
) -> System:
    """The multibody System of ``mechanism`` with every flexure modelled as ``spec``.

    ``options`` are Python keyword arguments of the connector that override
    the spec's own options (e.g. ``shear=True`` for beams, ``frame="follower"``
    for DCMM).

    Raises
    ------
    ValueError
        If ``spec``'s family builds no System (e.g. it is not a reduced model).
    SceneError
        If the model cannot represent a flexure.
    """
    fam = spec.model_family
    if fam.system is None:
        raise ValueError(f"'{spec.id}' builds no multibody System")
    return fam.system(mechanism, spec, settings, **{**spec.kwargs, **options})


def trace_nonlinear(
    mechanism: Mechanism,
    spec: ModelSpec,
    case: LoadCase,
    levels: int | None = None,
    scene: str = "",
    record_poses: bool = False,
    record_shapes: bool = False,
    record_reactions: bool = False,
    **options,
) -> LoadPath:
    """Build the model ``spec`` and trace ``case`` by load control (wall time includes the build).

    Raises
    ------
    core.SolverError
        If the path cannot be followed to full load.
    """
    t0 = path_clock()
    options = {**spec.kwargs, **options}
    system = build_system(mechanism, spec, **options)
    lp = solve_path(
        system,
        case,
        levels,
        model=spec.id,
        settings=options,
        scene=scene,
        record_poses=record_poses,
        record_shapes=record_shapes,
        record_reactions=record_reactions,
    )
    lp.seconds = path_clock() - t0
    return lp


def trace_linear(
    mechanism: Mechanism,
    spec: ModelSpec,
    case: LoadCase,
    levels: int | None = None,
    scene: str = "",
    record_poses: bool = False,
    record_shapes: bool = False,
    record_reactions: bool = False,
    **options,
) -> LoadPath:
    """Build the model ``spec`` and return its linear response (wall time includes the build).

    ``record_poses`` and ``record_shapes`` record the linearised poses and
    shapes q0 + lambda dq (see :func:`linear_response`); ``record_reactions``
    is accepted for a uniform runner signature and ignored.
    """
    t0 = path_clock()
    system = build_system(mechanism, spec, **options)
    lp = solve_linear(
        system,
        case,
        levels,
        model=spec.id,
        scene=scene,
        record_poses=record_poses,
        record_shapes=record_shapes,
    )
    lp.seconds = path_clock() - t0
    return lp


def solve_linear(
    system: System,
    case: LoadCase,
    levels: int | None = None,
    model: str = "ee",
    scene: str = "",
    record_poses: bool = False,
    record_shapes: bool = False,
) -> LoadPath:
    """:func:`linear_response` of a System's connectors."""
    return linear_response(
        system.mechanism,
        system.connectors,
        case,
        levels,
        model,
        scene,
        record_poses=record_poses,
        record_shapes=record_shapes,
    )


def linear_response(
    mechanism: Mechanism,
    connectors: Sequence[Connector],
    case: LoadCase,
    levels: int | None = None,
    model: str = "ee",
    scene: str = "",
    record_poses: bool = False,
    record_shapes: bool = False,
) -> LoadPath:
    """Linear response at the undeformed configuration (the EE prediction).

    Solves K0 dq = w + lambda f with the elastic tangent K0 at rest (no load
    stiffness, no large-rotation terms), w the weights of a scene with
    gravity (applied before the load case, as in every static run) and f the
    load case at full value, and reports the linearised target displacement
    J dq; without gravity it is proportional to the load. The validity monitor
    judges it by its body rotations alone
    (:data:`~flexval.reducedmodels.core.validity.MAX_LINEAR_ROTATION`): q0 + lambda dq is
    a linear response, not a configuration, so the connectors' own stretch
    limits do not apply to it (its linearised rigid rotations stretch chords
    by theta^2 / 2, which is exactly what that rotation limit bounds).

    One evaluation of each connector at rest and one factorisation: the
    connectors are numbered as a :class:`~flexval.reducedmodels.core.system.System` numbers
    them (the moving bodies' poses, then each connector's internal
    coordinates in turn) and assembled the same way, but without the index
    maps, groups and solver state a System builds for many Newton
    assemblies (on the paper's scenes they cost more than the response).

    ``record_poses`` and ``record_shapes`` record every body's pose and every
    connector's shape (with its section forces) at the linearised coordinates
    q0 + w + lambda dq of each level: the picture of the linear answer, not a
    configuration of the mechanism.
    """
    t0 = path_clock()
    ground = mechanism.ground
    bodies = mechanism.moving_bodies
    first = {b: 3 * k for k, b in enumerate(bodies)}

    def pose_dofs(body: str) -> np.ndarray:
        return np.full(3, -1) if body == ground else np.arange(first[body], first[body] + 3)

    reference = {b: mechanism.bodies[b].reference for b in mechanism.bodies}
    poses = {b: [*reference[b].tolist(), 0.0] for b in mechanism.bodies}  # at rest
    # each connector's local coordinates at rest, their global dofs (-1: the ground's) and
    # their places in q extended by the ground's pose, all connectors' end to end
    rest = [
        (np.array(poses[c.bodies[0]]), np.array(poses[c.bodies[1]]), c.initial_internal())
        for c in connectors
    ]
    numbering = RestNumbering.of(mechanism, connectors)
    n, dofs, gather, places, bounds = (
        numbering.n,
        numbering.dofs,
        numbering.gather,
        numbering.places,
        numbering.bounds,
    )
    start = bounds[-1] if bounds else 0
    # energy gradient and Hessian at rest, scattered as System.assemble does
    terms = [c.evaluate(*r) for c, r in zip(connectors, rest)]
    local_rows, local_cols = numbering.local_rows, numbering.local_cols
    keep, layout = numbering.keep, numbering.layout
    hessians = np.concatenate([np.ravel(h) for _, _, h in terms])
    K0 = layout.tangent(
        np.bincount(
            layout.slots[: layout.slots.size - n], weights=hessians[keep], minlength=layout.size
        )
    )
    moving = dofs >= 0
    g_zero = np.bincount(
        dofs[moving], weights=np.concatenate([g for _, g, _ in terms])[moving], minlength=n
    )
    at_rest = np.concatenate([r for state in rest for r in state])  # the local coordinates
    q0 = np.zeros(n)
    q0[: 3 * len(bodies)] = [x for b in bodies for x in poses[b]]
    q0[dofs[moving]] = at_rest[moving]  # and the internal coordinates
    drive = _drive_of(connectors, dofs, places, bounds)
    loads = Loads.of_case(
        case, pose_dofs, reference, mechanism.size(), None if drive is None else drive[1:]
    )
    g_unit = g_zero.copy()  # g = grad E(q0) - f = -f at rest
    loads.add_to(q0, 1.0, g_unit, np.zeros_like(g_unit))
    dq = K0.solve(g_zero - g_unit)  # per unit load factor
    # the weights, g = -w at rest and no load (without gravity g_zero is only round-off)
    has_weights = mechanism.inertia.gravity is not None
    dq_dead = K0.solve(-g_zero) if has_weights else np.zeros_like(dq)
    # the target point's linearised motion at rest: (dx - rel_y dtheta, dy + rel_x dtheta)
    tdofs = pose_dofs(mechanism.target_body).tolist()
    rel_x, rel_y = (mechanism.target_point - reference[mechanism.target_body]).tolist()
    (ux, uy, rot), (wx, wy, dead_rot) = (
        [v[tdofs[0]], v[tdofs[1]], v[tdofs[2]]] if tdofs[0] >= 0 else [0.0] * 3
        for v in (dq.tolist(), dq_dead.tolist())
    )
    lam = case.factors(levels)
    lp = LoadPath(
        model=model,
        load_case=case.name,
        load=(lam * case.magnitude).tolist(),
        dx=(wx - rel_y * dead_rot + lam * (ux - rel_y * rot)).tolist(),
        dy=(wy + rel_x * dead_rot + lam * (uy + rel_x * rot)).tolist(),
        rotation=(dead_rot + lam * rot).tolist(),
        seconds=0.0,
        converged=True,
        stats={"unknowns": n, "newton_iterations": 0, "step_cuts": 0, "substeps": 0},
        settings={},
        scene=scene,
        load_unit=case.unit,
    )
    # every level's largest body rotation at once, (levels,) rad
    turns = np.abs(dq_dead[2 : 3 * len(bodies) : 3] + lam[:, None] * dq[2 : 3 * len(bodies) : 3])
    if bodies:
        lp.valid, lp.validity = rotation_verdicts(turns, bodies)
    else:
        lp.valid, lp.validity = [True] * len(lam), [None] * len(lam)
    # section forces of the linear response: K0 dq on the undeformed centre lines
    groups = connector_groups(connectors)
    ground_pose = poses[ground]

    def section_gradients(dq_: np.ndarray) -> list[np.ndarray]:
        moved = np.concatenate([q0 + dq_, ground_pose])[gather] - at_rest
        products = np.bincount(local_rows, weights=hessians * moved[local_cols], minlength=start)
        return [products[a:b] for a, b in zip(places, bounds)]  # each connector's

    def section_forces(gradients: list[np.ndarray]) -> list:
        return [
            forces
            for group, run in groups
            for forces in group.section_forces(rest[run], gradients[run])
        ]

    per_unit = section_gradients(dq)
    sections = {f.name: f.section for f in mechanism.flexures}
    unit = section_forces(per_unit)  # the section forces per unit load factor
    dead = section_forces(section_gradients(dq_dead)) if has_weights else None  # the weights'
    if any(c.sway_load is not None for c in connectors):  # straight leaves it cannot buckle
        lp.valid, lp.validity = merge_reasons(
            lp.valid, lp.validity, linear_sway_verdicts(connectors, unit, lam, dead)
        )
    if has_weights:
        of_weights = section_gradients(dq_dead)
        for factor in lam:
            record_stress(
                lp,
                connectors,
                section_forces([w + factor * g for w, g in zip(of_weights, per_unit)]),
                sections,
            )
    else:  # section forces proportional to the load
        record_stress(lp, connectors, unit, sections, lam)
    lp.valid, lp.validity = merge_reasons(
        lp.valid, lp.validity, strain_reasons(lp, mechanism.material.youngs_modulus)
    )
    if record_poses or record_shapes:
        states = [q0 + dq_dead + factor * dq for factor in lam.tolist()]
        ground_q = np.asarray(ground_pose, float)
        if record_poses:
            lp.poses = {
                b: [
                    (q[first[b] : first[b] + 3] if b != ground else ground_q).tolist()
                    for q in states
                ]
                for b in mechanism.bodies
            }
        if record_shapes:
            lp.shapes = {c.name: [] for c in connectors}
            for q in states:
                local = np.concatenate([q, ground_q])[gather]
                for c, a, b in zip(connectors, places, bounds):
                    own = local[a:b]
                    lp.shapes[c.name].append(c.shape(own[:3], own[3:6], own[6:]).tolist())
            stacked = [
                None if f is None else _at_every_level(f, w, lam)
                for f, w in zip(unit, dead or [None] * len(unit))
            ]
            append_section_forces(lp, zip(connectors, stacked))
    if drive is not None:  # the drive's force and moment, linear in its multipliers
        connector, multipliers = drive[0], drive[1]
        lp.drive_reactions = [
            connector.reaction(
                q0[multipliers] + dq_dead[multipliers] + f * dq[multipliers]
            ).tolist()
            for f in lam.tolist()
        ]
    lp.seconds = path_clock() - t0
    return lp


def _at_every_level(
    unit: SectionForces, weights: SectionForces | None, factors: np.ndarray
) -> SectionForces:
    """The section forces of a linear response at each load factor, (levels, stations):
    ``factors`` times those per unit load, plus the weights' where there are any."""
    axial = factors[:, None] * np.asarray(unit.axial)[None]
    moment = factors[:, None] * np.asarray(unit.moment)[None]
    if weights is not None:
        axial, moment = np.asarray(weights.axial) + axial, np.asarray(weights.moment) + moment
    return SectionForces(unit.at, axial, moment)


def _drive_of(
    connectors: Sequence[Connector], dofs: np.ndarray, places: Sequence[int], bounds: Sequence[int]
) -> tuple | None:
    """(connector, its multipliers' global dofs, their loads in N) of the drive among
    ``connectors`` (numbered end to end: connector k's local coordinates are
    ``dofs[places[k]:bounds[k]]``), or None."""
    from .core.drives import DriveConnector

    for c, a, b in zip(connectors, places, bounds):
        if isinstance(c, DriveConnector):
            return c, dofs[a + 6 : b], c.multiplier_loads()
    return None


def run_reduced(
    mechanism: Mechanism,
    spec: ModelSpec,
    case: LoadCase,
    levels: int | None = None,
    scene: str = "",
    record_poses: bool = False,
    record_shapes: bool = False,
    record_reactions: bool = False,
    **options,
) -> LoadPath:
    """Trace ``case`` with the model ``spec`` (its family's runner; wall time includes the build).

    ``options`` override the spec's options (Python keyword arguments of the
    connector).

    Raises
    ------
    core.SolverError
        If the path cannot be followed to full load.
    """
    return spec.model_family.trace(
        mechanism,
        spec,
        case,
        levels=levels,
        scene=scene,
        record_poses=record_poses,
        record_shapes=record_shapes,
        record_reactions=record_reactions,
        **options,
    )
