"""Recording a traced path as a LoadPath, and load control through the requested levels.

:class:`PathRecorder` turns the points :func:`flexval.reducedmodels.core.tracer.trace`
yields into a :class:`~flexval.reducedmodels.core.loadpath.LoadPath` (target motion,
optional poses, shapes and reactions, the validity monitor, solver
statistics) and a tracer failure into a :class:`~flexval.reducedmodels.core.settings.SolverError`
that carries the path so far. :func:`solve_path` (load control) and
:func:`flexval.reducedmodels.core.continuation.solve_arclength` are thin uses of it.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from functools import cache
from types import ModuleType
from typing import NamedTuple

import numpy as np

from flexval.geometry import LoadCase, Section

from .connector import Connector
from .loadpath import LoadPath
from .sections import ForceStack, SectionForces
from .settings import SolverError
from .system import System
from .tracer import Counters, LoadControl, PathPoint, TraceFailure, trace
from .validity import merge_reasons, resolution_reason, unresolved_levels

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
        self.t0 = time.perf_counter()
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
        self._sections: dict | None = None  # see sections
        self.states: list[np.ndarray] = []  # recorded states not yet judged and stressed
        self.unstable: list[int | None] = []  # each point's surplus negative eigenvalues

    @property
    def sections(self) -> dict:
        """The system's flexure sections by name (read when the path is stressed)."""
        if self._sections is None:
            self._sections = {f.name: f.section for f in self.system.mechanism.flexures}
        return self._sections

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
        """Validity verdicts and section stresses of the states recorded since the last call."""
        if self.states:
            self.judged(*path_end_pass(self.system, self.states))

    def judged(
        self,
        verdicts: Sequence[list[str]],
        forces: Sequence[tuple[Connector, SectionForces | None]],
    ) -> None:
        """Record the verdicts and section forces of the states recorded since the last
        judgement, as :func:`path_end_pass` gives them."""
        self._verdicts(verdicts)
        record_path_stress(self.path, forces, self.sections)
        if self.path.shapes is not None:
            append_section_forces(self.path, forces)
        self.states = []

    def _verdicts(self, verdicts: Sequence[list[str]]) -> None:
        """Append the validity monitor's reasons at each level (empty: valid)."""
        valid, validity = _validity(verdicts)
        self.path.valid.extend(valid)
        self.path.validity.extend(validity)

    def finish(self) -> LoadPath:
        """The path of a successful trace (wall time from the recorder's creation)."""
        self._judge()
        note_stability(self.path, self.system)
        note_unstable_points(self.path, self.unstable)
        note_resolution(self.path, self.system.size, carries_weights(self.system.connectors))
        self.path.converged = True
        self.path.seconds = time.perf_counter() - self.t0
        return self.path

    def failure(self, exc: TraceFailure) -> SolverError:
        """The SolverError for a failed trace, carrying the path so far."""
        self._judge()
        note_stability(self.path, self.system)
        note_unstable_points(self.path, self.unstable)
        note_resolution(self.path, self.system.size, carries_weights(self.system.connectors))
        return failed_path(self.path, self.case, self.model, exc, time.perf_counter() - self.t0)

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


def path_end_pass(
    system: System, states: Sequence[np.ndarray]
) -> tuple[list[list[str]], list[tuple[Connector, SectionForces | None]]]:
    """The validity monitor's reasons at each state and every connector's stacked section forces.

    The reasons are those :meth:`System.validity` gives at each state
    (prefixed with the connector's name, connectors in order); the section
    forces (k, m) per connector, None for one without (pins). Each group of
    connectors computes both for all the states in one call
    (:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.path_end_pass`, given its
    coordinates at every state: :meth:`System.group_coordinates`).
    """
    reasons: list[list[str]] = [[] for _ in states]
    forces = []
    for (group, _), coordinates in zip(system.groups, system.group_coordinates(states)):
        verdicts, stacked = group.path_end_pass(coordinates)
        for c, per_level in zip(group.connectors, verdicts):
            for found, why in zip(reasons, per_level):
                if why:
                    found.extend(f"{c.name}: {w}" for w in why)
        forces += zip(group.connectors, stacked)
    return reasons, forces


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


