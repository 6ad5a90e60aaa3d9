"""The linear response of many copies of one mechanism topology at once: ``ee`` in a batch.

:func:`flexval.reducedmodels.models.linear_response` solves K0 dq = w + lambda f
at rest for one mechanism: one evaluation of each connector, one assembly,
one factorisation, the target's linearised motion, the validity monitor's
rotation test and the section forces of K0 dq. For N copies of one topology
(other dimensions, sections, loads) the numbering is the same, so
:func:`linear_responses` takes every step for all copies at once where the
arithmetic allows it: the assembly of every copy's K0 and of its rest
gradient is one ``bincount`` (each copy's slots offset, each slot summed in
the order a copy alone sums it), the outputs, the rotation test and the
section gradients K0 dq are array operations over the copies, the section
forces take one call per connector class for all copies and the stresses
one pass (:func:`flexval.reducedmodels.core.peaks.state_peaks`). Each copy's
K0 is factorised and solved by its own tangent (the LAPACK calls of a copy
alone), and its loads added by its own :class:`~flexval.reducedmodels.core.loads.Loads`:
every copy's path is the one it gets alone, bit for bit
(``tests/test_batch.py``).

Copies given the same mechanism and connectors (a batch of identical
copies) share their evaluation at rest, as :func:`flexval.reducedmodels.core.batch.run_batch`
shares their connectors.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flexval.geometry import LoadCase, Mechanism

from ..kernels.clock import path_clock
from .connector import Connector
from .loadpath import LoadPath
from .loads import Loads
from .peaks import append_stresses, state_peaks
from .restnumbering import RestNumbering
from .validity import MAX_LINEAR_ROTATION, linear_sway_verdicts, merge_reasons, strain_reasons

Member = tuple[Mechanism, Sequence[Connector]]
"""One copy: its mechanism and its connectors (``Family.connectors``)."""


@dataclass(frozen=True)
class _Rest:
    """One copy's connectors evaluated at rest, and its coordinates there.

    Attributes
    ----------
    states : list of (pose_a, pose_b, internal)
        Each connector's local state at rest (mm, rad).
    hessians : array (h,)
        Every connector's Hessian values, end to end.
    gradients : array (d,)
        Every connector's gradient over its local coordinates, end to end.
    local : array (d,)
        The local coordinates at rest, end to end.
    q0 : array (n,)
        The unknowns at rest.
    reference : dict of body -> array (2,)
        The bodies' reference points (mm).
    """

    states: list
    hessians: np.ndarray
    gradients: np.ndarray
    local: np.ndarray
    q0: np.ndarray
    reference: dict

    @classmethod
    def of(cls, mechanism: Mechanism, connectors: Sequence[Connector], numbering: RestNumbering):
        """Evaluate ``connectors`` at the rest state of ``mechanism`` (its own poses)."""
        reference = {b: mechanism.bodies[b].reference for b in mechanism.bodies}
        poses = {b: [*reference[b].tolist(), 0.0] for b in mechanism.bodies}  # at rest
        states = [
            (np.array(poses[c.bodies[0]]), np.array(poses[c.bodies[1]]), c.initial_internal())
            for c in connectors
        ]
        terms = [c.evaluate(*state) for c, state in zip(connectors, states)]
        local = np.concatenate([r for state in states for r in state])
        moving = numbering.dofs >= 0
        q0 = np.zeros(numbering.n)
        q0[: 3 * len(numbering.bodies)] = [x for b in numbering.bodies for x in poses[b]]
        q0[numbering.dofs[moving]] = local[moving]  # and the internal coordinates
        return cls(
            states,
            np.concatenate([np.ravel(h) for _, _, h in terms]),
            np.concatenate([g for _, g, _ in terms]),
            local,
            q0,
            reference,
        )


def linear_responses(
    members: Sequence[Member],
    cases: Sequence[LoadCase],
    levels: int | None = None,
    model: str = "ee",
    scene: str = "",
) -> list[LoadPath | Exception]:
    """Every copy's linear response at rest (the EE prediction), as each gets it alone.

    The path :func:`flexval.reducedmodels.models.linear_response` gives for
    each copy's mechanism, connectors and load case, for all copies at once
    (see the module text). Each path's ``seconds`` is its share of the
    whole call's wall time.

    Parameters
    ----------
    members : sequence of (Mechanism, connectors)
        The copies, all of copy 0's topology: the same moving bodies and
        ground, the same kinds of connectors joining the same bodies, with
        the same internal coordinates and Hessian patterns.
    cases : sequence of LoadCase
        Each copy's load case; all request the same load factors.
    levels, model, scene :
        As for :func:`~flexval.reducedmodels.models.linear_response`.

    Returns
    -------
    list of LoadPath or Exception
        Per copy: its path, or what its solve raised (a singular K0:
        ``numpy.linalg.LinAlgError``; a connector that refused its rest
        state: ``ValueError``).

    Raises
    ------
    ValueError
        If the copies are not of one topology or request different load factors.
    """
    t0 = path_clock()
    count = len(members)
    if count == 0:
        return []
    numbering = RestNumbering.of(*members[0])
    kinds = [(type(c), c.bodies, c.n_internal) for c in members[0][1]]
    lam = cases[0].factors(levels)
    rests: dict[tuple[int, int], _Rest | Exception] = {}
    for k, (mechanism, connectors) in enumerate(members):
        key = (id(mechanism), id(connectors))  # copies of one mechanism: evaluated once
        if key in rests:
            continue
        if k > 0 and (  # copy 0 is numbered by its own numbering
            list(mechanism.moving_bodies) != numbering.bodies
            or [(type(c), c.bodies, c.n_internal) for c in connectors] != kinds
            or not numbering.fits(connectors)
        ):
            raise ValueError("the copies are not of one topology")
        try:
            rests[key] = _Rest.of(mechanism, connectors, numbering)
        except (ValueError, FloatingPointError) as exc:
            rests[key] = exc
    distinct = {id(case): case for case in cases[1:] if case is not cases[0]}.values()
    if any(not np.array_equal(case.factors(levels), lam) for case in distinct):
        raise ValueError("the copies' load cases request different load factors")
    results: list[LoadPath | Exception | None] = [None] * count
    solved = []  # the copies whose connectors took their rest state
    for k, (mechanism, connectors) in enumerate(members):
        rest = rests[(id(mechanism), id(connectors))]
        if isinstance(rest, Exception):
            results[k] = rest
        else:
            solved.append(k)
    rest_of = [rests[(id(members[k][0]), id(members[k][1]))] for k in solved]
    if solved:
        for k, path in zip(solved, _solve(numbering, members, cases, solved, rest_of, lam)):
            results[k] = path
    seconds = (path_clock() - t0) / count
    for path in results:
        if isinstance(path, LoadPath):
            path.model, path.scene, path.seconds = model, scene, seconds
    return results


def _solve(
    numbering: RestNumbering,
    members: Sequence[Member],
    cases: Sequence[LoadCase],
    copies: list[int],
    rests: list[_Rest],
    lam: np.ndarray,
) -> list[LoadPath | Exception]:
    """The linear responses of copies ``copies`` (their rest evaluations ``rests``)."""
    n, layout, count = numbering.n, numbering.layout, len(copies)
    dofs, keep = numbering.dofs, numbering.keep
    moving = dofs >= 0
    slots = layout.slots[: layout.slots.size - n]
    if (slots < 0).any():  # a storage that drops entries: each copy's own assembly refuses it
        raise ValueError("K0's storage drops entries")
    hessians = np.array([rest.hessians for rest in rests])  # (copies, h)
    offsets = np.arange(count)[:, None]
    storages = np.bincount(
        (slots[None, :] + layout.size * offsets).ravel(),
        weights=hessians[:, keep].ravel(),
        minlength=count * layout.size,
    ).reshape(count, layout.size)
    gradients = np.array([rest.gradients for rest in rests])[:, moving]
    g_zero = np.bincount(
        (dofs[moving][None, :] + n * offsets).ravel(),
        weights=gradients.ravel(),
        minlength=count * n,
    ).reshape(count, n)
    gravity = [members[k][0].inertia.gravity is not None for k in copies]
    poses = numbering.bodies
    first = {b: 3 * i for i, b in enumerate(poses)}

    def pose_dofs(body: str) -> np.ndarray:
        return np.arange(first[body], first[body] + 3) if body in first else np.full(3, -1)

    loads_of: dict[tuple[int, int], Loads] = {}
    dq, dq_dead = np.zeros((count, n)), np.zeros((count, n))
    failed: dict[int, Exception] = {}
    for i, (k, rest) in enumerate(zip(copies, rests)):
        mechanism, case = members[k][0], cases[k]
        key = (id(case), id(mechanism))
        if key not in loads_of:
            loads_of[key] = Loads.of_case(case, pose_dofs, rest.reference, mechanism.size())
        g_unit = g_zero[i].copy()  # g = grad E(q0) - f = -f at rest
        loads_of[key].add_to(rest.q0, 1.0, g_unit, np.zeros_like(g_unit))
        tangent = layout.tangent(storages[i])
        try:
            dq[i] = tangent.solve(g_zero[i] - g_unit)  # per unit load factor
            if gravity[i]:  # the weights, g = -w at rest and no load
                dq_dead[i] = tangent.solve(-g_zero[i])
        except (np.linalg.LinAlgError, ValueError) as exc:
            failed[i] = exc
    # the target point's linearised motion at rest: (dx - rel_y dtheta, dy + rel_x dtheta)
    target = np.zeros((count, 5))  # rel x, rel y (mm), the target's x, y, theta dofs
    for i, k in enumerate(copies):
        mechanism = members[k][0]
        body = mechanism.target_body
        rel = mechanism.target_point - rests[i].reference[body]
        target[i] = [*rel.tolist(), *pose_dofs(body).tolist()]
    rel_x, rel_y = target[:, :1], target[:, 1:2]
    tdofs = target[:, 2:].astype(np.int64)
    on_ground = tdofs[:, :1] < 0
    rows = np.arange(count)[:, None]
    ux, uy, rot = (np.where(on_ground, 0.0, dq[rows, tdofs[:, [j]]]) for j in range(3))
    wx, wy, dead_rot = (np.where(on_ground, 0.0, dq_dead[rows, tdofs[:, [j]]]) for j in range(3))
    dx = (wx - rel_y * dead_rot) + lam * (ux - rel_y * rot)
    dy = (wy + rel_x * dead_rot) + lam * (uy + rel_x * rot)
    rotation = dead_rot + lam * rot
    magnitude = np.array([[cases[k].magnitude] for k in copies])
    # every level's largest body rotation, (copies, levels, bodies) rad
    b3 = 3 * len(poses)
    turns = np.abs(dq_dead[:, None, 2:b3:3] + lam[None, :, None] * dq[:, None, 2:b3:3])
    too_far = (turns > MAX_LINEAR_ROTATION).any(axis=(1, 2)) if poses else np.zeros(count, bool)
    forces, sway = _section_forces(numbering, members, copies, rests, dq, dq_dead, gravity, lam)
    paths: list[LoadPath | Exception] = []
    rows_of = zip((lam * magnitude).tolist(), dx.tolist(), dy.tolist(), rotation.tolist(), forces)
    for i, (k, (load, x, y, turn, stresses)) in enumerate(zip(copies, rows_of)):
        if i in failed:
            paths.append(failed[i])
            continue
        case = cases[k]
        path = LoadPath(
            model="",
            load_case=case.name,
            load=load,
            dx=x,
            dy=y,
            rotation=turn,
            seconds=0.0,
            converged=True,
            stats={"unknowns": n, "newton_iterations": 0, "step_cuts": 0, "substeps": 0},
            settings={},
            load_unit=case.unit,
        )
        if too_far[i]:
            path.valid, path.validity = rotation_verdicts(turns[i], poses)
        else:
            path.valid, path.validity = [True] * lam.size, [None] * lam.size
        path.valid, path.validity = merge_reasons(path.valid, path.validity, sway[i])
        append_stresses(path, stresses)
        path.valid, path.validity = merge_reasons(
            path.valid, path.validity, strain_reasons(path, members[k][0].material.youngs_modulus)
        )
        paths.append(path)
    return paths


def rotation_verdicts(turns: np.ndarray, bodies: list[str]) -> tuple[list, list]:
    """The validity monitor's verdict at each level of a linear response from its bodies'
    rotations ``turns`` (levels, bodies; rad): beyond
    :data:`~flexval.reducedmodels.core.validity.MAX_LINEAR_ROTATION` the linearised kinematics
    no longer hold."""
    valid, validity = [], []
    for row, k in zip(turns.tolist(), np.argmax(turns, axis=1).tolist()):
        reason = None
        if row[k] > MAX_LINEAR_ROTATION:
            reason = (
                f"linear response: body {bodies[k]!r} turned "
                f"{math.degrees(row[k]):.3g} deg (limit "
                f"{math.degrees(MAX_LINEAR_ROTATION):.3g} deg: linearised kinematics)"
            )
        valid.append(reason is None)
        validity.append(reason)
    return valid, validity


def _section_forces(
    numbering: RestNumbering,
    members: Sequence[Member],
    copies: list[int],
    rests: list[_Rest],
    dq: np.ndarray,
    dq_dead: np.ndarray,
    gravity: list[bool],
    lam: np.ndarray,
) -> tuple[list[list[tuple[str, tuple]]], list[list[list[str]]]]:
    """Each copy's flexures' stresses (:func:`~flexval.reducedmodels.core.peaks.state_peaks`
    entries by flexure name, in its connectors' order) from the section forces of K0 dq on
    the undeformed centre lines, every copy's connectors of one class in one call; and each
    copy's reasons per level where a straight leaf it cannot buckle is compressed beyond its
    sway load (:func:`~flexval.reducedmodels.core.validity.linear_sway_verdicts`)."""
    count = len(copies)
    start = numbering.bounds[-1] if numbering.bounds else 0
    hessians = np.array([rest.hessians for rest in rests])
    local = np.array([rest.local for rest in rests])
    grounds = np.array(  # each copy's ground pose, read after its unknowns
        [[*rest.reference[members[k][0].ground].tolist(), 0.0] for k, rest in zip(copies, rests)]
    )
    q0 = np.array([rest.q0 for rest in rests])
    offsets = (np.arange(count) * start)[:, None]

    def gradients(motion: np.ndarray) -> np.ndarray:
        """Every copy's K0 dq per local coordinate, (copies, d)."""
        moved = np.concatenate([q0 + motion, grounds], 1)[:, numbering.gather] - local
        return np.bincount(
            (numbering.local_rows[None, :] + offsets).ravel(),
            weights=(hessians * moved[:, numbering.local_cols]).ravel(),
            minlength=count * start,
        ).reshape(count, start)

    per_unit = gradients(dq)
    connectors0 = members[copies[0]][1]
    classes = list(dict.fromkeys(type(c) for c in connectors0))
    # each class's connectors of every copy, copy after copy: (copy, index) and the group
    runs = []
    for kind in classes:
        where = [j for j, c in enumerate(connectors0) if type(c) is kind]
        group = kind.group([members[k][1][j] for k in copies for j in where])
        runs.append((where, group))
    bounds = list(zip(numbering.places, numbering.bounds))

    def forces_at(gradient: np.ndarray) -> list[list]:
        """Every copy's connectors' section forces for local gradients (copies, d)."""
        out: list[list] = [[None] * len(connectors0) for _ in range(count)]
        for where, group in runs:
            states = [rests[i].states[j] for i in range(count) for j in where]
            given = [gradient[i, bounds[j][0] : bounds[j][1]] for i in range(count) for j in where]
            found = iter(group.section_forces(states, given))
            for i in range(count):
                for j in where:
                    out[i][j] = next(found)
        return out

    sections = [{f.name: f.section for f in members[k][0].flexures} for k in copies]
    stressed = [
        (i, j, c.name, sections[i][c.name], c.surface_stress)
        for i, k in enumerate(copies)
        for j, c in enumerate(members[k][1])
        if sections[i].get(c.name) is not None
    ]
    found: list[list[tuple[str, tuple]]] = [[] for _ in range(count)]
    sway: list[list[list[str]]] = [[[] for _ in lam] for _ in range(count)]
    if any(c.sway_load is not None for c in connectors0):  # straight leaves it cannot buckle
        unit = forces_at(per_unit)
        dead = forces_at(gradients(dq_dead)) if any(gravity) else None
        for i, k in enumerate(copies):
            sway[i] = linear_sway_verdicts(
                members[k][1], unit[i], lam, None if dead is None else dead[i]
            )
    if not any(gravity):  # section forces proportional to the load
        forces = forces_at(per_unit)
        chosen = [
            (i, name, forces[i][j], s, k)
            for i, j, name, s, k in stressed
            if forces[i][j] is not None
        ]
        peaks = state_peaks([(f, s) for *_, f, s, _ in chosen], lam, [k for *_, k in chosen])
        for (i, name, *_), entry in zip(chosen, peaks):
            found[i].append((name, entry))
        return found, sway
    of_weights = gradients(dq_dead)
    for factor in lam:  # the weights' forces, then the load's at this level
        forces = forces_at(of_weights + factor * per_unit)
        chosen = [
            (i, name, forces[i][j], s, k)
            for i, j, name, s, k in stressed
            if forces[i][j] is not None
        ]
        peaks = state_peaks([(f, s) for *_, f, s, _ in chosen], (1.0,), [k for *_, k in chosen])
        for (i, name, *_), entry in zip(chosen, peaks):
            found[i].append((name, entry))
    return found, sway
