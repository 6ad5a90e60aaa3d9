"""What a Dask worker runs: one model on a block of sweep points, all load cases.

A task receives a :class:`PointBlock` (the points' indices, axis values and
scene digests, not their scenes), builds each point's scene from the sweep's
base scene data (:meth:`~flexval.validation.sweep.spec.PointBuilder.build`:
the same function as the driver's check, so the same scene), runs the model
on the block through :func:`run_model_block` (the one place a model is solved:
a tracer that runs many copies of one mechanism together replaces its loop),
and writes its rows as one staged Parquet part
(:meth:`~flexval.validation.sweep.store.ResultStore.stage`); it returns a
small summary (the part, counts, its own CPU seconds, the invalid points found).
It never raises for a model that fails: a SolverError, a model that refuses
the geometry, an unexpected numerical exception or a non-finite result is a
row with its status and reason. The reference task also returns its load
paths and limit loads, which the model tasks of the same points receive
from Dask (the reference is computed once per point and shared); a model's
rows on a point the reference did not run on (``reference_sample``) carry
its own outputs and no errors.

With the ``peak_stress`` output (the default), a row carries its peak stress
at the last level its path recorded (:func:`flexval.validation.report.strength.peak_at_full_load`
of the path so far) and that level's load (``peak_stress_load``: 1 for a
converged row, at or below ``load_reached`` for a solver failure), and a
converged row its error against the reference's at full load; with the ``limit_load``
output, a run that stops below full load is searched for its first limit
point by arc length (:func:`flexval.validation.failures.first_limit`, as the
report does), and the row carries that load and the load of the first bifurcation
point on its load-control path (``bifurcation_load``; the tracer locates it, nothing
more is run).

Units: errors in percent, times in s, stresses in MPa, loads in N or N mm.
"""

from __future__ import annotations

import functools
import hashlib
import time
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from flexval.geometry import LoadCase, SceneError
from flexval.reducedmodels import LoadPath, ModelSpec, SolverError
from flexval.reducedmodels.core.batch import RUN_FAILURES, run_batch

from ..cache import ResultCache, result_key
from ..failures import first_limit
from ..run import run_model
from ..studies.compare import METRICS, errors
from ..studies.parasitic import largest_parasitic_error
from ..studies.yieldpoint import yield_columns
from .points import Point
from .spec import PointBuilder
from .store import PARAM_PREFIX, ResultStore
from .tolerance import target_columns

FAILURES = RUN_FAILURES
"""What a model run may raise and a row records (anything else fails the task)."""


@dataclass(frozen=True)
class TaskInfo:
    """What every row of a task shares: sweep name, reference id, code version and the
    optional outputs asked for (see :data:`flexval.validation.sweep.fields.OPTIONAL_OUTPUTS`)."""

    sweep: str
    reference: str
    code: str
    outputs: tuple[str, ...]


def cached_run(cache: ResultCache | None, scene, spec, case) -> LoadPath:
    """``spec``'s path of ``case`` on a point's scene: from the result cache where there is
    one (a sweep's runs are keyed apart from a command's: they record no shapes)."""
    if cache is None:
        return run_model(scene, spec, case)
    key = result_key(scene, spec.id, case.name, None, {"sweep": True})
    return cache.path(key, lambda: run_model(scene, spec, case))


def row_key(digest: str, model: str, case: str, info: TaskInfo) -> str:
    """Key of one result row: the point's scene digest, model, case, reference, code and
    outputs (a row without a limit load is not the answer to a sweep that asks for one)."""
    text = "|".join((digest, model, case, info.reference, info.code, ",".join(info.outputs)))
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def base_row(point: Point, model: str, case: str, info: TaskInfo) -> dict:
    """A row with the point's identity and parameters and every result field empty."""
    row = dict(_row_template(model, case, info))
    row["key"] = row_key(point.digest, model, case, info)
    row["point"] = point.index
    row["load_unit"] = point.scene.load_case(case).unit if point.scene is not None else None
    row.update({PARAM_PREFIX + k: v for k, v in point.params.items()})
    return row


@functools.lru_cache(maxsize=64)
def _row_template(model: str, case: str, info: TaskInfo) -> dict:
    """The fields :func:`base_row` shares between the rows of one model and case (copied:
    a row is filled in place)."""
    return {
        "key": None,
        "sweep": info.sweep,
        "point": None,
        "model": model,
        "reference": info.reference,
        "load_case": case,
        "status": "ok",
        "reason": None,
        "load_reached": None,
        "seconds": None,
        "newton_iterations": None,
        "valid": None,
        "validity": None,
        "load_unit": None,
        "peak_stress": None,
        "peak_stress_flexure": None,
        "peak_stress_at": None,
        "peak_stress_load": None,
        "peak_stress_error": None,
        "parasitic": None,
        "limit_load": None,
        "limit_load_error": None,
        "bifurcation_load": None,
        **{m: None for m in METRICS},
    }


