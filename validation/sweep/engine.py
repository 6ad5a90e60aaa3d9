"""Run a sweep on a Dask cluster; the workers write the Parquet parts, the driver publishes them.

Tasks are whole runs of one model on a block of points (every load case of
the sweep). The driver sends *parameter blocks*, not scenes
(:class:`~flexval.validation.sweep.tasks.PointBlock`: indices, axis values and
scene digests); each worker builds the scenes from the sweep's base scene data
and writes its rows as a staged part, which the driver renames into the
dataset once it has counted the task. The points are taken block by block, at
most :data:`BLOCKS_IN_FLIGHT` blocks at a time, so the driver holds a few
blocks of parameters, whatever the point count, and no scene at all.

Task sizes follow the measured cost: the first tasks of each model hold
:func:`auto_batch` points; the CPU seconds the tasks report for their points then
size the later ones to :data:`TASK_SECONDS` of work (:func:`task_points`). A
sweep's ``batch`` fixes the size; a reference-class (costly) model runs one
point a task. The reference runs once per point in its own tasks (on the
``reference_sample`` points only, when the sweep gives one:
:func:`reference_positions`); a model task receives the reference paths of its
points from Dask. Behind a cheap reference, every model's tasks hold the points
of one reference task (the reference's size), and with work stealing off
(:data:`WORK_STEALING`) they run on its worker, which has built their scenes
already; each task runs its model on its points as one batch
(:func:`~flexval.validation.sweep.tasks.run_model_block`).

Resuming: every row's key hashes the point's scene, the model, the load
case, the reference, the code version and the optional outputs; a (point,
model) pair whose rows are all stored already is not run again, and the
summary reads only the rows of the current keys (:func:`current_keys`),
never those a sweep left under an older code version. After a run, those are the
keys the run wrote and found (:meth:`SweepStats.current_keys`: the workers
return their rows' keys), so the driver does not hash every point again and
reads the rows back as Arrow columns (:class:`~flexval.validation.sweep.columns.Columns`),
making dicts only of the rows the summary lists one by one. A task that raises
even after Dask's retries (a worker that keeps dying) becomes rows with
status ``error``: the sweep goes on.

Units: times in s.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexval.reducedmodels.catalogue import REFERENCE

from ..cache import code_version
from .columns import Columns
from .points import Point
from .spec import Sweep
from .store import ResultStore
from .tasks import (
    PointBlock,
    SweepJob,
    TaskInfo,
    base_row,
    model_task,
    reference_task,
    row_key,
    summary_of,
)

RETRIES = 2
"""Times Dask reruns a task whose worker died before it finished."""
MESSAGE_LOG_LENGTH = 10
"""Recent messages Dask keeps per connection (``distributed.admin.low-level-log-length``,
1000 by default) in a local cluster: each message to a worker holds its task's arguments, so
a thousand held 470 MB of scenes in a driver that sent scenes (20,000 points)."""
WORK_STEALING = False
"""Dask's work stealing, off: a model task then runs on the worker that holds its block's
reference paths (and its points' scenes, built there by the reference's task), instead of
being moved to an idle worker that fetches the paths and builds every scene again."""
BLAS_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
"""Worker environment of the local cluster: one BLAS thread per single-threaded worker."""


@dataclass
class SweepStats:
    """What one call of :func:`run_sweep` did."""

    tasks: int = 0
    rows_written: int = 0
    rows_failed: int = 0
    rows_skipped: int = 0
    seconds: float = 0.0
    parts: list = field(default_factory=list)
    task_points: dict = field(default_factory=dict)
    """Model id: the points of its largest task."""
    keys: list = field(default_factory=list)
    """Arrays of row keys (24-byte strings): the rows this call wrote and the stored rows
    it found current (see :meth:`current_keys`)."""

    def current_keys(self) -> np.ndarray:
        """The keys of every stored row of the sweep under the current code, sorted: those
        :func:`current_keys` gives of the stored rows, known from the run without hashing a
        point again."""
        if not self.keys:
            return np.empty(0, dtype="S24")
        return np.unique(np.concatenate(self.keys).astype("S24"))


def chunks(points: list, size: int) -> Iterator[list]:
    """``points`` in consecutive runs of ``size`` (the last may be shorter)."""
    for k in range(0, len(points), size):
        yield points[k : k + size]


MAX_AUTO_BATCH = 25
"""Most points per task of a reduced model before its cost is measured (:func:`auto_batch`):
about 0.1 s of work for an open-chain point and load case of beam:20, less for the others, so
the first tasks are short and report the cost soon."""
TASKS_PER_WORKER = 4
"""Fewest tasks per worker and model that the task sizes aim at: the last tasks of a
sweep leave workers idle, the less the smaller the tasks."""
TASK_SECONDS = 1.0
"""Work per task, CPU s, that :func:`task_points` aims at once a model's cost is measured
(the CPU time of the tasks' own thread: on cores shared with other jobs the wall time of the
same work is longer, and tasks sized by it came out two to four times smaller, each paying
again the batch's set-up and its Parquet part). Dask's cost per task and the driver's
(publishing the part, the progress line) are under 1 % of a second's work, so one driver
keeps pace with a hundred workers (``benchmarks/bench_sweep.py`` measures both); an
interruption or the sweep's last task leaves a worker idle for about this long at most."""
MAX_TASK_POINTS = 5000
"""Most points per task, whatever their cost: bounds a task's rows (about 4 kB each in the
worker's memory) and the reference paths one task hands to the model tasks."""


def auto_batch(points: int, workers: int) -> int:
    """Points per reduced-model task before its cost is measured: enough tasks for
    :data:`TASKS_PER_WORKER` per worker and model, at most :data:`MAX_AUTO_BATCH` points each."""
    return max(1, min(MAX_AUTO_BATCH, points // (TASKS_PER_WORKER * max(workers, 1))))


def task_points(
    seconds_per_point: float | None, remaining: int, workers: int, fixed: int | None = None
) -> int:
    """Points per task of a model: ``fixed`` if the sweep gives it; before any task of the
    model finished (``seconds_per_point`` None) :func:`auto_batch` of the ``remaining``
    points; then enough for :data:`TASK_SECONDS` of work, at most :data:`MAX_TASK_POINTS`,
    and few enough that the remaining points still make :data:`TASKS_PER_WORKER` tasks per
    worker (short tasks at the end: the workers finish together)."""
    if fixed:
        return fixed
    if seconds_per_point is None:
        return auto_batch(remaining, workers)
    sized = int(TASK_SECONDS / max(seconds_per_point, 1e-9))
    tail = remaining // (TASKS_PER_WORKER * max(workers, 1))
    return max(1, min(MAX_TASK_POINTS, sized, tail))


@dataclass
class TaskCost:
    """The CPU seconds and points of a model's finished tasks, and the cost of one more
    point (:meth:`per_point`): a task costs a fixed part (the batch's set-up, its Parquet
    part) and a part per point."""

    tasks: int = 0
    points: float = 0.0
    seconds: float = 0.0
    points2: float = 0.0
    products: float = 0.0
    smallest: float = math.inf
    largest: float = 0.0

    def add(self, points: int, seconds: float) -> None:
        """Count a finished task of ``points`` points that took ``seconds`` CPU s."""
        self.tasks += 1
        self.points += points
        self.seconds += seconds
        self.points2 += points * points
        self.products += points * seconds
        self.smallest = min(self.smallest, points)
        self.largest = max(self.largest, points)

    def per_point(self) -> float | None:
        """CPU s per point: the slope of the tasks' seconds against their points (least
        squares) once their sizes differ by a factor :data:`FIT_SPREAD`, else (or where the
        slope is not positive) their mean seconds per point, which counts the fixed part
        too; at most the mean. None before any task finished."""
        if not self.points:
            return None
        mean = self.seconds / self.points
        if self.largest < FIT_SPREAD * self.smallest:
            return mean
        n = self.tasks
        slope = (n * self.products - self.points * self.seconds) / (
            n * self.points2 - self.points**2
        )
        return min(slope, mean) if slope > 0.0 else mean


FIT_SPREAD = 2.0
"""Ratio of the largest to the smallest task of a model from which :meth:`TaskCost.per_point`
fits the fixed part apart: the first tasks of :func:`auto_batch` points cost mostly it."""


def task_info(sweep: Sweep) -> TaskInfo:
    """What every task of ``sweep`` shares (and its row keys hash)."""
    return TaskInfo(sweep.name, sweep.reference.id, code_version(), sweep.outputs)


def reference_positions(sweep: Sweep) -> np.ndarray | None:
    """The positions of the points the reference runs on, sorted: None for every point, or
    the sweep's ``reference_sample`` of them drawn without replacement, seeded by the seeds
    of its random axes (0 without any), so a rerun draws the same. The draw is among the
    valid points of a checked sweep; among all points of a lazy one (whose invalid points
    only the workers find), where a refused draw leaves the reference a point fewer."""
    k = sweep.reference_sample
    if k is None:
        return None
    points = sweep.points
    if points.checked:
        pool = np.array([n for n in range(len(points)) if points.reason(n) is None], dtype=np.int64)
    else:
        pool = np.arange(len(points), dtype=np.int64)
    if k >= len(pool):
        return None
    seeds = [a.seed for a in sweep.axes if a.random and a.seed is not None] or [0]
    return np.sort(np.random.default_rng(seeds).choice(pool, size=k, replace=False))


def current_keys(sweep: Sweep) -> set[str]:
    """The keys of every row ``sweep`` produces with the current code (from the points'
    records: no scene is built). A point of a lazy sweep not known to be invalid may be
    either: its invalid-point key and its models' keys are all current."""
    info = task_info(sweep)
    sample = reference_positions(sweep)
    sampled = None if sample is None else set(sample.tolist())
    checked = sweep.points.checked
    keys = set()
    for position, r in enumerate(sweep.points.records()):
        if r.reason is not None or not checked:
            keys.add(row_key(r.digest, "-", "-", info))
            if r.reason is not None:
                continue
        models = [s.id for s in sweep.models]
        if sampled is None or position in sampled:
            models.append(sweep.reference.id)
        keys.update(row_key(r.digest, m, c, info) for m in models for c in sweep.load_cases)
    return keys


START_METHOD = "forkserver"
"""How the local cluster starts its worker processes: forked from one server process that
imported :data:`WORKER_MODULES` once (and holds no other thread, so the fork is safe). A
worker then starts in milliseconds, with flexval's numerical stack loaded, and ends without
tearing an interpreter down; started by ``spawn`` (Dask's default), each worker is a fresh
interpreter that imports Dask and the modules its tasks need, and workers take about twice
as long to start and many times as long to end
(``benchmarks/bench_sweep.py --cluster-start``). Where the platform has no forkserver
(Windows), ``spawn``."""
WORKER_MODULES = (
    "distributed",
    "flexval.validation.sweep.tasks",
    "flexval.reducedmodels.models",
    "flexval.reducedmodels.core.tangent",
    "flexval.reducedmodels.beam.elements",
    "flexval.reducedmodels.dcmm.connector",
    "flexval.reducedmodels.prbm.connector",
    "flexval.validation.sweep.preload",
)
"""What the forkserver imports before it forks the workers: Dask's worker, the sweep's
tasks, the reduced models' modules, and the sweep's models' code and compiled kernels
(:mod:`flexval.validation.sweep.preload`; a module missing here is imported by the worker
that needs it)."""


QUIET_DASK = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.deploy.cluster-repr-interval": "5s",
}
"""Dask's periodic work in a local cluster, made rarer: the workers' statistical profiler
(every 10 ms, for a dashboard flexval does not serve), the event-loop ticks (20 ms), the
system and memory monitors (0.5 s and 0.1 s: the nannies run in the driver). These settings
cut an idle cluster's CPU use in the driver and in each worker several-fold."""


def sweep_models(sweep: Sweep) -> list[str]:
    """The ids of the models a sweep runs, its reference last (what its workers load)."""
    return [*(s.id for s in sweep.models), sweep.reference.id]


def local_cluster(workers: int | None = None, models: Sequence[str] = ()):
    """A LocalCluster of single-threaded worker processes (default: one per core), started
    by :data:`START_METHOD`; with a forkserver, the workers are forked with the code and
    compiled kernels of ``models`` (ids) loaded (:mod:`flexval.validation.sweep.preload`).

    Dask keeps :data:`MESSAGE_LOG_LENGTH` recent messages per connection, not a thousand.
    Dask's own log lines below ERROR are silenced: when other jobs share the cores,
    a close prints "Worker process still alive after 4.0 seconds, killing" for
    workers that had finished; a worker lost mid-task is a recorded failure row.
    """
    import logging
    import multiprocessing
    import os

    import dask
    from distributed import LocalCluster

    method = START_METHOD if START_METHOD in multiprocessing.get_all_start_methods() else "spawn"
    # the scheduler runs in this process: its logs of recent messages would hold the
    # arguments (points and scenes) of the last thousand tasks sent to each worker
    dask.config.set(
        {
            "distributed.admin.low-level-log-length": MESSAGE_LOG_LENGTH,
            "distributed.scheduler.work-stealing": WORK_STEALING,
            "distributed.worker.multiprocessing-method": method,
            **QUIET_DASK,
        }
    )
    if method == "forkserver":
        from multiprocessing import forkserver

        from distributed.utils import get_mp_context

        from .preload import MODELS_ENV, SEPARATOR

        # after Dask's own choice, which it makes once; used when the server first starts
        get_mp_context().set_forkserver_preload(list(WORKER_MODULES))
        before = os.environ.get(MODELS_ENV)
        os.environ[MODELS_ENV] = SEPARATOR.join(models)  # what the server's environment says
        try:
            forkserver.ensure_running()  # it loads them while this process starts the scheduler
        finally:
            if before is None:
                del os.environ[MODELS_ENV]
            else:
                os.environ[MODELS_ENV] = before
    n = workers or os.cpu_count() or 1
    return LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",  # its HTTP server on a free port: 8787 may be taken
        env=BLAS_ENV,
        silence_logs=logging.ERROR,
    )


def stop_workers_on_signals(client) -> None:
    """Make the workers of a local cluster end at once on SIGINT or SIGTERM, after removing
    their own temporary files (:func:`flexval.validation.interrupt.worker_signals`): a
    terminal's Ctrl-C reaches them too, and an interrupted sweep sends them SIGTERM."""
    from distributed.diagnostics.plugin import WorkerPlugin

    class WorkerSignals(WorkerPlugin):
        name = "flexval-worker-signals"

        def setup(self, worker) -> None:
            import threading

            from ..interrupt import worker_signals

            if threading.current_thread() is threading.main_thread():
                worker_signals()

    client.register_plugin(WorkerSignals())


class _Progress:
    """One line per finished task: tasks finished and submitted, runs (point and model) done
    or found stored, failed rows, and the ETA from the runs' mean rate."""

    def __init__(self, total: int, emit: Callable[[str], None] | None):
        self.total, self.emit = total, emit
        self.done = self.failed = self.runs = self.skipped = 0
        self.t0 = time.perf_counter()

    def update(self, failed_rows: int, runs: int, submitted: int) -> None:
        self.done += 1
        self.failed += failed_rows
        self.runs += runs
        if self.emit is None:
            return
        elapsed = time.perf_counter() - self.t0
        left = max(self.total - self.skipped - self.runs, 0)
        eta = elapsed / max(self.runs, 1) * left
        self.emit(
            f"sweep: {self.done}/{submitted} tasks, {self.runs + self.skipped:,}/{self.total:,} "
            f"runs, {self.failed} failed rows, {elapsed:.0f} s elapsed, ETA {eta:.0f} s"
        )


BLOCK_TASKS = TASKS_PER_WORKER
"""Points of one block of :func:`run_sweep`: this many of the largest task per worker."""
BLOCKS_IN_FLIGHT = 2
"""Blocks whose tasks are submitted and not all finished: the next block is made and
submitted when fewer remain, so the workers always have the next tasks queued while the
driver holds the parameters of at most this many blocks."""


@dataclass
class _Block:
    """A block of points in the driver: positions, parameters, digests and indices, which
    (point, spec) pairs run, the stored keys per point, and the reference futures its model
    tasks wait on (released with the block)."""

    positions: np.ndarray
    values: np.ndarray
    digests: list[str] | None
    """None for a lazy sweep with no stored row: its workers compute them."""
    indices: list[int]
    run: np.ndarray
    skip: list[frozenset]
    stored: int
    current: np.ndarray
    """The keys of its stored rows that the sweep gives under the current code."""
    refs: dict = field(default_factory=dict)
    open: int = 0
    rerun: int = 0
    """Points whose reference rows are stored but whose reference runs again (a model
    runs there, and needs it): counted as runs, not as stored, in the progress."""


def _make_block(sweep: Sweep, positions: np.ndarray, done: np.ndarray, sampled, info) -> _Block:
    """The block of ``positions``: parameters, digests, and the (point, spec) pairs to run
    given the stored keys ``done`` (a lazy sweep's point stored as invalid is left out)."""
    points, cases = sweep.points, sweep.load_cases
    specs = (sweep.reference, *sweep.models)
    builder = points.builder
    if builder is not None:
        values = builder.values(positions)
        indices = positions.tolist()
    else:
        built = [points[int(k)] for k in positions]
        values = np.array([[p.params[a.path] for a in sweep.axes] for p in built])
        values = values.reshape(len(positions), len(sweep.axes))
        indices = [p.index for p in built]
    if points.checked:
        digests = [points.digest(int(k)) for k in positions]
    elif done.size:
        digests = [builder.digest_of(v) for v in values]
    else:  # a lazy sweep's digests follow from the values: the workers compute them
        digests = None
    run = np.ones((len(positions), len(specs)), dtype=bool)
    skip = [frozenset()] * len(positions)
    current = []  # the stored keys the sweep gives now
    # the reference runs wherever a model runs (it gives the errors), on its sample only
    on_sample = np.ones(len(positions), bool) if sampled is None else np.isin(positions, sampled)
    if done.size:
        keep = []
        for i, d in enumerate(digests):
            if not points.checked:
                invalid = np.array([row_key(d, "-", "-", info)], "S24")
                if np.isin(invalid, done)[0]:
                    current.append(invalid)
                    continue  # a lazy sweep's point stored as invalid
            keys = np.array([[row_key(d, s.id, c, info) for c in cases] for s in specs], "S24")
            stored = np.isin(keys, done)
            run[i] = ~stored.all(axis=1)
            skip[i] = frozenset(k.decode() for k in keys[stored])
            current.append(keys[1:][stored[1:]])
            if on_sample[i]:
                current.append(keys[0][stored[0]])
            keep.append(i)
        positions, values, run, on_sample = (x[keep] for x in (positions, values, run, on_sample))
        digests, indices, skip = ([x[i] for i in keep] for x in (digests, indices, skip))
    # (digests are None only where nothing is stored: the loop above did not run)
    stored_refs = ~run[:, 0] & on_sample
    stored = int((~run[:, 1:]).sum() + stored_refs.sum())
    run[:, 0] = on_sample & run.any(axis=1)
    known = np.concatenate(current) if current else np.empty(0, dtype="S24")
    block = _Block(positions, values, digests, indices, run, skip, stored, known)
    block.rerun = int((stored_refs & run[:, 0]).sum())
    return block


def _point_blocks(sweep: Sweep, size: Callable[[], int]) -> Iterator[np.ndarray]:
    """The positions of the points to run, in consecutive runs of ``size()`` (asked anew for
    every block), without the points a checked sweep knows to be invalid."""
    points = sweep.points
    start = 0
    while start < len(points):
        stop = min(len(points), start + size())
        block = np.arange(start, stop, dtype=np.int64)
        if points.checked:
            block = block[[points.reason(int(k)) is None for k in block]]
        start = stop
        if len(block):
            yield block


def _task_block(blk: _Block, chunk: np.ndarray, j: int, sweep: Sweep) -> PointBlock:
    """The :class:`PointBlock` of the points ``chunk`` (positions in ``blk``) for spec ``j``:
    it owns the invalid-point row of a point whose first running spec it is."""
    first = blk.run.argmax(axis=1)
    built = None
    if sweep.points.builder is None:
        built = tuple(sweep.points[int(blk.positions[i])] for i in chunk)
    return PointBlock(
        tuple(blk.indices[i] for i in chunk),
        blk.values[chunk],
        None if blk.digests is None else tuple(blk.digests[i] for i in chunk),
        tuple(bool(first[i] == j) for i in chunk),
        frozenset().union(*(blk.skip[i] for i in chunk)),
        built,
    )


def _failed_task(
    blk: _Block, chunk: np.ndarray, model: str, exc: Exception, sweep: Sweep, info: TaskInfo
) -> list[dict]:
    """The ``error`` rows of a task that raised (not yet stored)."""
    reason = f"task failed: {type(exc).__name__}: {exc}"
    rows = []
    for i in chunk:
        params = dict(zip((a.path for a in sweep.axes), blk.values[i].tolist()))
        d = sweep.points.builder.digest_of(blk.values[i]) if blk.digests is None else blk.digests[i]
        point = Point(blk.indices[i], params, None, d)
        rows += [
            base_row(point, model, c, info) | {"status": "error", "reason": reason}
            for c in sweep.load_cases
        ]
    return [r for r in rows if not any(r["key"] in blk.skip[i] for i in chunk)]


def run_sweep(
    sweep: Sweep,
    out_dir: str | Path,
    client,
    use_cache: bool = True,
    progress: Callable[[str], None] | None = None,
) -> SweepStats:
    """Run what is missing of ``sweep`` on the Dask ``client``; rows go to ``out_dir/results``.

    The points are made and submitted block by block (:data:`BLOCK_TASKS` tasks per worker
    of the largest task), at most :data:`BLOCKS_IN_FLIGHT` blocks at a time: the driver holds
    the stored keys (24 bytes a row), the reasons of the invalid points and the parameters
    of those blocks; never a scene, nor the rows of a finished task.

    Parameters
    ----------
    sweep : Sweep
    out_dir : path
        Output folder; the Parquet dataset is its ``results`` sub-folder.
    client : distributed.Client
    use_cache : bool
        Let workers reuse cached converged paths of a costly reference.
    progress : callable, optional
        Called with a progress line after each finished task.
    """
    from distributed import as_completed

    t0 = time.perf_counter()
    store = results_store(sweep, out_dir)
    store.clear_staged()
    done = store.key_array()
    info = task_info(sweep)
    stats = SweepStats()
    cases = sweep.load_cases
    specs = (sweep.reference, *sweep.models)
    points = sweep.points
    builder = points.builder
    job = SweepJob(
        info,
        None if builder is None else builder.light(),
        tuple(a.path for a in sweep.axes),
        cases,
        str(store.folder),
    )
    sampled = reference_positions(sweep)

    fresh_invalid = []  # the invalid points a checking pass found: their rows, here
    for r in points.invalid_records():
        key = row_key(r.digest, "-", "-", info)
        if np.isin(key.encode(), done):
            stats.keys.append(np.array([key], dtype="S24"))
        else:
            point = Point(r.index, points.params(r.index), None, r.digest, r.reason)
            fresh_invalid.append(
                base_row(point, "-", "-", info) | {"status": "invalid_point", "reason": r.reason}
            )
    part = store.append(fresh_invalid)
    if part is not None:
        stats.parts.append(part)
    stats.rows_written += len(fresh_invalid)
    stats.keys.append(np.array([r["key"] for r in fresh_invalid], dtype="S24"))
    del fresh_invalid

    workers = max(sum(client.nthreads().values()), 1)
    costly = [spec.model_family.has(REFERENCE) for spec in specs]
    cost = [TaskCost() for _ in specs]  # the finished tasks, per spec
    taken = [0]  # points put in blocks so far

    def batch(j: int) -> int:
        if costly[j]:
            return 1
        return task_points(cost[j].per_point(), len(points) - taken[0], workers, sweep.batch)

    def measured() -> bool:
        """Whether every task size that follows a measured cost has one."""
        return all(costly[j] or sweep.batch or cost[j].tasks for j in range(len(specs)))

    sizes = [1] * len(specs)  # points per task of each spec in the block being made

    def block_size() -> int:
        sizes[:] = [batch(j) for j in range(len(specs))]
        if not costly[0]:  # a model's task then needs one reference task, on one worker
            sizes[1:] = [sizes[0]] * (len(specs) - 1)
        size = max(sizes) * workers * BLOCK_TASKS
        taken[0] += size
        return size

    n_ref = points.valid_count if sampled is None else len(sampled)
    bar = _Progress(points.valid_count * len(sweep.models) + n_ref, progress)

    def submit(blk: _Block) -> Iterator[tuple[object, int, np.ndarray]]:
        """Submit the tasks of ``blk``: (future, spec, positions in the block)."""
        bar.skipped += blk.stored - blk.rerun
        stats.rows_skipped += blk.stored * len(cases)
        for j, spec in enumerate(specs):
            todo = np.flatnonzero(blk.run[:, j])
            for chunk in chunks(todo, sizes[j]):
                block = _task_block(blk, chunk, j, sweep)
                if j == 0:
                    ref = client.submit(
                        reference_task, block, spec, job, use_cache, retries=RETRIES, pure=False
                    )
                    blk.refs.update((int(i), ref) for i in chunk)
                    fut = client.submit(summary_of, ref, pure=False)
                else:
                    mine = [blk.refs[i] for i in chunk.tolist() if i in blk.refs]
                    refs = list({id(f): f for f in mine}.values())
                    fut = client.submit(
                        model_task, block, spec, job, refs, retries=RETRIES, pure=False
                    )
                stats.tasks += 1
                stats.task_points[spec.id] = max(stats.task_points.get(spec.id, 0), len(chunk))
                yield fut, j, chunk

    tasks: dict = {}  # future: (block, spec, positions in the block)
    blocks: dict[int, _Block] = {}
    pending = enumerate(_point_blocks(sweep, block_size))
    finished = as_completed()

    def refill() -> None:
        # the next block waits for the first measured costs: sized by auto_batch again,
        # its tasks would be as small as the first block's
        while len(blocks) < BLOCKS_IN_FLIGHT and (not blocks or measured()):
            nxt = next(pending, None)
            if nxt is None:
                return
            b, positions = nxt
            blk = _make_block(sweep, positions, done, sampled, info)
            stats.keys.append(blk.current)
            for fut, j, chunk in submit(blk):
                tasks[fut] = (b, j, chunk)
                blk.open += 1
                finished.add(fut)
            if blk.open:
                blocks[b] = blk

    refill()
    for fut in finished:
        b, j, chunk = tasks.pop(fut)
        blk = blocks[b]
        try:
            result = fut.result()
        except Exception as exc:  # a lost task is a recorded failure, not a lost sweep
            rows = _failed_task(blk, chunk, specs[j].id, exc, sweep, info)
            staged = store.stage(rows)
            result = {
                "staged": staged,
                "rows": len(rows),
                "keys": np.array([r["key"] for r in rows], dtype="S24"),
                "failed": len(rows),
                "points": 0,
                "cpu": 0.0,
                "first": False,
                "invalid": {},
            }
        if result["staged"] is not None:
            stats.parts.append(store.publish(result["staged"]))
        stats.rows_written += result["rows"]
        stats.keys.append(result["keys"])
        stats.rows_failed += result["failed"]
        if result["points"] and not result["first"]:  # a first task pays one-time costs
            cost[j].add(result["points"], result["cpu"])
        if result["invalid"]:
            points.note_invalid(result["invalid"])
        fut.release()
        bar.update(result["failed"], len(chunk), stats.tasks)
        del fut, result
        blk.open -= 1
        if not blk.open:
            del blocks[b]  # its reference futures go with it
        refill()
    stats.seconds = time.perf_counter() - t0
    return stats


def results_store(sweep: Sweep, out_dir: str | Path) -> ResultStore:
    """The Parquet store of ``sweep``'s results: the ``results`` folder of ``out_dir``."""
    return ResultStore(Path(out_dir) / "results", [a.path for a in sweep.axes])


def sweep_rows(sweep: Sweep, out_dir: str | Path, stats: SweepStats | None = None) -> Columns:
    """The stored rows of ``sweep`` under the current code (see :func:`current_keys`), as
    columns that are also a sequence of dicts; the invalid points among them are noted in
    ``sweep.points`` (a lazy sweep learns its invalid points from its workers, and a resumed
    one from its stored rows).

    With the ``stats`` of the :func:`run_sweep` call that just ran, the current rows are
    those it wrote and found (:meth:`SweepStats.current_keys`): no point is hashed again.
    """
    keys = current_keys(sweep) if stats is None else stats.current_keys()
    rows = results_store(sweep, out_dir).rows(keys)
    invalid_at = np.flatnonzero(np.equal(rows.column("status"), "invalid_point"))
    if invalid_at.size and not sweep.points.checked:
        points, reasons = rows.column("point"), rows.column("reason")
        sweep.points.note_invalid({points[k]: reasons[k] for k in invalid_at.tolist()})
    return rows