def record_stress(
    path: LoadPath, connectors, forces, sections: dict, scales: Sequence[float] = (1.0,)
) -> None:
    """Append each flexure's peak outer-fibre stress (MPa) at one state, scaled, to ``path``.

    The linear response's form: one level is appended per entry of
    ``scales``, with the section forces times it (the load factors of a
    linear response, whose section forces are computed once). Connectors
    without section forces (None: pins) or without a section are skipped;
    the stress profile is kept for the last level only (``path.stress_profile``).

    Parameters
    ----------
    path : LoadPath
    connectors, forces :
        The system's connectors and their section forces (N, N mm) at the
        state (:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.section_forces`).
    sections : dict of flexure name -> Section
    scales : sequence of float
        The factors of the levels to append.
    """
    named = []
    for c, found in zip(connectors, forces):
        section = sections.get(c.name)
        if section is not None and found is not None:
            named.append((c.name, found, section))
    if len(named) < STACK_FROM:  # a path's few flexures: each alone
        factors = [abs(f) for f in np.asarray(scales, float).tolist()]
        append_stresses(
            path,
            ((name, _state_peak(found, section, factors)) for name, found, section in named),
        )
        return
    peaks = state_peaks([(found, section) for _, found, section in named], scales)
    append_stresses(path, ((name, found) for (name, _, _), found in zip(named, peaks)))


def record_path_stress(
    path: LoadPath, forces: Sequence[tuple[Connector, SectionForces | None]], sections: dict
) -> None:
    """Append each flexure's peak outer-fibre stress (MPa) and its place at several levels.

    ``forces`` pairs each connector with its section forces stacked over the
    levels (:func:`path_end_pass`); connectors without section forces (pins)
    or without a section are skipped, and the stress profile is kept for the
    last level (``path.stress_profile``).

    Parameters
    ----------
    path : LoadPath
    forces : sequence of (Connector, SectionForces or None)
        Section forces (N, N mm), (k, m) each, in the order of the levels.
    sections : dict of flexure name -> Section
    """
    named = []
    for c, stacked in forces:
        section = sections.get(c.name)
        if section is not None and stacked is not None:
            named.append((c.name, stacked, section))
    if len(named) < STACK_FROM:  # a path's few flexures: each alone
        append_stresses(
            path, ((name, _path_peak(stacked, section)) for name, stacked, section in named)
        )
        return
    found = path_peaks([(stacked, section) for _, stacked, section in named])
    append_stresses(path, ((name, peaks) for (name, _, _), peaks in zip(named, found)))


class _Sections(NamedTuple):
    """Uniform sections of several flexures as arrays (c, 1, ...) (mm, mm^2, mm^4): what
    :meth:`SectionForces.fibre_stress` reads of one, so one call serves them all."""

    thickness: np.ndarray
    area: np.ndarray
    inertia: np.ndarray
    profile: None = None


Peaks = tuple[list[float], list[float], list[float], list[float]]
"""A flexure's peak stress at each level (MPa), its place (arc-length fraction from the first
end), the stations' fractions and the stress at each station at the last level (MPa)."""


STACK_FROM = 8
"""Least number of flexures with uniform sections and forces of one shape whose stresses
:func:`path_peaks` and :func:`state_peaks` compute stacked: below it (a path's own few
flexures) stacking them costs more than it saves."""
STACK_SIZE = 64
"""Most flexures in one stack of :func:`path_peaks` and :func:`state_peaks` (a linear batch's
flexures), so that a stack's forces, stresses and the temporaries between them stay in the
processor's caches (64 flexures of 11 levels and 17 stations, ``dcmm:1``'s: 96 kB per array)
instead of every pass going to memory. A ``dcmm:1`` batch of 1000 copies (open chain f+,
3000 flexures) spent 19.6 us per path in :func:`path_peaks` as one stack, 15 in stacks of
64 (32 to 128 alike within the machine's noise, 16 slower). A traced batch's stacks take
:func:`stack_peaks`' one compiled pass, without temporaries."""


