"""Run many models on many load cases, with caching, timing and progress.

Timing is wall-clock per whole load path (model build included), the median
of ``repeats`` runs; the median and every sample are kept in the LoadPath's
``stats`` (``seconds_median``, ``seconds_samples``) and ``seconds`` holds the
median. ``stats["cached"]`` says whether the path was read from the on-disk
cache (its seconds are then those of the run that filled it).

Independent runs can be computed ahead on several processes
(:func:`prefetch`) into a :class:`RunMemo`; the campaigns then find them
there, so their results and the order of every table are those of a serial
run.
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.reducedmodels import LoadPath, ModelSpec, SolverError

from ..cache import ResultCache, result_key
from ..failures import Failure, failure_of
from ..interrupt import stop_pool, worker_signals
from ..run import run_model


def available_cores() -> int:
    """CPU cores this process may run on (the default number of report workers)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


LOG_LINES = 10
"""Lines a bar writes into a log (stderr not a terminal): one per tenth of the work."""


class Progress:
    """Progress on stderr (silent when disabled): a one-line bar redrawn in place on a
    terminal, or with ``lines`` one line per unit of work, which also says about how long
    the rest will take at the rate so far (for output interleaved with other lines). Into a
    log (stderr not a terminal) a bar writes such lines at each tenth of the work only,
    never the carriage returns of a bar redrawn in place."""

    def __init__(
        self, total: int, enabled: bool = True, width: int = 24, lines: bool = False
    ) -> None:
        self.total, self.done, self.enabled, self.width = total, 0, enabled, width
        self.lines = lines
        self.logged = not lines and not _is_terminal(sys.stderr)  # lines, thinned
        self.t0 = time.perf_counter()

    def step(self, label: str) -> None:
        """Count one unit of work done, labelled ``label``."""
        self.done += 1
        if not self.enabled:
            return
        if self.logged and not self._tenth_reached():
            return
        filled = int(self.width * min(self.done, self.total) / max(self.total, 1))
        bar = "#" * filled + "." * (self.width - filled)
        elapsed = time.perf_counter() - self.t0
        if self.lines or self.logged:
            left = elapsed * max(self.total - self.done, 0) / self.done
            print(
                f"[{bar}] {self.done:>3}/{self.total} {elapsed:7.1f} s, about {left:.0f} s "
                f"left  {label}",
                file=sys.stderr,
                flush=True,
            )
            return
        end = "\n" if self.done >= self.total else ""
        print(
            f"\r[{bar}] {self.done:>3}/{self.total} {elapsed:7.1f} s  {label:<40.40}",
            end=end,
            file=sys.stderr,
            flush=True,
        )

    def _tenth_reached(self) -> bool:
        """Whether this step completes another tenth of the work (or all of it)."""
        total = max(self.total, 1)
        return (
            self.done >= total
            or (self.done * LOG_LINES) // total > ((self.done - 1) * LOG_LINES) // total
        )


