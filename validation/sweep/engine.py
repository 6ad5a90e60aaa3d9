"""Run a sweep on a Dask cluster, appending rows to the Parquet store as tasks finish.

Tasks are whole runs of one model on a batch of points (every load case of
the sweep): :attr:`Sweep.batch` points per task for the reduced models (by
default :func:`auto_batch`), so the per-task cost of Dask stays small
against the work, and one point per task for the costly reference-class
models (the continuum). The reference runs once per point in its own
tasks; a model task receives the reference paths of its points from Dask.

Resuming: every row's key hashes the point's scene, the model, the load
case, the reference, the code version and the optional outputs; a (point,
model) pair whose rows are all stored already is not run again, and the
summary reads only the rows of the current keys (:func:`current_keys`),
never those a sweep left under an older code version. A task that raises
even after Dask's retries (a worker that keeps dying) becomes rows with
status ``error``: the sweep goes on.

Units: times in s.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexval.reducedmodels import ModelSpec
from flexval.reducedmodels.catalogue import REFERENCE

from ..cache import code_version
from .spec import Point, Sweep
from .store import ResultStore
from .tasks import TaskInfo, base_row, row_key, run_model_batch, run_reference

RETRIES = 2
"""Times Dask reruns a task whose worker died before it finished."""
MESSAGE_LOG_LENGTH = 10
"""Recent messages Dask keeps per connection (``distributed.admin.low-level-log-length``,
1000 by default) in a local cluster: each message to a worker holds its task's points, so
a thousand held 470 MB of scenes in the driver of a 20,000-point sweep."""
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


def chunks(points: list[Point], size: int) -> Iterator[list[Point]]:
    """``points`` in consecutive runs of ``size`` (the last may be shorter)."""
    for k in range(0, len(points), size):
        yield points[k : k + size]


MAX_AUTO_BATCH = 25
"""Most points per task of a reduced model chosen by :func:`auto_batch`. Dask costs about 5 ms
per task (``benchmarks/bench_sweep.py``: wall time outside the tasks over the tasks, 4 to 15 ms
on the loaded 2-core machine) against about 0.1 s of reduced-model work per open-chain point
and load case: 25 points per task keep that cost near 1 % of the work (batch 5: 2.4 %,
10: 1.8 %, 25: 0.7 % of one worker's time measured on 200 variants)."""
TASKS_PER_WORKER = 4
"""Fewest tasks per worker and model that :func:`auto_batch` aims at: the last tasks of a
sweep leave workers idle, the less the smaller the tasks."""


def auto_batch(points: int, workers: int) -> int:
    """Points per reduced-model task when the sweep gives none: enough tasks for
    :data:`TASKS_PER_WORKER` per worker and model, at most :data:`MAX_AUTO_BATCH` points each."""
    return max(1, min(MAX_AUTO_BATCH, points // (TASKS_PER_WORKER * max(workers, 1))))


def _batch_size(sweep: Sweep, spec: ModelSpec, workers: int) -> int:
    """Points per task: one for a reference-class (costly) model; the sweep's batch, or
    :func:`auto_batch` for ``workers``, otherwise."""
    if spec.model_family.has(REFERENCE):
        return 1
    return sweep.batch or auto_batch(sweep.points.valid_count, workers)


def task_info(sweep: Sweep) -> TaskInfo:
    """What every task of ``sweep`` shares (and its row keys hash)."""
    return TaskInfo(sweep.name, sweep.reference.id, code_version(), sweep.outputs)


def current_keys(sweep: Sweep) -> set[str]:
    """The keys of every row ``sweep`` produces with the current code (from the points'
    records: no scene is built)."""
    info = task_info(sweep)
    models = [sweep.reference.id, *(s.id for s in sweep.models)]
    keys = set()
    for r in sweep.points.records():
        if r.reason is not None:
            keys.add(row_key(r.digest, "-", "-", info))
        else:
            keys.update(row_key(r.digest, m, c, info) for m in models for c in sweep.load_cases)
    return keys


def local_cluster(workers: int | None = None):
    """A LocalCluster of single-threaded worker processes (default: one per core).

    Dask keeps :data:`MESSAGE_LOG_LENGTH` recent messages per connection, not a thousand.
    Dask's own log lines below ERROR are silenced: on a loaded machine every
    close printed "Worker process still alive after 4.0 seconds, killing" for
    workers that had finished; a worker lost mid-task is a recorded failure row.
    """
    import logging
    import os

    import dask
    from distributed import LocalCluster

    # the scheduler runs in this process: its logs of recent messages would hold the
    # arguments (points and scenes) of the last thousand tasks sent to each worker
    dask.config.set({"distributed.admin.low-level-log-length": MESSAGE_LOG_LENGTH})
    n = workers or os.cpu_count() or 1
    return LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",
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
    """One line per finished task: tasks done, failed rows, ETA from the mean task rate."""

    def __init__(self, total: int, emit: Callable[[str], None] | None):
        self.total, self.emit, self.done, self.failed = total, emit, 0, 0
        self.t0 = time.perf_counter()

    def update(self, failed_rows: int) -> None:
        self.done += 1
        self.failed += failed_rows
        if self.emit is None:
            return
        elapsed = time.perf_counter() - self.t0
        eta = elapsed / self.done * (self.total - self.done)
        self.emit(
            f"sweep: {self.done}/{self.total} tasks, {self.failed} failed rows, "
            f"{elapsed:.0f} s elapsed, ETA {eta:.0f} s"
        )


BLOCK_TASKS = TASKS_PER_WORKER
"""Points of one block of :func:`run_sweep`: this many of the largest task per worker."""
BLOCKS_IN_FLIGHT = 2
"""Blocks whose tasks are submitted and not all finished: the next block is built and
submitted when fewer remain, so the workers always have the next tasks queued while the
driver holds the scenes of at most this many blocks."""


def _blocks(need: np.ndarray, size: int) -> Iterator[np.ndarray]:
    """The positions where ``need`` holds, in consecutive runs of ``size``."""
    positions = np.flatnonzero(need)
    for k in range(0, len(positions), size):
        yield positions[k : k + size]


def run_sweep(
    sweep: Sweep,
    out_dir: str | Path,
    client,
    use_cache: bool = True,
    progress: Callable[[str], None] | None = None,
) -> SweepStats:
    """Run what is missing of ``sweep`` on the Dask ``client``; rows go to ``out_dir/results``.

    The points are built and submitted block by block (:data:`BLOCK_TASKS` tasks per
    worker of the largest task), at most :data:`BLOCKS_IN_FLIGHT` blocks at a time: the
    driver holds every point's record (:class:`~flexval.validation.sweep.spec.PointRecord`)
    and which of its (point, model) pairs are missing, and the scenes of those blocks only.

    Parameters
    ----------
    sweep : Sweep
    out_dir : path
        Output folder; the Parquet dataset is its ``results`` sub-folder.
    client : distributed.Client
    use_cache : bool
        Let workers reuse cached converged reference paths.
    progress : callable, optional
        Called with a progress line after each finished task.
    """
    from distributed import as_completed

    t0 = time.perf_counter()
    store = results_store(sweep, out_dir)
    done = store.keys()
    info = task_info(sweep)
    stats = SweepStats()
    cases = sweep.load_cases
    specs = (sweep.reference, *sweep.models)

    fresh_invalid = []
    missing = np.zeros((len(sweep.points), len(specs)), dtype=bool)
    for k, r in enumerate(sweep.points.records()):
        if r.reason is not None:
            if row_key(r.digest, "-", "-", info) not in done:
                point = Point(r.index, sweep.points.params(r.index), None, r.digest, r.reason)
                fresh_invalid.append(
                    base_row(point, "-", "-", info)
                    | {"status": "invalid_point", "reason": r.reason}
                )
            continue
        for j, spec in enumerate(specs):
            missing[k, j] = any(row_key(r.digest, spec.id, c, info) not in done for c in cases)
    if fresh_invalid:
        stats.parts.append(store.append(fresh_invalid))
    stats.rows_written += len(fresh_invalid)
    del fresh_invalid
    stats.rows_skipped = (sweep.points.valid_count * len(specs) - int(missing.sum())) * len(cases)

    workers = sum(client.nthreads().values())
    batch = [_batch_size(sweep, spec, workers) for spec in specs]
    size = max(batch) * max(workers, 1) * BLOCK_TASKS
    need = missing.any(axis=1)  # the reference runs wherever a model runs (it gives the errors)
    stats.tasks = sum(
        -(-len(block) // batch[0])
        + sum(-(-int(missing[block, j].sum()) // batch[j]) for j in range(1, len(specs)))
        for block in _blocks(need, size)
    )

    def submit(block: np.ndarray) -> Iterator[tuple[object, list[Point], str]]:
        """Build the points of ``block`` and submit their tasks: (future, points, model)."""
        points = {int(k): sweep.points[int(k)] for k in block}
        ref_future = {}
        for chunk in chunks(list(points.values()), batch[0]):
            fut = client.submit(
                run_reference,
                chunk,
                sweep.reference,
                cases,
                info,
                use_cache,
                retries=RETRIES,
                pure=False,
            )
            ref_future.update((p.index, fut) for p in chunk)
            yield fut, chunk, sweep.reference.id
        for j, spec in enumerate(specs[1:], start=1):
            todo = [points[int(k)] for k in block if missing[k, j]]
            for chunk in chunks(todo, batch[j]):
                refs = list({id(ref_future[p.index]): ref_future[p.index] for p in chunk}.values())
                fut = client.submit(
                    run_model_batch,
                    chunk,
                    spec,
                    cases,
                    info,
                    refs,
                    retries=RETRIES,
                    pure=False,
                )
                yield fut, chunk, spec.id

    tasks: dict = {}  # future: (points, model, block)
    open_blocks: dict[int, int] = {}  # block: its tasks not finished
    pending = enumerate(_blocks(need, size))
    finished = as_completed()

    def refill() -> None:
        while len(open_blocks) < BLOCKS_IN_FLIGHT:
            nxt = next(pending, None)
            if nxt is None:
                return
            b, block = nxt
            for fut, chunk, model in submit(block):
                tasks[fut] = (chunk, model, b)
                open_blocks[b] = open_blocks.get(b, 0) + 1
                finished.add(fut)

    refill()
    bar = _Progress(stats.tasks, progress)
    for fut in finished:
        chunk, model, b = tasks.pop(fut)
        try:
            result = fut.result()
            rows = result["rows"] if isinstance(result, dict) else result
        except Exception as exc:  # a lost task is a recorded failure, not a lost sweep
            reason = f"task failed: {type(exc).__name__}: {exc}"
            rows = [
                base_row(p, model, c, info) | {"status": "error", "reason": reason}
                for p in chunk
                for c in cases
            ]
        result = None
        rows = [r for r in rows if r["key"] not in done]
        failed = sum(r["status"] != "ok" for r in rows)
        part = store.append(rows)
        if part is not None:
            stats.parts.append(part)
        done.update(r["key"] for r in rows)
        stats.rows_written += len(rows)
        stats.rows_failed += failed
        fut.release()
        del fut, chunk, rows  # the block's scenes go with its last task
        bar.update(failed)
        open_blocks[b] -= 1
        if not open_blocks[b]:
            del open_blocks[b]
            refill()
    stats.seconds = time.perf_counter() - t0
    return stats


def results_store(sweep: Sweep, out_dir: str | Path) -> ResultStore:
    """The Parquet store of ``sweep``'s results: the ``results`` folder of ``out_dir``."""
    return ResultStore(Path(out_dir) / "results", [a.path for a in sweep.axes])


def sweep_rows(sweep: Sweep, out_dir: str | Path) -> list[dict]:
    """The stored rows of ``sweep`` under the current code (see :func:`current_keys`)."""
    return results_store(sweep, out_dir).rows(current_keys(sweep))
