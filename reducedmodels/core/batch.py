"""Many copies of one mechanism and model traced together: a batch.

A design study runs the same mechanism topology with the same model
thousands of times, with other dimensions and loads. Traced one by one,
each path pays the per-call costs of the core (Python, LAPACK's checks,
numpy's small-array overheads) at every Newton iteration; a 9-unknown
``dcmm:1`` path costs far more than its arithmetic.
:class:`~flexval.reducedmodels.core.batchsystem.BatchSystem` puts N copies
side by side in one :class:`~flexval.reducedmodels.core.system.System` (one
compiled assembly per connector group, one block-diagonal factorisation), and
:func:`trace_batch` steps them together through the one tracer
(:func:`flexval.reducedmodels.core.tracer.trace`) with the one Newton iteration
applied to every copy at once (:func:`flexval.reducedmodels.core.newton.solve`).

Each copy stays what it is alone: every Newton test and every decision of load
control is made per copy; where copies disagree, the minority goes on as a
batch of its own from the last reported level they shared (:data:`DEAD_WEIGHT`
sheds the copies that left); a batch that cannot go on hands its copies to runs
alone from rest; copies of more than :data:`SOLO_UNKNOWNS` unknowns are traced
one by one. A copy's path is its solo run's up to round-off (over the built-in
scenes' reduced-model paths, end values within 1.6e-11 of the mechanism's size),
and the same bit for bit in a batch of any size. The rules in full are in
ARCHITECTURE.md, "The core".

Units: mm, N, N mm, rad; times in s.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import NamedTuple

import numpy as np

from flexval.geometry import LoadCase, Mechanism, SceneError

from ..kernels.clock import path_clock
from .allocator import keep_freed_memory
from .batchsystem import BatchSystem, Member, copy_parts, copy_unknowns
from .linearbatch import linear_responses
from .loadpath import LoadPath
from .recorder import record_batch
from .settings import SolverError
from .system import System
from .tracer import Counters, LoadControl, PathPoint, TraceFailure, trace

BATCH_UNKNOWNS = 40_000
"""Most unknowns of one batch (larger sets of copies are traced as several): the band of a
batch this size, some 10 MB with the factor, stays in the processor's caches; beyond it the
cost per path grows (``benchmarks/bench_batch.py --n N`` measures it for N copies)."""


SOLO_UNKNOWNS = 500
"""Most unknowns of a copy that :func:`run_batch` traces in a batch with others (copies with
more are traced one by one, each by its family's own runner): a copy's own band is then wide
enough that sharing the iteration saves little, and copies that part ways cost more than
that: beam:100 (900 unknowns) runs slower batched than alone once its copies part ways,
beam:20 (180 unknowns) still faster (``benchmarks/bench_batch.py --spread 0.02``)."""


@contextmanager
def collection_paused() -> Iterator[None]:
    """Python's cyclic garbage collector paused within the block (as it was, after it).

    A batch creates some ten small objects per copy and level (renamed
    connectors, numbering maps, each path's lists and dicts); every 700 of
    them start a collection, which scans all the batch's live objects as they
    age: a third of a ``dcmm:1`` batch's time (1000 copies, open chain f+,
    measured). Reference counting still frees what a batch drops; cycles
    wait for the next collection after the block.
    """
    paused = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if paused:
            gc.enable()


class _Start(NamedTuple):
    """A reported point of a batch where some of its copies go on as a batch of their own."""

    batch: BatchSystem
    all_points: list[PathPoint]
    carried: dict
    count: int
    positions: list[int]
    """The copies' places in ``batch``, in the order of the new batch."""

    def take(self, batch: BatchSystem) -> np.ndarray:
        """The index, in the old batch's numbering, of each unknown of ``batch``."""
        take = np.empty(batch.n_dofs, np.int64)
        for dofs, j in zip(batch.copy_dofs, self.positions):
            take[dofs] = self.batch.copy_dofs[j]
        return take

    def points(self, take: np.ndarray) -> list[PathPoint]:
        """The points up to the start, in the new batch's numbering (as its own would be)."""
        n, chosen = self.batch.n_copies, self.positions
        return [
            PathPoint(
                p.state[take],
                p.factor,
                np.broadcast_to(p.iterations, (n,))[chosen],
                None,
                p.step,
                Counters(
                    np.broadcast_to(p.counters.newton_iterations, (n,))[chosen],
                    p.counters.step_cuts,
                    p.counters.substeps,
                ),
                p.bifurcations,
            )
            for p in self.all_points[: self.count]
        ]


class _Group(NamedTuple):
    """Copies to trace as one batch: from rest, or from where they left another batch."""

    copies: list[int]
    start: _Start | None = None


DEAD_WEIGHT = 0.25
"""Share of a batch's copies that may have left it before the rest go on as a new batch (from
the point just reached), for copies of at least :data:`REBUILD_UNKNOWNS` unknowns: a copy that
left still takes its place in every assembly and factorisation of its batch, while a new
batch costs its build once."""
REBUILD_UNKNOWNS = 16
"""Fewest unknowns of a copy for which a batch sheds the copies that left it
(:data:`DEAD_WEIGHT`): below, a dead copy's share of an iteration costs less than building
the new batch: shedding cost dcmm:1 (9 unknowns) and dcmm:2 (18) time and saved prbm (21),
dcmm:3 (27) and beam:20 (180) some (``benchmarks/bench_batch.py --spread 0.02``)."""


def _dead_weight(active: np.ndarray, unknowns: int) -> bool:
    """Whether a batch of copies of ``unknowns`` unknowns, ``active`` still in it, carries too
    many that left (:data:`DEAD_WEIGHT`, :data:`REBUILD_UNKNOWNS`)."""
    dead = active.size - int(np.count_nonzero(active))
    return (
        unknowns >= REBUILD_UNKNOWNS
        and 0 < dead < active.size
        and dead >= DEAD_WEIGHT * active.size
    )


@collection_paused()
def trace_batch(
    members: Sequence[System | Member],
    cases: Sequence[LoadCase],
    levels: int | None = None,
    model: str = "",
    scene: str = "",
    settings: dict | None = None,
) -> list[LoadPath | SolverError]:
    """The load-control paths of many copies, traced together where they agree.

    Parameters
    ----------
    members : sequence of System or (Mechanism, connectors)
        The copies (see :class:`BatchSystem`).
    cases : sequence of LoadCase
        Each copy's load case; all must request the same load factors
        (``levels`` equal steps, default each case's own).
    levels, model, scene, settings :
        As for :func:`flexval.reducedmodels.core.recorder.solve_path`.

    Returns
    -------
    list of LoadPath or SolverError
        Per copy, in order: its path, or the error its solo run raises. The
        copies that leave a batch by a vote go on together as a batch of
        their own from the last reported level they shared; the copies of a
        batch that cannot go on are each traced alone from rest. Every copy
        is traced by the batch's arithmetic, so its
        path does not depend on which copies it was traced with (a sweep
        gives the same rows whatever its task sizes). Each path's
        ``seconds`` is its share of the wall time of every batch it was
        traced in (a batch's time split evenly among its copies, so the
        paths' seconds add up to the whole), ``stats["batch"]`` the number
        of copies its last batch recorded.
    """
    keep_freed_memory()
    distinct = {id(case): case for case in cases}.values()  # each case once
    factors = [case.factors(levels) for case in distinct]
    if any(not np.array_equal(f, factors[0]) for f in factors):
        raise ValueError("the copies' load cases request different load factors")
    size = max(1, BATCH_UNKNOWNS // max(copy_unknowns(members[0]), 1)) if members else 1
    if len(members) > size:
        return [
            path
            for start in range(0, len(members), size)
            for path in trace_batch(
                members[start : start + size],
                cases[start : start + size],
                levels,
                model,
                scene,
                settings,
            )
        ]
    results: list[LoadPath | SolverError | None] = [None] * len(members)
    groups = [_Group(list(range(len(members))))]  # copies to trace as one batch, in turn
    spent = np.zeros(len(members))  # each copy's share of the batches it was traced in, s
    known_loads: dict = {}  # each copy's loads in its own numbering, for all its batches
    while groups:
        group = groups.pop(0)
        copies = group.copies
        t0 = path_clock()
        batch = BatchSystem([members[k] for k in copies])
        loads = batch.use_loads([cases[k] for k in copies], known_loads)
        stepping = LoadControl(factors[0], batch)
        unknowns = batch.n_dofs // len(copies)
        points: list[PathPoint] = []
        shared: list[tuple[dict, int]] = []  # at each point: load control's snapshot, points
        resume = None
        if group.start is not None:  # go on from the point where these copies left a batch
            take = group.start.take(batch)
            points = group.start.points(take)
            stepping.resume(group.start.carried, take, loads)
            shared.append((stepping.snapshot(), len(points)))
            resume = points[-1].counters
        left_at = np.full(len(copies), -1)  # the snapshot each copy that left goes on from
        active = stepping.active.copy()
        failure = None
        try:
            for point in trace(batch, loads, stepping, stepping.newton, resume):
                left_at[active & ~stepping.active] = len(shared) - 1
                points.append(point)
                shared.append((stepping.snapshot(), len(points)))
                active = stepping.active.copy()
                if not stepping.finished() and _dead_weight(active, unknowns):
                    left_at[active] = len(shared) - 1  # the rest go on without the dead weight
                    stepping.leave(active)
                    active[:] = False
                    break
        except TraceFailure as exc:
            failure = exc
        left_at[active & ~stepping.active] = len(shared) - 1
        group_cases = [cases[k] for k in copies]
        if failure is not None and (len(copies) > 1 or group.start is not None):
            # each copy alone from rest: its own way to fail, as its solo run meets it
            spent[copies] += (path_clock() - t0) / len(copies)
            groups += [_Group([k]) for k in copies]
            continue
        kept = [0] if failure is not None else np.flatnonzero(stepping.active).tolist()
        paths = record_batch(batch, points, kept, group_cases, model, scene, settings, failure)
        spent[copies] += (path_clock() - t0) / len(copies)
        seconds = spent[copies].tolist()
        for j, path in zip(kept, paths):
            recorded = path.path if isinstance(path, SolverError) else path
            recorded.seconds = seconds[j]
            recorded.stats["batch"] = len(kept)
            results[copies[j]] = path
        for where in np.unique(left_at[~stepping.active]).tolist():
            gone = np.flatnonzero(~stepping.active & (left_at == where)).tolist()
            gone = [j for j in gone if results[copies[j]] is None]
            if where < 0:  # their first solve failed: each from rest, alone
                groups += [_Group([copies[j]]) for j in gone]
            elif gone:  # on together from the last point they shared
                start = _Start(batch, points, *shared[where], gone)
                groups.append(_Group([copies[j] for j in gone], start))
    return results


RUN_FAILURES = (
    SolverError,
    SceneError,
    ArithmeticError,
    ValueError,
    RuntimeError,
    np.linalg.LinAlgError,
)
"""What a model's run may raise for one copy and :func:`run_batch` returns as its result: the
solver's failure, a flexure the model cannot represent, a state or a tangent it cannot handle."""


@collection_paused()
def run_batch(
    mechanisms: Sequence[Mechanism],
    spec,
    cases: Sequence[LoadCase],
    levels: int | None = None,
    scene: str = "",
) -> list[LoadPath | Exception]:
    """Every copy's load path with the model ``spec``: its own mechanism and load case.

    A family that builds a System and traces it by load control (beams,
    DCMM, PRBM, the continuum) runs as :func:`trace_batch`; a linear family
    that builds connectors (``ee``: its path is the linear response of its
    connectors at rest) as
    :func:`~flexval.reducedmodels.core.linearbatch.linear_responses`, every copy's
    small solve and outputs at once; another linear family copy by copy
    through its own runner, and so does every copy of a batch whose cases
    prescribe a motion (displacement control). Copies given the same mechanism
    object share its connectors (built once). Each path's ``seconds`` includes its share of
    building the connectors.

    Parameters
    ----------
    mechanisms : sequence of Mechanism
        One per copy, all of one topology (bodies, flexures and pins alike).
    spec : ModelSpec
        The model (see :func:`flexval.reducedmodels.catalogue.parse_model`).
    cases : sequence of LoadCase
        One per copy, requesting the same load factors.
    levels, scene :
        As for the family's runner.

    Returns
    -------
    list of LoadPath or Exception
        Per copy, in order: its path, or what its solo run raises (one of
        :data:`RUN_FAILURES`: a copy the model cannot build, a solver
        failure). Copies are grouped by topology (bodies, connectors and
        their sizes, load factors), each group traced as its own batches.
    """
    from ..catalogue import LINEAR

    keep_freed_memory()
    family = spec.model_family
    results: list[LoadPath | Exception | None] = [None] * len(mechanisms)

    def alone(k: int) -> None:
        try:
            path = family.trace(mechanisms[k], spec, cases[k], levels=levels, scene=scene)
        except RUN_FAILURES as exc:
            results[k] = exc
            return
        path.stats["batch"] = 1
        results[k] = path

    linear = family.has(LINEAR)
    driven = any(case.drive is not None for case in cases)  # a prescribed motion: each alone
    if family.system is None or (linear and family.connectors is None) or driven:
        for k in range(len(mechanisms)):
            alone(k)
        return results
    t0 = path_clock()
    options = dict(spec.kwargs)
    built: dict[int, System | Member | Exception] = {}  # copies of one mechanism share it
    for m in mechanisms:
        if id(m) in built:
            continue
        try:
            built[id(m)] = (
                family.system(m, spec, None, **options)
                if family.connectors is None
                else (m, family.connectors(m, spec, **options))
            )
        except RUN_FAILURES as exc:
            built[id(m)] = exc
        member = built[id(m)]
        if (
            not linear
            and not isinstance(member, Exception)
            and copy_unknowns(member) > SOLO_UNKNOWNS
        ):
            for k in range(len(mechanisms)):  # copies this large: each alone (SOLO_UNKNOWNS)
                alone(k)
            return results
    for k, m in enumerate(mechanisms):
        if isinstance(built[id(m)], Exception):
            results[k] = built[id(m)]
    build = (path_clock() - t0) / max(len(mechanisms), 1)
    groups: dict[tuple, list[int]] = {}  # copies that can share a batch, in order
    keys: dict[tuple[int, int], tuple] = {}
    for k in range(len(mechanisms)):
        if results[k] is None:
            member = built[id(mechanisms[k])]
            at = (id(member), id(cases[k]))  # copies of one mechanism and case share a key
            if at not in keys:
                keys[at] = _topology(member, cases[k].factors(levels))
            groups.setdefault(keys[at], []).append(k)
    for todo in groups.values():
        members = [built[id(mechanisms[k])] for k in todo]
        try:
            if linear:
                traced = linear_responses(members, [cases[k] for k in todo], levels, spec.id, scene)
                for path in traced:
                    if isinstance(path, LoadPath):
                        path.stats["batch"] = len(todo)
            else:
                traced = trace_batch(
                    members, [cases[k] for k in todo], levels, spec.id, scene, options
                )
        except RUN_FAILURES:  # a batch it cannot trace: each copy alone
            for k in todo:
                alone(k)
            continue
        for k, result in zip(todo, traced):
            if isinstance(result, LoadPath):
                result.seconds += build
            results[k] = result
    return results


def _topology(member: System | Member, factors: np.ndarray) -> tuple:
    """What copies must share to be one batch (:meth:`BatchSystem._check`) and to be traced
    through the same load factors: a key that groups the copies of a sweep's block whose
    flexures change kind, or whose meshes change size, into batches of their own."""
    mechanism, connectors = copy_parts(member)
    ground = mechanism.ground
    return (
        tuple(mechanism.bodies),
        ground,
        tuple(mechanism.bodies[ground].reference.tolist()),
        tuple((type(c), c.bodies, c.n_internal) for c in connectors),
        tuple(np.asarray(factors, float).tolist()),
    )