def _is_terminal(stream) -> bool:
    """Whether ``stream`` is an interactive terminal (a closed or odd stream is not)."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False


@contextmanager
def level_progress(
    specs: list[ModelSpec], cases: list[LoadCase], levels: int | None, enabled: bool
) -> Iterator[None]:
    """Within the block, one :class:`Progress` line on stderr per converged load level of the
    load-control paths of every model in ``specs`` on every case in ``cases`` (``levels``
    each, default the case's): the model, the case, level k/N of the path and its load,
    the time so far and about how long the rest takes at that rate. Nothing when not
    ``enabled``; the paths are the same either way
    (:func:`flexval.reducedmodels.core.recorder.observing`
    only reads them)."""
    if not enabled:
        yield
        return
    from flexval.reducedmodels.catalogue import LINEAR
    from flexval.reducedmodels.core.recorder import observing

    per_path = {c.name: len(c.factors(levels)) for c in cases}
    traced = [s for s in specs if not s.model_family.has(LINEAR)]  # a linear model traces none
    bar = Progress(len(traced) * sum(per_path.values()), lines=True)

    def show(lp: LoadPath) -> None:
        n = per_path.get(lp.load_case, 0)
        bar.step(
            f"{lp.model} on {lp.load_case}: level {len(lp.load)}/{n}, load "
            f"{lp.load[-1]:.4g} {lp.load_unit}"
        )

    with observing(show):
        yield


def run_key(scene: Scene, spec: ModelSpec, case: LoadCase, repeats: int, record: bool) -> str:
    """Cache key of one :func:`timed_run`."""
    return result_key(scene, spec.id, case.name, None, {"record": record, "repeats": repeats})


class RunMemo:
    """The paths computed during one command, in memory, in front of a :class:`ResultCache`.

    ``get``/``put`` as the cache's; a path :meth:`remember`-ed here (computed by a
    worker of :func:`prefetch`) is found without touching the disk, also when the
    disk cache is disabled.
    """

    def __init__(self, disk: ResultCache):
        self.disk = disk
        self.paths: dict[str, LoadPath] = {}

    def remember(self, key: str, lp: LoadPath) -> None:
        """Keep ``lp`` (returned by a worker's :func:`timed_run`) under ``key``; unless it
        came from the disk cache it is marked as computed by this command."""
        lp.stats.setdefault("cached", False)
        self.paths[key] = lp

    def get(self, key: str) -> LoadPath | None:
        """The path under ``key``: from memory, else from the disk cache, else None."""
        hit = self.paths.get(key)
        return hit if hit is not None else self.disk.get(key)

    def put(self, key: str, lp: LoadPath) -> None:
        """Store ``lp`` (just computed) in the disk cache and in memory."""
        self.disk.put(key, lp)
        self.remember(key, lp)

    path = ResultCache.path
    """The cache's one cached run (:meth:`ResultCache.path`), over this memo's get and put."""


@dataclass(frozen=True)
class Job:
    """One :func:`timed_run` to compute ahead (see :func:`prefetch`)."""

    scene: Scene
    spec: ModelSpec
    case: LoadCase
    repeats: int
    record: bool

    @property
    def key(self) -> str:
        """Its cache key."""
        return run_key(self.scene, self.spec, self.case, self.repeats, self.record)


def _run_job(job: Job, disk: ResultCache) -> LoadPath | None:
    """A worker's :func:`timed_run` of ``job`` (None if it fails: the campaign then
    reruns it in the main process, which records the failure)."""
    try:
        return timed_run(job.scene, job.spec, job.case, job.repeats, disk, job.record)
    except (SolverError, SceneError):
        return None


def prefetch(jobs: list[Job], memo: RunMemo, workers: int, progress: bool = True) -> None:
    """Compute ``jobs`` on ``workers`` processes into ``memo``, in the order listed
    (put the longest first); duplicates are computed once, and a path in the disk
    cache is read, not recomputed.

    Nothing happens with fewer than two workers: the campaigns then run every
    job themselves, one after the other. An exception here (SIGINT or SIGTERM
    among them) stops the workers at once; the paths they finished are in the
    disk cache.
    """
    todo: dict[str, Job] = {}
    for job in jobs:
        todo.setdefault(job.key, job)
    if workers < 2 or len(todo) < 2:
        return
    bar = Progress(len(todo), enabled=progress)
    pool = ProcessPoolExecutor(max_workers=workers, initializer=worker_signals)
    try:
        futures = {pool.submit(_run_job, job, memo.disk): key for key, job in todo.items()}
        for fut in as_completed(futures):
            lp, job = fut.result(), todo[futures[fut]]
            if lp is not None:
                memo.remember(futures[fut], lp)
            state = "FAILED" if lp is None else f"{lp.seconds:.3g} s"
            bar.step(f"{job.scene.name} {job.spec.id} {job.case.name} {state}")
    except BaseException:  # an interruption (flexval.validation.interrupt) or a failure
        stop_pool(pool)  # the queued jobs are dropped, not waited for
        raise
    pool.shutdown()


def timed_run(
    scene: Scene,
    spec: ModelSpec,
    case: LoadCase,
    repeats: int = 1,
    cache: ResultCache | None = None,
    record: bool = False,
) -> LoadPath:
    """One model on one load case: cached, else run ``repeats`` times (median seconds).

    ``record`` also records body poses and deformed shapes (for figures).
    Raises SolverError on failure (failures are not cached).
    """

    def timed() -> LoadPath:
        samples, lp = [], None
        for _ in range(max(1, repeats)):
            lp = run_model(scene, spec, case, record_poses=record, record_shapes=record)
            samples.append(lp.seconds)
        lp.seconds = statistics.median(samples)
        lp.stats["seconds_median"] = lp.seconds
        lp.stats["seconds_samples"] = samples
        return lp

    if cache is None:
        return timed()
    return cache.path(run_key(scene, spec, case, repeats, record), timed)


def run_campaign(
    scene: Scene,
    specs: list[ModelSpec],
    cases: list[LoadCase],
    repeats: int,
    cache: ResultCache | None,
    progress: Progress | None = None,
    record_models: tuple[str, ...] = (),
    repeats_for: Callable[[ModelSpec], int] | None = None,
) -> tuple[dict[tuple[str, str], LoadPath], list[Failure]]:
    """Every spec on every case: ({(model, case): LoadPath}, failures).

    A model that fails on a case is a result, not an error: its
    :class:`~flexval.validation.failures.Failure` is listed and its partial path
    (the levels it reached) kept, and the campaign carries on. So is a
    model that cannot represent a flexure of the scene (a failure at load 0).
    """
    results: dict[tuple[str, str], LoadPath] = {}
    failures: list[Failure] = []
    for spec in specs:
        for case in cases:
            reps = repeats_for(spec) if repeats_for else repeats
            try:
                lp = timed_run(scene, spec, case, reps, cache, record=spec.id in record_models)
                results[(spec.id, case.name)] = lp
                label = f"{scene.name} {spec.id} {case.name} {lp.seconds:.3g} s"
            except (SolverError, SceneError) as exc:
                failures.append(failure_of(exc, scene, spec, case))
                if getattr(exc, "path", None) is not None:
                    results[(spec.id, case.name)] = exc.path
                label = f"{scene.name} {spec.id} {case.name} FAILED"
            if progress:
                progress.step(label)
    return results, failures
