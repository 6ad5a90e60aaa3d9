"""Recording traced paths as LoadPaths: a path alone, point by point, or a batch's copies.

:class:`PathRecorder` turns the points :func:`flexval.reducedmodels.core.tracer.trace`
yields into a :class:`~flexval.reducedmodels.core.loadpath.LoadPath` (target motion,
optional poses, shapes and reactions, the validity monitor, solver
statistics) and a tracer failure into a :class:`~flexval.reducedmodels.core.settings.SolverError`
that carries the path so far. :func:`record_batch` makes each copy's LoadPath of the points
a batch traced (:func:`flexval.reducedmodels.core.batch.trace_batch`), the one its own
recorder makes of the same points. Both judge their states with the one :func:`end_pass`
(a path alone is a batch of one copy) and build paths with the same helpers.
:func:`solve_path` (load control) and
:func:`flexval.reducedmodels.core.continuation.solve_arclength` are thin uses of it.

Units: mm, N, N mm, MPa, rad.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from flexval.geometry import LoadCase, Mechanism, Section

from ..kernels.clock import path_clock
from .connector import Connector
from .loadpath import LoadPath
from .peaks import STACK_FROM, Peaks, append_stresses, path_peaks, stack_peaks
from .sections import SectionForces
from .settings import SolverError
from .system import System
from .tracer import Counters, LoadControl, PathPoint, TraceFailure, trace
from .validity import merge_reasons, resolution_reason, unresolved_levels

if TYPE_CHECKING:  # annotations only: the batch's System is built on System
    from .batchsystem import BatchSystem

_OBSERVERS: list[Callable[[LoadPath], None]] = []
"""Called with the path after each point a :class:`PathRecorder` records (see :func:`observing`)."""


@contextmanager
def observing(callback: Callable[[LoadPath], None]) -> Iterator[None]:
    """Within the block, call ``callback(path)`` after every point any :class:`PathRecorder`
    records, and every time step a dynamic run accepts (the path so far: its last load, or
    time, is the point's); for progress reports. The
    callback only reads: the traced path is the same with or without it."""
    _OBSERVERS.append(callback)
    try:
        yield
    finally:
        _OBSERVERS.remove(callback)


def notify(path: LoadPath) -> None:
    """Tell every observer (:func:`observing`) that ``path`` has a new point: a load level
    recorded by a :class:`PathRecorder`, or a time step accepted by
    :func:`flexval.reducedmodels.analyses.dynamics.solve_dynamic`."""
    for callback in _OBSERVERS:
        callback(path)


class PathRecorder:
    """Builds the LoadPath of ``system`` on ``case`` from the points of a trace.

    Every point is checked by the validity monitor (:meth:`System.validity`):
    ``LoadPath.valid`` and ``LoadPath.validity`` say, per point, whether the
    state is inside every model's range of meaning and if not why; the run
    goes on either way. The monitor's verdicts and the section stresses are
    computed when the path ends (:meth:`finish` or :meth:`failure`), for all
    its points at once: a connector's section forces then take one
    vectorised pass per path (:meth:`Connector.path_section_forces`)
    instead of one call per level.

    Parameters
    ----------
    system : System
    case : LoadCase
    model : str
        Model id recorded in the result (and named in failures).
    scene : str
    settings : dict
        Model settings recorded in the result.
    record_poses, record_shapes, record_reactions : bool
        Also record every body's pose, every connector's shape and the
        ground reaction at each point.
    limit_points : bool
        Record the indices of the local extrema of the load
        (``stats['limit_points']``), for paths whose load rises and falls.
    """

    def __init__(
        self,
        system: System,
        case: LoadCase,
        model: str = "",
        scene: str = "",
        settings: dict | None = None,
        record_poses: bool = False,
        record_shapes: bool = False,
        record_reactions: bool = False,
        limit_points: bool = False,
    ):
        self.t0 = path_clock()
        system.check_drive(case, model)
        self.system, self.case, self.model = system, case, model
        self.magnitude = case.magnitude  # the full load (N or N mm), read at every level
        self.path = LoadPath(
            model=model,
            load_case=case.name,
            load=[],
            dx=[],
            dy=[],
            rotation=[],
            seconds=0.0,
            settings=settings or {},
            scene=scene,
            load_unit=case.unit,
            poses={b: [] for b in system.mechanism.bodies} if record_poses else None,
            shapes={c.name: [] for c in system.connectors} if record_shapes else None,
            reactions=[] if record_reactions else None,
            drive_reactions=[] if case.drive is not None else None,
            valid=[],
            validity=[],
            bifurcations=[],
        )
        self.stats = {
            "unknowns": system.n_dofs,
            "newton_iterations": 0,
            "step_cuts": 0,
            "substeps": 0,
            "iterations": [],
        }
        if limit_points:
            self.stats["limit_points"] = []
        self.path.stats = self.stats
        self.factors: list[float] = []
        self.states: list[np.ndarray] = []  # recorded states not yet judged and stressed
        self.unstable: list[int | None] = []  # each point's surplus negative eigenvalues

    def record(self, point: PathPoint) -> None:
        """Append one converged point."""
        system, lp, q = self.system, self.path, point.state
        dx, dy, rot = system.target(q)
        lp.load.append(point.factor * self.magnitude)
        lp.dx.append(dx), lp.dy.append(dy), lp.rotation.append(rot)
        self.states.append(q)
        if lp.reactions is not None:
            lp.reactions.append(system.reaction(q).tolist())
        if lp.drive_reactions is not None:
            lp.drive_reactions.append(system.drive_reaction(q).tolist())
        if lp.poses is not None:
            for b in system.mechanism.bodies:
                lp.poses[b].append(system.pose(q, b).tolist())
        if lp.shapes is not None:
            for c, local in zip(system.connectors, system.local_states(q)):
                lp.shapes[c.name].append(c.shape(*local).tolist())
        self.stats["iterations"].append(point.iterations)
        self.unstable.append(point.unstable)
        _count(self.stats, point.counters)
        _append_bifurcations(lp, point.bifurcations, self.magnitude)
        self.factors.append(point.factor)
        f = self.factors
        if "limit_points" in self.stats and len(f) >= 3 and (f[-2] - f[-3]) * (f[-1] - f[-2]) < 0:
            self.stats["limit_points"].append(len(f) - 2)
        notify(lp)

    def _judge(self) -> None:
        """Validity verdicts and section stresses of the states recorded since the last call
        (:func:`end_pass`, this path as a batch's one copy)."""
        if not self.states:
            return
        shapes = self.path.shapes is not None
        judgement = end_pass(self.system, self.states, with_forces=shapes)
        valid, validity = _validity(judgement.reasons[0])
        self.path.valid.extend(valid)
        self.path.validity.extend(validity)
        append_stresses(self.path, judgement.peaks[0])
        if shapes:
            append_section_forces(self.path, judgement.forces[0])
        self.states = []

    def finish(self) -> LoadPath:
        """The path of a successful trace (wall time from the recorder's creation)."""
        self._judge()
        note_stability(self.path, self.system)
        note_unstable_points(self.path, self.unstable)
        note_resolution(self.path, self.system.size, carries_weights(self.system.connectors))
        self.path.converged = True
        self.path.seconds = path_clock() - self.t0
        return self.path

    def failure(self, exc: TraceFailure) -> SolverError:
        """The SolverError for a failed trace, carrying the path so far."""
        self._judge()
        note_stability(self.path, self.system)
        note_unstable_points(self.path, self.unstable)
        note_resolution(self.path, self.system.size, carries_weights(self.system.connectors))
        return failed_path(self.path, self.case, self.model, exc, path_clock() - self.t0)

    def run(
        self, points: Iterator[PathPoint], stop: Callable[[LoadPath], bool] | None = None
    ) -> tuple[LoadPath, PathPoint]:
        """Record the points (until ``stop(path)`` is True); return the path and the last point.

        Raises
        ------
        SolverError
            If the trace fails; carries the last converged load factor and the path so far.
        """
        last = None
        try:
            for last in points:
                self.record(last)
                if stop is not None and stop(self.path):
                    break
        except TraceFailure as exc:
            raise self.failure(exc) from None
        return self.finish(), last


def note_stability(path: LoadPath, system: System) -> None:
    """``stats["stability"]``: why the path's stability was not judged, where it was not
    (:meth:`~flexval.reducedmodels.core.system.System.stability_note`)."""
    note = system.stability_note()
    if note is not None:
        path.stats["stability"] = note


def note_unstable_points(path: LoadPath, unstable: Sequence[int | None]) -> None:
    """Mark the points of a path that are unstable equilibria (``unstable``: each point's
    negative eigenvalues beyond the path's first point's, None where not counted): an
    arc-length trace passes them on its way past a limit or bifurcation point, but the load
    case's control (dead loads, or a prescribed motion) cannot hold the mechanism there, so
    they are outside what the model can be trusted to show as a reachable state."""
    if len(unstable) != len(path.load) or not any(unstable):
        return
    extra = [
        [
            f"an unstable equilibrium ({k} more negative eigenvalue{'s' if k > 1 else ''} of "
            "the tangent than at rest): the load case's control cannot hold the mechanism here"
        ]
        if k
        else []
        for k in unstable
    ]
    path.valid, path.validity = merge_reasons(path.valid, path.validity, extra)


def note_resolution(path: LoadPath, size: float, weighted: bool) -> None:
    """Mark the levels of a traced path whose load double precision does not resolve
    (:func:`~flexval.reducedmodels.core.validity.unresolved_levels`; ``size`` in mm, ``weighted``
    where the path's rest carries weights)."""
    if not path.load:  # stopped before its first level
        return
    mask, moved, floor = unresolved_levels(
        path.load, path.dx, path.dy, path.rotation, size, path.stats["unknowns"], weighted
    )
    if mask.any():
        extra = [
            [resolution_reason(m, float(floor))] if bad else []
            for bad, m in zip(mask.tolist(), moved.tolist())
        ]
        path.valid, path.validity = merge_reasons(path.valid, path.validity, extra)


def carries_weights(connectors: Iterable[Connector]) -> bool:
    """Whether any connector carries dead loads of its own (``dead_load_scale`` > 0, N)."""
    return any(c.dead_load_scale > 0.0 for c in connectors)


def _append_bifurcations(path: LoadPath, factors: Iterable[float], magnitude: float) -> None:
    """Append bifurcation points (load factors) as ``{"load", "fraction"}`` (N or N mm; the
    case's full load ``magnitude``)."""
    path.bifurcations.extend({"load": f * magnitude, "fraction": f} for f in factors)


def _count(stats: dict, counters: Counters) -> None:
    """Set a path's solver totals (Newton iterations, step cuts, sub-steps) from ``counters``."""
    stats["newton_iterations"] = counters.newton_iterations
    stats["step_cuts"] = counters.step_cuts
    stats["substeps"] = counters.substeps


def _validity(verdicts: Sequence[list[str]]) -> tuple[list[bool], list[str | None]]:
    """The validity monitor's ``valid`` and ``validity`` entries of levels with these reasons
    (empty: valid)."""
    if not any(verdicts):  # every level valid
        return [True] * len(verdicts), [None] * len(verdicts)
    return [not why for why in verdicts], ["; ".join(why) if why else None for why in verdicts]


def levels_path(
    case: LoadCase,
    model: str,
    scene: str,
    settings: dict | None,
    unknowns: int,
    load: list[float],
    dx: list[float],
    dy: list[float],
    rotation: list[float],
    iterations: list[int],
    counters: Counters,
    verdicts: Sequence[list[str]],
    peaks: Iterable[tuple[str, Peaks]],
) -> LoadPath:
    """The LoadPath a :class:`PathRecorder` makes of converged levels recorded and judged at
    once: a batch's copy, whose states the batch traced and judged for it.

    The load at each level (N or N mm: its factor times the case's
    magnitude), the target's motion (mm, rad), each level's Newton
    iterations (lists the path keeps) and the totals after the last
    (``counters``), the validity monitor's reasons at each level, and each
    flexure's :data:`Peaks` (MPa), by name in the connectors' order. Poses,
    shapes and reactions are not recorded this way; ``seconds`` is left 0.
    """
    valid, validity = _validity(verdicts)
    path = LoadPath(
        model=model,
        load_case=case.name,
        load=load,
        dx=dx,
        dy=dy,
        rotation=rotation,
        seconds=0.0,
        settings=settings or {},
        scene=scene,
        load_unit=case.unit,
        valid=valid,
        validity=validity,
        bifurcations=[],
    )
    path.stats = {"unknowns": unknowns}
    _count(path.stats, counters)
    path.stats["iterations"] = iterations
    append_stresses(path, peaks)
    notify(path)
    return path


def failed_path(
    path: LoadPath, case: LoadCase, model: str, exc: TraceFailure, seconds: float
) -> SolverError:
    """The SolverError of a trace that failed (``exc``) after recording ``path``: the path
    marked unconverged (its totals, bifurcations and reason from ``exc``; ``seconds`` its
    wall time, s), carried by the error."""
    stats, lam = path.stats, exc.factor
    _count(stats, exc.counters)
    _append_bifurcations(path, exc.bifurcations, case.magnitude)
    reason = exc.reason
    if exc.bifurcation is not None:
        _append_bifurcations(path, [exc.bifurcation], case.magnitude)
        stats["stopped_at_bifurcation"] = exc.bifurcation  # load factor
        reason = (
            f"bifurcation at {exc.bifurcation * case.magnitude:.6g} {case.unit} "
            f"(fraction {exc.bifurcation:.6g}): beyond it load control finds only "
            "unstable equilibria (trace it with --arclength)"
        )
    stats["failure"] = reason
    path.converged = False
    path.seconds = seconds
    return SolverError(
        f"{model or 'model'} on load case '{case.name}': {reason}; "
        f"last converged load {lam * case.magnitude:.6g} {case.unit} "
        f"({100 * lam:.2f} % of full load)",
        lam,
        path,
    )


def append_section_forces(
    path: LoadPath, forces: Iterable[tuple[Connector, SectionForces | None]]
) -> None:
    """Append each flexure's section forces (N, N mm), stacked over levels (k, m), to
    ``path.section_forces`` (connectors without them, pins, are skipped)."""
    if path.section_forces is None:
        path.section_forces = {}
    for c, stacked in forces:
        if stacked is None:
            continue
        kept = path.section_forces.setdefault(
            c.name, {"at": np.asarray(stacked.at, float).tolist(), "axial": [], "moment": []}
        )
        kept["axial"] += np.atleast_2d(stacked.axial).tolist()
        kept["moment"] += np.atleast_2d(stacked.moment).tolist()


def solve_path(
    system: System,
    case: LoadCase,
    levels: int | None = None,
    model: str = "",
    settings: dict | None = None,
    scene: str = "",
    record_poses: bool = False,
    record_shapes: bool = False,
    record_reactions: bool = False,
) -> LoadPath:
    """Trace the load path of ``case`` through its requested levels by load control.

    Between two requested levels the load factor advances in sub-steps
    (:class:`~flexval.reducedmodels.core.tracer.LoadControl`); the reported levels are
    exactly the requested ones (``levels`` equal steps, default the load
    case's).

    Raises
    ------
    SolverError
        When step cutting cannot save a step; carries the last converged load
        factor and the partial LoadPath.
    """
    recorder = PathRecorder(
        system, case, model, scene, settings, record_poses, record_shapes, record_reactions
    )
    points = trace(system, system.loads(case), LoadControl(case.factors(levels)))
    return recorder.run(points)[0]


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


class Judgement(NamedTuple):
    """What the end pass finds at every level of a batch's kept copies (a path alone: one copy),
    each copy's entries in its own connectors' order."""

    reasons: list[list[list[str]]]
    """Per kept copy, per level: the validity monitor's reasons, each prefixed with its
    connector's name (none: valid)."""
    peaks: list[list[tuple[str, Peaks]]]
    """Per kept copy: each stressed flexure's name and :data:`~flexval.reducedmodels.core.peaks.
    Peaks` (MPa)."""
    forces: list[list[tuple[Connector, SectionForces]]] | None
    """Per kept copy (when asked for): each connector with section forces and them, (k, m)
    (N, N mm)."""


def end_pass(
    system: System,
    states: Sequence[np.ndarray],
    kept: Sequence[int] = (0,),
    with_forces: bool = False,
) -> Judgement:
    """The validity monitor's verdicts and the flexures' stresses at every state, per kept copy.

    The one end pass of a recorded path, for a path alone (a System: one
    copy) and for a batch's copies alike. Each group of connectors judges
    all its connectors at every state in one call
    (:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.path_end_stacks`,
    given its coordinates: :meth:`System.group_coordinates`); connectors
    stacked alike with uniform sections, at least
    :data:`~flexval.reducedmodels.core.peaks.STACK_FROM` of them, take their
    stresses from their stack (:func:`~flexval.reducedmodels.core.peaks.stack_peaks`),
    the others from :func:`~flexval.reducedmodels.core.peaks.path_peaks`: each
    flexure's numbers are the same either way, so a copy's path is its solo
    run's. Which copy and connector a group's row is comes from
    :meth:`System.copy_layout`. A System of one copy takes each connector's
    forces as its group gives them
    (:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.path_end_pass`),
    without stacks, which would cost it more than they save.

    Parameters
    ----------
    system : System
        The path's System, or a batch's.
    states : sequence of ndarray
        The recorded states (the system's coordinates, mm and rad).
    kept : sequence of int
        The copies to judge (default: a path alone's one copy).
    with_forces : bool
        Also give each connector's section forces (recorded with a path's shapes).
    """
    origin_table, members = system.copy_layout()
    place = np.full(len(members), -1, np.int64)  # each copy's place in kept (-1: not kept)
    place[list(kept)] = np.arange(len(kept))
    alone = len(members) == 1  # one copy: its connectors' forces as its groups give them
    sections = {f.name: f.section for f in members[0][0].flexures} if alone else None
    flexures = None if alone else copy_flexures(members)
    reasons: dict[int, list[list[str]]] = {}  # of the copies with any, per level
    count = len(members[0][1])  # connectors a copy (every copy's kinds are copy 0's)
    peaks: list[list] = [[None] * count for _ in kept]  # per copy and connector: (name, peaks)
    forces = [[None] * count for _ in kept] if with_forces else None
    stressed = []  # (copy's place in kept, connector's index in its copy, name) of entries
    entries = []  # their (forces, section), whose peaks path_peaks finds
    surface_stresses = []  # their connectors' surface stress surface_stresses
    for (group, run), coordinates in zip(system.groups, system.group_coordinates(states)):
        if alone:
            verdicts, own = group.path_end_pass(coordinates)
        else:
            verdicts, stacks = group.path_end_stacks(coordinates)
        connectors = group.connectors
        clean = None  # a verdict without reasons (groups share one among their connectors)
        for k, c, per_level in zip(origin_table[run, 0].tolist(), connectors, verdicts):
            if per_level is clean:
                continue
            if not any(per_level):
                clean = per_level
            elif place[k] >= 0:
                into_levels = reasons.setdefault(int(place[k]), [[] for _ in states])
                for into, why in zip(into_levels, per_level):
                    if why:
                        into.extend(f"{c.name}: {w}" for w in why)
        if alone:  # place 0, each connector's index its place in the System
            for i, (c, found) in enumerate(zip(connectors, own), run.start):
                if found is None:
                    continue
                if forces is not None:
                    forces[0][i] = (c, found)
                section = sections.get(c.name)
                if section is not None:
                    stressed.append((0, i, c.name))
                    entries.append((found, section))
                    surface_stresses.append(c.surface_stress)
            continue
        for stack in stacks:
            copy, index = origin_table[run.start + np.asarray(stack.members, np.int64)].T
            row, at = flexures.row[copy], place[copy]
            if forces is not None:
                for r in np.flatnonzero(at >= 0).tolist():
                    forces[at[r]][index[r]] = (
                        connectors[stack.members[r]],
                        SectionForces(stack.at, stack.axial[r], stack.moment[r]),
                    )
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
                surface_stresses.append(connectors[stack.members[r]].surface_stress)
    for (j, index, name), found in zip(stressed, path_peaks(entries, surface_stresses)):
        peaks[j][index] = (name, found)
    no_reasons = [[] for _ in states]
    return Judgement(
        [reasons.get(j, no_reasons) for j in range(len(kept))],
        [[entry for entry in of_copy if entry is not None] for of_copy in peaks],
        None if forces is None else [[f for f in of_copy if f is not None] for of_copy in forces],
    )


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

    The batch's states are judged by the one :func:`end_pass`, every kept copy at
    once; each copy's path is then built as :func:`levels_path` says.
    """
    if not kept:
        return []
    states = np.array([p.state for p in points])
    judgement = end_pass(batch, states, kept)
    reasons = {j: of_copy for j, of_copy in enumerate(judgement.reasons) if any(of_copy)}
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
            judgement.peaks[j],
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