def _finite(lp: LoadPath) -> bool:
    return bool(np.all(np.isfinite(np.concatenate([lp.load, lp.dx, lp.dy, lp.rotation]))))


def attempt(
    point: Point,
    spec: ModelSpec,
    case: str,
    row: dict,
    info: TaskInfo,
    cache: ResultCache | None = None,
    solved: LoadPath | BaseException | None = None,
) -> LoadPath | None:
    """Run ``spec`` on ``case`` of the point (or take its outcome ``solved`` from
    :func:`run_model_block`); fill ``row`` (status, reason, time, peak stress, limit load if
    asked for); the path or None."""
    scene = point.scene
    lc = scene.load_case(case)
    try:
        if isinstance(solved, BaseException):
            raise solved
        lp = solved if solved is not None else cached_run(cache, scene, spec, lc)
    except SolverError as exc:
        row.update(status="solver_failure", reason=str(exc), load_reached=exc.load_factor)
        if exc.path is not None and exc.path.load:
            _peak(exc.path, lc, row, info)
            row.update(yield_columns(scene, exc.path, info.outputs))
        if "limit_load" in info.outputs:
            row["limit_load"] = _limit_load(point, spec, lc, row)
            row["bifurcation_load"] = _bifurcation_load(exc.path)
        return None
    except SceneError as exc:
        row.update(status="model_invalid", reason=f"{exc.field}: {exc.reason}")
        return None
    except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        row.update(status="error", reason=f"{type(exc).__name__}: {exc}")
        return None
    if not _finite(lp):
        row.update(status="error", reason="non-finite values in a converged path")
        return None
    row.update(
        load_reached=1.0,
        seconds=lp.seconds,
        newton_iterations=int(lp.stats.get("newton_iterations", 0)),
    )
    if lp.valid is not None:
        row["valid"] = all(lp.valid)
        row["validity"] = next((v for v in lp.validity or () if v), None)
    _peak(lp, lc, row, info)
    row.update(yield_columns(scene, lp, info.outputs))
    row.update(target_columns(lp))
    if "limit_load" in info.outputs:
        row["bifurcation_load"] = _bifurcation_load(lp)
    return lp


def _bifurcation_load(lp: LoadPath | None) -> float | None:
    """The load of the first bifurcation point on ``lp`` (N or N mm), or None."""
    if lp is None or not lp.bifurcations:
        return None
    return float(lp.bifurcations[0]["load"])


def _peak(lp: LoadPath, case: LoadCase, row: dict, info: TaskInfo) -> None:
    """Fill ``row``'s peak stress (MPa), its flexure and place at the last level of ``lp``,
    and that level's load as a fraction of ``case``'s full load, when the sweep asks for
    it and the model gives one."""
    if "peak_stress" not in info.outputs:
        return
    # imported here: the module draws figures too, and matplotlib costs a worker 0.3 s to
    # import; a sweep without peak stresses never needs it
    from ..report.strength import peak_at_full_load

    peak = peak_at_full_load(lp)
    if peak is not None:
        reached = 1.0 if lp.converged else abs(lp.load[-1]) / case.magnitude
        row.update(
            peak_stress=peak["stress"],
            peak_stress_flexure=peak["flexure"],
            peak_stress_at=peak["at"],
            peak_stress_load=reached,
        )