def _fibre_stresses(
    entries: Sequence[tuple[SectionForces, Section]],
) -> tuple[list[int], list[tuple[list[int], np.ndarray, np.ndarray]]]:
    """The entries whose outer-fibre stress (MPa) is computed alone, and the stacks of the others.

    Entries with uniform sections and forces of one shape, at least
    :data:`STACK_FROM` of them, are stacked (their forces (c, ..., m),
    their sections as arrays), at most :data:`STACK_SIZE` to a stack, and each
    stack takes one call of :meth:`SectionForces.fibre_stress`, elementwise the
    arithmetic of each
    alone, so that a flexure's stress is the same whether it is computed with
    others (a batch's copies) or alone. Returns the indices of the entries
    left alone (a varying section, a few flexures) and, per stack, (the
    entries' indices, their stresses (c, ..., m), their stations (c, m)).
    """
    alone: list[int] = []
    alike: dict[tuple, list[int]] = {}  # uniform sections, by the forces' shape
    for j, (forces, section) in enumerate(entries):
        if section.profile is None:
            alike.setdefault(forces.axial.shape, []).append(j)
        else:
            alone.append(j)
    stacks = []
    constants: dict[int, tuple[float, float, float]] = {}  # a section's, read once
    for alike_members in alike.values():
        if len(alike_members) < STACK_FROM:
            alone += alike_members
            continue
        for first in range(0, len(alike_members), STACK_SIZE):
            members = alike_members[first : first + STACK_SIZE]
            stacks.append((members, *_stacked_stress([entries[j] for j in members], constants)))
    return alone, stacks


def _stacked_stress(
    chosen: list[tuple[SectionForces, Section]], constants: dict[int, tuple[float, float, float]]
) -> tuple[np.ndarray, np.ndarray]:
    """The outer-fibre stresses (c, ..., m) (MPa) and stations (c, m) of uniform sections'
    forces of one shape, stacked: :meth:`SectionForces.fibre_stress` elementwise, each as
    alone; ``constants`` keeps each section's h, A and I by id."""
    at = np.array([f.at for f, _ in chosen])
    axial = np.array([f.axial for f, _ in chosen])  # np.array of equal shapes: np.stack's copy,
    moment = np.array([f.moment for f, _ in chosen])  # at a third the cost
    values = section_constants([s for _, s in chosen], constants)
    shape = (-1, *[1] * (axial.ndim - 1))  # each section's constants against its forces
    stacked = _Sections(*(values[:, k].reshape(shape) for k in range(3)))
    return SectionForces(at, axial, moment).fibre_stress(stacked), at


def section_constants(
    sections: Sequence[Section], known: dict[int, tuple[float, float, float]] | None = None
) -> np.ndarray:
    """Uniform sections' thickness (mm), area (mm^2) and second moment (mm^4), (c, 3);
    ``known`` keeps each section's by id (sections repeat among a batch's copies)."""
    known = {} if known is None else known
    for s in sections:
        if id(s) not in known:
            known[id(s)] = (s.thickness, s.area, s.inertia)
    return np.array([known[id(s)] for s in sections], float).reshape(-1, 3)


def _unit_peaks(unit: np.ndarray, at: np.ndarray) -> list[Peaks]:
    """:data:`Peaks` of stacked stresses ``unit`` (c, k, m) (MPa) at stations ``at`` (c, m)."""
    places = np.take_along_axis(at, unit.argmax(axis=2), axis=1)
    return list(zip(unit.max(axis=2).tolist(), places.tolist(), at.tolist(), unit[:, -1].tolist()))


def path_peaks(entries: Sequence[tuple[SectionForces, Section]]) -> list[Peaks]:
    """Each flexure's peak outer-fibre stress at every level, its place and its last profile.

    Many flexures at once (:func:`_fibre_stresses`: a batch's copies), each as alone.

    Parameters
    ----------
    entries : sequence of (SectionForces, Section)
        Section forces (N, N mm) stacked over k levels, (k, m) each, and the
        flexure's section.

    Returns
    -------
    list of :data:`Peaks`
        Per entry, plain lists.
    """
    out: list = [None] * len(entries)
    alone, stacks = _fibre_stresses(entries)
    for j in alone:
        out[j] = _path_peak(*entries[j])
    for members, unit, at in stacks:  # unit (c, k, m)
        for j, peaks in zip(members, _unit_peaks(unit, at)):
            out[j] = peaks
    return out


