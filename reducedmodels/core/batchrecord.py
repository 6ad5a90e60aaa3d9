"""Recording a batch's copies: each copy's LoadPath from the points the batch traced.

:func:`record_batch` turns the points :func:`flexval.reducedmodels.core.batch.trace_batch`
traced for many copies at once into each copy's
:class:`~flexval.reducedmodels.core.loadpath.LoadPath`, the one its own
:class:`~flexval.reducedmodels.core.recorder.PathRecorder` makes of the same points. The
end pass (validity monitor, section forces, stresses) takes one pass per group
of the batch's connectors for every copy and level at once; what each copy's
flexures are (names, sections) is read once per distinct mechanism
(:func:`copy_flexures`) and looked up for the stacks' rows as arrays.

Units: mm, N, N mm, MPa, rad.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from flexval.geometry import LoadCase, Mechanism, Section

from .connector import Connector
from .loadpath import LoadPath
from .recorder import (
    STACK_FROM,
    carries_weights,
    failed_path,
    levels_path,
    note_stability,
    path_peaks,
    stack_peaks,
)
from .sections import SectionForces
from .settings import SolverError
from .tracer import Counters, PathPoint, TraceFailure
from .validity import resolution_reason, unresolved_levels

if TYPE_CHECKING:  # annotations only: the batch imports this module
    from .batchsystem import BatchSystem


class CopyFlexures(NamedTuple):
    """The flexure behind each connector of a batch's copies, per distinct copy.

    Copies that share their mechanism and connectors share a row, so a batch
    of one mechanism reads its flexures once.
    """

    row: np.ndarray
    """(copies,): each copy's row."""
    names: list[list[str]]
    """Per row, each connector's name (its flexure's), in the copy's connector order."""
    sections: list[list[Section | None]]
    """Per row, each connector's flexure section (None: a connector of no flexure, a pin)."""
    constants: np.ndarray
    """(rows, connectors, 3): each uniform section's thickness (mm), area (mm^2) and second
    moment (mm^4); NaN for the others."""
    uniform: np.ndarray
    """(rows, connectors) of bool: the connector has a flexure of uniform section (whose
    stresses are stacked with others')."""
    stressed: np.ndarray
    """(rows, connectors) of bool: the connector has a flexure, of any section (its stresses
    are recorded)."""


def copy_flexures(members: Sequence[tuple[Mechanism, Sequence[Connector]]]) -> CopyFlexures:
    """The :class:`CopyFlexures` of a batch's copies (its ``members``: each copy's mechanism
    and connectors)."""
    rows: dict[tuple[int, int], int] = {}
    row = np.empty(len(members), np.int64)
    names, sections = [], []
    for k, (mechanism, connectors) in enumerate(members):
        key = (id(mechanism), id(connectors))
        if key not in rows:
            rows[key] = len(names)
            by_name = {f.name: f.section for f in mechanism.flexures}
            names.append([c.name for c in connectors])
            sections.append([by_name.get(c.name) for c in connectors])
        row[k] = rows[key]
    count = len(sections[0]) if sections else 0
    constants = np.full((len(sections), count, 3), np.nan)
    uniform = np.zeros((len(sections), count), bool)
    stressed = np.zeros((len(sections), count), bool)
    for r, of_row in enumerate(sections):
        for i, section in enumerate(of_row):
            if section is None:
                continue
            stressed[r, i] = True
            if section.profile is None:
                uniform[r, i] = True
                constants[r, i] = (section.thickness, section.area, section.inertia)
    return CopyFlexures(row, names, sections, constants, uniform, stressed)