def _limit_load(point: Point, spec: ModelSpec, case: LoadCase, row: dict) -> float | None:
    """The first limit load below full load of ``spec`` on ``case`` (N or N mm), or None
    when there is none (a failure of another kind, or a model that cannot be traced by arc
    length); a search that itself fails adds its reason to ``row``."""
    try:
        limit = first_limit(point.scene, spec, case)
    except (SceneError, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        row["reason"] = f"{row['reason']}; limit-point search failed: {type(exc).__name__}: {exc}"
        return None
    return limit[0] if limit is not None and limit[0] <= case.magnitude else None


def _relative(value: float | None, reference: float | None) -> float | None:
    """(value - reference) / reference in percent, None if either is missing."""
    if value is None or reference is None or reference == 0.0:
        return None
    return 100.0 * (value - reference) / reference


@dataclass(frozen=True)
class SweepJob:
    """What every task of a sweep shares: its rows' identity, how to build a point, the load
    cases, and the store's folder and columns (a few kB, whatever the point count)."""

    info: TaskInfo
    builder: PointBuilder | None
    """:meth:`PointBuilder.light` of the sweep's builder (None: the blocks carry built points)."""
    paths: tuple[str, ...]
    cases: tuple[str, ...]
    folder: str

    def store(self) -> ResultStore:
        """The sweep's Parquet store."""
        return ResultStore(self.folder, list(self.paths))


@dataclass(frozen=True)
class PointBlock:
    """The points of one task: indices, axis values (one row each, in axis order) and scene
    digests; the worker builds their scenes.

    ``owner`` marks the points whose ``invalid_point`` row this task writes should the scene
    loader refuse them (one task per point does); ``skip`` holds the keys of rows already
    stored, which the task does not write again. ``built`` carries built points instead
    (a sweep given as a tuple of points).
    """

    indices: tuple[int, ...]
    values: np.ndarray
    digests: tuple[str, ...] | None
    """None: the worker computes them from the values (a lazy sweep's,
    :meth:`~flexval.validation.sweep.spec.PointBuilder.digest_of`)."""
    owner: tuple[bool, ...]
    skip: frozenset[str] = frozenset()
    built: tuple[Point, ...] | None = None

    def __len__(self) -> int:
        return len(self.indices)

    def points(self, job: SweepJob) -> list[Point]:
        """The block's points, built (scene None and a reason for a refused random draw).

        Raises
        ------
        RuntimeError
            If a point's scene hashes to another digest than the driver's (the driver's
            digests key the rows, so a point built differently must not be stored).
        """
        if self.built is not None:
            return list(self.built)
        digests = self.digests
        if digests is None:
            digests = tuple(job.builder.digest_of(v) for v in self.values)
        keys = [(job.folder, index, want) for index, want in zip(self.indices, digests)]
        points = [_BUILT.get(key) for key in keys]
        missing = [n for n, p in enumerate(points) if p is None]
        if missing:
            built = job.builder.build_block(
                [self.indices[n] for n in missing], self.values[missing]
            )
            for n, point in zip(missing, built):
                if point.digest != digests[n]:
                    raise RuntimeError(
                        f"point {self.indices[n]} of the sweep built differently from its key"
                    )
                _remember(keys[n], point)
                points[n] = point
        return points


BUILT_POINTS = 4096
"""Points a worker keeps built (a few tasks' worth, some megabytes): the reference's task and
the model tasks of one block mostly run on the worker that holds the reference's paths, and
building a point's scene (parsing and checking it) costs more than its reduced models."""

_BUILT: OrderedDict[tuple, Point] = OrderedDict()


def _remember(key: tuple, point: Point) -> None:
    """Keep ``point`` among the last :data:`BUILT_POINTS` built in this process."""
    _BUILT[key] = point
    while len(_BUILT) > BUILT_POINTS:
        _BUILT.popitem(last=False)


def run_model_block(
    spec: ModelSpec,
    scenes: list,
    cases: tuple[str, ...],
    cache: ResultCache | None = None,
) -> list[list[LoadPath | BaseException]]:
    """``spec`` on every scene and load case: per scene, per case, its load path or the
    exception it raised (one of :data:`FAILURES`; anything else propagates).

    The only place a sweep solves a model. The scenes of one block are copies of one
    mechanism with other parameter values: without a ``cache`` each load case is one batch
    (:func:`flexval.reducedmodels.core.batch.run_batch`: the copies traced together, each path
    what its own run gives, its time its share of the batch's). ``cache`` (costly models
    only) keeps converged paths, one run at a time.
    """
    if cache is None:
        per_case = []
        for case in cases:
            paths = run_batch(
                [scene.mechanism for scene in scenes],
                spec,
                [scene.load_case(case) for scene in scenes],
            )
            for scene, lp in zip(scenes, paths):
                if isinstance(lp, LoadPath):
                    lp.scene = scene.name
            per_case.append(paths)
        return [list(row) for row in zip(*per_case)] if per_case else [[] for _ in scenes]
    out = []
    for scene in scenes:
        per = []
        for case in cases:
            try:
                lp = cached_run(cache, scene, spec, scene.load_case(case))
            except FAILURES as exc:
                lp = exc
            per.append(lp)
        out.append(per)
    return out


def _invalid_rows(points: list[Point], block: PointBlock, info: TaskInfo) -> list[dict]:
    """The ``invalid_point`` rows of the refused points this task owns."""
    return [
        base_row(p, "-", "-", info) | {"status": "invalid_point", "reason": p.reason}
        for p, own in zip(points, block.owner)
        if p.scene is None and own
    ]


_RAN: set[str] = set()
"""The models this process has run a task of."""


def _first_task(spec: ModelSpec) -> bool:
    """Whether this is the first task of ``spec`` in this process: it pays the one-time
    costs (imports, loading the compiled kernels: more than many later points cost), which
    the driver leaves out of the model's cost."""
    first = spec.id not in _RAN
    _RAN.add(spec.id)
    return first


def _finish(
    rows: list[dict],
    points: list[Point],
    block: PointBlock,
    job: SweepJob,
    t0: float,
    first: bool,
) -> dict:
    """Stage the rows not stored yet as one part; the task's summary for the driver: its
    part, counts, the rows' keys (24 bytes each: the driver then knows every row of the run
    without hashing a point again), CPU seconds since ``t0`` (:func:`time.thread_time`),
    whether it was its model's first task in this process, the invalid points found."""
    rows = [r for r in rows + _invalid_rows(points, block, job.info) if r["key"] not in block.skip]
    staged = job.store().stage(rows)
    return {
        "staged": None if staged is None else str(staged),
        "rows": len(rows),
        "keys": np.array([r["key"] for r in rows], dtype="S24"),
        "failed": sum(r["status"] != "ok" for r in rows),
        "points": len(block),
        "cpu": time.thread_time() - t0,
        "first": first,
        "invalid": {p.index: p.reason for p in points if p.scene is None},
    }


def reference_task(block: PointBlock, spec: ModelSpec, job: SweepJob, use_cache: bool) -> dict:
    """The reference on every point and case of ``block``: {"summary": what
    :func:`_finish` gives, "ran": indices of its points, "paths": {(point, case): path},
    "limits": {(point, case): limit load}}.

    Converged paths of a costly reference (one whose family declares a cost: the continuum)
    are cached on the worker (:class:`ResultCache`), so a resumed sweep does not recompute
    them; a cheap one is not (hashing and writing a path costs more than tracing it).
    """
    t0 = time.thread_time()
    first = _first_task(spec)
    points = block.points(job)
    valid = [p for p in points if p.scene is not None]
    cache = ResultCache() if use_cache and spec.model_family.cost is not None else None
    solved = run_model_block(spec, [p.scene for p in valid], job.cases, cache)
    rows, paths, limits = [], {}, {}
    for p, outcomes in zip(valid, solved):
        for case, outcome in zip(job.cases, outcomes):
            row = base_row(p, spec.id, case, job.info)
            lp = attempt(p, spec, case, row, job.info, solved=outcome)
            if lp is not None:
                paths[(p.index, case)] = lp
            if row["limit_load"] is not None:
                limits[(p.index, case)] = row["limit_load"]
            rows.append(row)
    return {
        "summary": _finish(rows, points, block, job, t0, first),
        "ran": frozenset(block.indices),
        "paths": paths,
        "limits": limits,
    }


def summary_of(result: dict) -> dict:
    """The summary of a :func:`reference_task` result (what the driver fetches of it)."""
    return result["summary"]


def model_task(block: PointBlock, spec: ModelSpec, job: SweepJob, references: list[dict]) -> dict:
    """Rows of ``spec`` on every point and case of ``block``, with errors (of the paths, the
    peak stress and the limit load) against the reference's where it ran, found in
    ``references`` (results of :func:`reference_task`); the summary of :func:`_finish`."""
    t0 = time.thread_time()
    first = _first_task(spec)
    ran: set = set()
    ref_paths: dict = {}
    ref_limits: dict = {}
    for r in references:
        ran.update(r["ran"])
        ref_paths.update(r["paths"])
        ref_limits.update(r["limits"])
    points = block.points(job)
    valid = [p for p in points if p.scene is not None]
    solved = run_model_block(spec, [p.scene for p in valid], job.cases)
    rows = []
    for p, outcomes in zip(valid, solved):
        for case, outcome in zip(job.cases, outcomes):
            row = base_row(p, spec.id, case, job.info)
            lp = attempt(p, spec, case, row, job.info, solved=outcome)
            if p.index in ran:
                _errors(p, lp, ref_paths.get((p.index, case)), row, job.info)
                row["limit_load_error"] = _relative(
                    row["limit_load"], ref_limits.get((p.index, case))
                )
            rows.append(row)
    return _finish(rows, points, block, job, t0, first)


def _errors(p: Point, lp: LoadPath | None, ref: LoadPath | None, row: dict, info: TaskInfo):
    """Fill ``row``'s errors of ``lp`` against the reference's path ``ref`` (percent)."""
    if lp is not None and ref is not None:
        row.update(errors(lp, ref, p.scene.mechanism.size()))
        if lp.converged and ref.converged:
            case = p.scene.load_case(row["load_case"])
            row["parasitic"] = largest_parasitic_error(lp, ref, p.scene, case)
        ref_peak = None
        if row["peak_stress"] is not None:
            from ..report.strength import peak_at_full_load  # see _peak

            ref_peak = peak_at_full_load(ref)
        row["peak_stress_error"] = _relative(
            row["peak_stress"], ref_peak["stress"] if ref_peak else None
        )
    elif lp is not None:
        row["reason"] = f"no errors: the reference {info.reference} failed here"