@cache
def stress_kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.stresskernel`, imported and loaded on first use (numba is
    imported only by the runs that stack stresses: a batch's)."""
    from ..kernels import stresskernel

    stresskernel.warm_up()
    return stresskernel


def stack_peaks(stack: ForceStack, constants: np.ndarray) -> list[Peaks]:
    """:func:`path_peaks` of a stack's members (forces (g, k, m)) with uniform sections, whose
    :func:`section_constants` are ``constants`` (g, 3): the same numbers, from one compiled
    pass (:func:`flexval.reducedmodels.kernels.stresskernel.stack_peaks`) without a
    :class:`SectionForces` per member."""
    count, levels, stations = stack.axial.shape
    peaks, places = np.empty((count, levels)), np.empty((count, levels))
    profile = np.empty((count, stations))
    at = np.ascontiguousarray(stack.at, float)
    stress_kernels().stack_peaks(
        at,
        stack.axial,
        stack.moment,
        np.ascontiguousarray(constants, float),
        peaks,
        places,
        profile,
    )
    stations_of = np.broadcast_to(at, (count, stations)).tolist()
    return list(zip(peaks.tolist(), places.tolist(), stations_of, profile.tolist()))


def _path_peak(forces: SectionForces, section: Section) -> Peaks:
    """:func:`path_peaks` of one flexure alone (forces (k, m))."""
    unit = forces.fibre_stress(section)
    return (
        unit.max(axis=1).tolist(),
        forces.at[unit.argmax(axis=1)].tolist(),
        forces.at.tolist(),
        unit[-1].tolist(),
    )


def _state_peak(forces: SectionForces, section: Section, factors: list[float]) -> Peaks:
    """:func:`state_peaks` of one flexure alone (forces (m,); ``factors`` the scales' sizes)."""
    unit = forces.fibre_stress(section)
    peak = int(np.argmax(unit))
    top = float(unit[peak])  # plain floats: one product per level
    return (
        [f * top for f in factors],
        [float(forces.at[peak])] * len(factors),
        forces.at.tolist(),
        (factors[-1] * unit).tolist(),
    )


def state_peaks(
    entries: Sequence[tuple[SectionForces, Section]], scales: Sequence[float] = (1.0,)
) -> list[Peaks]:
    """Each flexure's peak outer-fibre stress at one state, scaled to several levels.

    The linear response's form (:func:`record_stress`): the stress at the
    state times each entry of ``scales`` in size (MPa), its place at every
    level, the stations and the profile at the last level. Many flexures at
    once (:func:`_fibre_stresses`), each as alone.

    Parameters
    ----------
    entries : sequence of (SectionForces, Section)
        Section forces (N, N mm) at the state, (m,) each, and the flexure's section.
    scales : sequence of float
        The factors of the levels.
    """
    factors = [abs(f) for f in np.asarray(scales, float).tolist()]
    out: list = [None] * len(entries)
    alone, stacks = _fibre_stresses(entries)
    for j in alone:
        out[j] = _state_peak(*entries[j], factors)
    for members, unit, at in stacks:  # unit (c, m)
        rows = np.arange(len(members))
        peak = unit.argmax(axis=1)
        tops, places = unit[rows, peak].tolist(), at[rows, peak].tolist()
        profiles = (factors[-1] * unit).tolist()
        for j, top, place, station, profile in zip(members, tops, places, at.tolist(), profiles):
            out[j] = ([f * top for f in factors], [place] * len(factors), station, profile)
    return out


def append_stresses(path: LoadPath, found: Iterable[tuple[str, Peaks]]) -> None:
    """Append each named flexure's peak stresses (MPa) and their places (:data:`Peaks`, as
    :func:`path_peaks` gives them: lists of its own, which a flexure's first levels become);
    its profile replaces the last one."""
    if path.peak_stress is None:
        path.peak_stress, path.peak_stress_at, path.stress_profile = {}, {}, {}
    stresses, places_of, profiles = path.peak_stress, path.peak_stress_at, path.stress_profile
    for name, (peaks, places, at, profile) in found:
        so_far = stresses.get(name)
        if so_far is None:  # the flexure's first levels
            stresses[name], places_of[name] = peaks, places
        else:
            so_far.extend(peaks)
            places_of[name].extend(places)
        profiles[name] = {"at": at, "stress": profile}


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