def record_batch(
    batch: BatchSystem,
    points: Sequence[PathPoint],
    kept: Sequence[int],
    cases: Sequence[LoadCase],
    model: str = "",
    scene: str = "",
    settings: dict | None = None,
    failure: TraceFailure | None = None,
) -> list[LoadPath | SolverError]:
    """The LoadPaths of copies ``kept`` from the batch's points, as each copy's recorder makes it.

    With a ``failure`` (the trace of a batch of one copy stopped), the copy's
    :class:`~flexval.reducedmodels.core.settings.SolverError` carrying the path so far, as its
    recorder makes it of the same failure.

    The validity monitor and the section forces take one pass per group of
    the batch's connectors for every copy and level at once
    (:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.path_end_stacks`),
    as :func:`~flexval.reducedmodels.core.recorder.path_end_pass` takes one per
    group of a copy; the stresses of connectors stacked alike come from
    their stack (:func:`~flexval.reducedmodels.core.recorder.stack_peaks`), the
    others' from :func:`~flexval.reducedmodels.core.recorder.path_peaks`; reasons
    and stresses then go to each copy in its own connectors' order.
    """
    if not kept:
        return []
    states = np.array([p.state for p in points])
    place = np.full(batch.n_copies, -1, np.int64)  # each copy's place in kept (-1: not kept)
    place[kept] = np.arange(len(kept))
    flexures = copy_flexures(batch.members)
    reasons: dict[int, list[list[str]]] = {}  # of the copies with any, per level
    count = len(batch.members[0][1])  # connectors a copy (every copy's kinds are copy 0's)
    peaks: list[list] = [[None] * count for _ in kept]  # per copy and connector: (name, peaks)
    stressed = []  # (copy's place in kept, connector's index in its copy, name) of entries
    entries = []  # their (forces, section), whose peaks path_peaks finds
    origin_table = batch.origin_table
    for (group, run), coordinates in zip(batch.groups, batch.group_coordinates(states)):
        verdicts, stacks = group.path_end_stacks(coordinates)
        connectors = group.connectors
        clean = None  # a verdict without reasons (groups share one among their connectors)
        for k, c, per_level in zip(origin_table[run, 0].tolist(), connectors, verdicts):
            if per_level is clean:
                continue
            if not any(per_level):
                clean = per_level
            elif place[k] >= 0:
                into_levels = reasons.setdefault(int(place[k]), [[] for _ in points])
                for into, why in zip(into_levels, per_level):
                    if why:
                        into.extend(f"{c.name}: {w}" for w in why)
        for stack in stacks:
            copy, index = origin_table[run.start + np.asarray(stack.members, np.int64)].T
            row, at = flexures.row[copy], place[copy]
            rows = np.flatnonzero((at >= 0) & flexures.stressed[row, index])
            row, at, index = row[rows], at[rows], index[rows]
            names = [flexures.names[r][i] for r, i in zip(row.tolist(), index.tolist())]
            if rows.size >= STACK_FROM and flexures.uniform[row, index].all():
                if rows.size < len(stack.members):
                    stack = stack._replace(axial=stack.axial[rows], moment=stack.moment[rows])
                found = stack_peaks(stack, flexures.constants[row, index])
                for j, i, name, peak in zip(at.tolist(), index.tolist(), names, found):
                    peaks[j][i] = (name, peak)
                continue
            for r, j, i, name in zip(rows.tolist(), at.tolist(), index.tolist(), names):
                stressed.append((j, i, name))
                section = flexures.sections[flexures.row[copy[r]]][i]
                entries.append((SectionForces(stack.at, stack.axial[r], stack.moment[r]), section))
    for (j, index, name), found in zip(stressed, path_peaks(entries)):
        peaks[j][index] = (name, found)
    no_reasons = [[] for _ in points]
    copies = batch.n_copies
    iterations = np.array([np.broadcast_to(p.iterations, (copies,)) for p in points]).T.tolist()
    last = points[-1].counters
    newton = np.broadcast_to(last.newton_iterations, (copies,)).tolist()
    targets = batch.copy_targets(states)
    factors = [p.factor for p in points]
    _note_resolution(batch, kept, factors, targets, reasons)
    dx, dy, rotation = (v.T.tolist() for v in targets)
    load_of: dict[int, list[float]] = {}  # each case's load at each level (N or N mm), once
    totals: dict[int, Counters] = {}  # the counts after the last point, by Newton iterations

    def counters_of(newton_iterations: int) -> Counters:
        found = totals.get(newton_iterations)
        if found is None:
            found = totals[newton_iterations] = Counters(
                newton_iterations, last.step_cuts, last.substeps
            )
        return found

    paths = []
    for j, k in enumerate(kept):
        case = cases[k]
        load = load_of.get(id(case))
        if load is None:
            load = load_of[id(case)] = [f * case.magnitude for f in factors]
        path = levels_path(
            case,
            model,
            scene,
            settings,
            batch.copy_dofs[k].size,
            list(load),
            dx[k],
            dy[k],
            rotation[k],
            iterations[k],
            counters_of(newton[k]),
            reasons.get(j, no_reasons),
            [entry for entry in peaks[j] if entry is not None],  # in the connectors' order
        )
        if k in batch.solo_systems:  # a copy judged alone: its stability note, as alone
            note_stability(path, batch.solo_systems[k])
        if failure is None:
            paths.append(path)
            continue
        counts = failure.counters
        alone = Counters(
            int(np.broadcast_to(counts.newton_iterations, (copies,))[k]),
            counts.step_cuts,
            counts.substeps,
        )
        failed = TraceFailure(
            failure.reason, failure.factor, alone, failure.bifurcations, failure.bifurcation
        )
        paths.append(failed_path(path, cases[k], model, failed, 0.0))
    return paths


def _note_resolution(
    batch: BatchSystem,
    kept: Sequence[int],
    factors: Sequence[float],
    targets: tuple[np.ndarray, ...],
    reasons: dict[int, list[list[str]]],
) -> None:
    """Add to ``reasons`` (by place in ``kept``, per level) where a kept copy's load is below
    its round-off (:func:`~flexval.reducedmodels.core.validity.unresolved_levels`, every copy at
    once), after its connectors' reasons as :func:`~flexval.reducedmodels.core.recorder.
    note_resolution` adds them to a path alone; ``targets`` are the copies' dx, dy (mm) and
    rotation (rad), each (levels, copies)."""
    members = [batch.members[k] for k in kept]
    mask, moved, floor = unresolved_levels(
        np.asarray(factors),
        *(v[:, kept].T for v in targets),
        np.array([mechanism.size() for mechanism, _ in members]),
        np.array([batch.copy_dofs[k].size for k in kept]),
        np.array([carries_weights(connectors) for _, connectors in members]),
    )
    if not mask.any():
        return
    for j in np.flatnonzero(mask.any(axis=1)).tolist():
        into = reasons.setdefault(j, [[] for _ in factors])
        for level in np.flatnonzero(mask[j]).tolist():
            into[level].append(resolution_reason(float(moved[j, level]), float(floor[j])))
