"""What a Dask worker runs: one model on a batch of sweep points, all load cases.

A task returns finished result rows (see :mod:`flexval.validation.sweep.store`),
never raises for a model that fails: a SolverError, a model that refuses
the geometry, an unexpected numerical exception or a non-finite result is a
row with its status and reason. The reference task also returns its load
paths and limit loads, which the model tasks of the same points receive
from Dask (the reference is computed once per point and shared).

With the ``peak_stress`` output (the default), a row carries its peak stress
at the last level its path recorded (:func:`flexval.validation.strength.peak_at_full_load`
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

import hashlib
from dataclasses import dataclass

import numpy as np

from flexval.geometry import LoadCase, SceneError
from flexval.reducedmodels import LoadPath, ModelSpec, SolverError

from ..cache import ResultCache, result_key
from ..compare import METRICS, errors
from ..failures import first_limit
from ..run import run_model
from ..strength import peak_at_full_load
from .spec import Point
from .store import PARAM_PREFIX


@dataclass(frozen=True)
class TaskInfo:
    """What every row of a task shares: sweep name, reference id, code version and the
    optional outputs asked for (see :data:`flexval.validation.sweep.spec.OPTIONAL_OUTPUTS`)."""

    sweep: str
    reference: str
    code: str
    outputs: tuple[str, ...]


def row_key(digest: str, model: str, case: str, info: TaskInfo) -> str:
    """Key of one result row: the point's scene digest, model, case, reference, code and
    outputs (a row without a limit load is not the answer to a sweep that asks for one)."""
    text = "|".join((digest, model, case, info.reference, info.code, ",".join(info.outputs)))
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def base_row(point: Point, model: str, case: str, info: TaskInfo) -> dict:
    """A row with the point's identity and parameters and every result field empty."""
    row = {
        "key": row_key(point.digest, model, case, info),
        "sweep": info.sweep,
        "point": point.index,
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
        "load_unit": point.scene.load_case(case).unit if point.scene is not None else None,
        "peak_stress": None,
        "peak_stress_flexure": None,
        "peak_stress_at": None,
        "peak_stress_load": None,
        "peak_stress_error": None,
        "limit_load": None,
        "limit_load_error": None,
        "bifurcation_load": None,
        **{m: None for m in METRICS},
    }
    row.update({PARAM_PREFIX + k: v for k, v in point.params.items()})
    return row


def _finite(lp: LoadPath) -> bool:
    return bool(np.all(np.isfinite(np.concatenate([lp.load, lp.dx, lp.dy, lp.rotation]))))


def attempt(
    point: Point,
    spec: ModelSpec,
    case: str,
    row: dict,
    info: TaskInfo,
    cache: ResultCache | None = None,
) -> LoadPath | None:
    """Run ``spec`` on ``case`` of the point; fill ``row`` (status, reason, time, peak
    stress, limit load if asked for); the path or None."""
    scene = point.scene
    lc = scene.load_case(case)
    key = result_key(scene, spec.id, case, None, {"sweep": True}) if cache else None
    lp = cache.get(key) if cache else None
    try:
        if lp is None:
            lp = run_model(scene, spec, lc)
            if cache:
                cache.put(key, lp)
    except SolverError as exc:
        row.update(status="solver_failure", reason=str(exc), load_reached=exc.load_factor)
        if exc.path is not None and exc.path.load:
            _peak(exc.path, lc, row, info)
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
    peak = peak_at_full_load(lp) if "peak_stress" in info.outputs else None
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


def run_reference(
    points: list[Point],
    spec: ModelSpec,
    cases: tuple[str, ...],
    info: TaskInfo,
    use_cache: bool = True,
) -> dict:
    """The reference on every point and case: {"rows": [...], "paths": {(point, case): path},
    "limits": {(point, case): limit load}}.

    Converged reference paths are cached on the worker (:class:`ResultCache`),
    so a resumed sweep does not recompute a reference it already had.
    """
    cache = ResultCache(enabled=use_cache)
    rows, paths, limits = [], {}, {}
    for p in points:
        for case in cases:
            row = base_row(p, spec.id, case, info)
            lp = attempt(p, spec, case, row, info, cache)
            if lp is not None:
                paths[(p.index, case)] = lp
            if row["limit_load"] is not None:
                limits[(p.index, case)] = row["limit_load"]
            rows.append(row)
    return {"rows": rows, "paths": paths, "limits": limits}


def run_model_batch(
    points: list[Point],
    spec: ModelSpec,
    cases: tuple[str, ...],
    info: TaskInfo,
    references: list[dict],
) -> list[dict]:
    """Rows of ``spec`` on every point and case, with errors (of the paths, the peak stress
    and the limit load) against the reference's, found in ``references`` (results of
    :func:`run_reference`)."""
    ref_paths: dict = {}
    ref_limits: dict = {}
    for r in references:
        ref_paths.update(r["paths"])
        ref_limits.update(r["limits"])
    rows = []
    for p in points:
        for case in cases:
            row = base_row(p, spec.id, case, info)
            lp = attempt(p, spec, case, row, info)
            ref = ref_paths.get((p.index, case))
            if lp is not None and ref is not None:
                row.update(errors(lp, ref, p.scene.mechanism.size()))
                ref_peak = peak_at_full_load(ref) if row["peak_stress"] is not None else None
                row["peak_stress_error"] = _relative(
                    row["peak_stress"], ref_peak["stress"] if ref_peak else None
                )
            elif lp is not None:
                row["reason"] = f"no errors: the reference {info.reference} failed here"
            row["limit_load_error"] = _relative(row["limit_load"], ref_limits.get((p.index, case)))
            rows.append(row)
    return rows
