"""What a Dask worker runs: one model on a batch of sweep points, all load cases.

A task returns finished result rows (see :mod:`validation.sweep.store`),
never raises for a model that fails: a SolverError, a model that refuses
the geometry, an unexpected numerical exception or a non-finite result is a
row with its status and reason. The reference task also returns its load
paths, which the model tasks of the same points receive from Dask (the
reference is computed once per point and shared).

Units: errors in percent, times in s.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from geometry import SceneError
from reducedmodels import LoadPath, ModelSpec, SolverError

from ..cache import ResultCache, result_key
from ..compare import METRICS, errors
from ..run import run_model
from .spec import Point
from .store import PARAM_PREFIX


@dataclass(frozen=True)
class TaskInfo:
    """What every row of a task shares: sweep name, reference id and code version."""

    sweep: str
    reference: str
    code: str


def row_key(digest: str, model: str, case: str, info: TaskInfo) -> str:
    """Key of one result row: the point's scene digest, model, case, reference and code."""
    text = "|".join((digest, model, case, info.reference, info.code))
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def base_row(point: Point, model: str, case: str, info: TaskInfo) -> dict:
    """A row with the point's identity and parameters and every result field empty."""
    row = {"key": row_key(point.digest, model, case, info), "sweep": info.sweep,
           "point": point.index, "model": model, "reference": info.reference,
           "load_case": case, "status": "ok", "reason": None, "load_reached": None,
           "seconds": None, "newton_iterations": None, "valid": None, "validity": None,
           **{m: None for m in METRICS}}
    row.update({PARAM_PREFIX + k: v for k, v in point.params.items()})
    return row


def _finite(lp: LoadPath) -> bool:
    return bool(np.all(np.isfinite(np.concatenate([lp.load, lp.dx, lp.dy, lp.rotation]))))


def attempt(point: Point, spec: ModelSpec, case: str, row: dict,
            cache: ResultCache | None = None) -> LoadPath | None:
    """Run ``spec`` on ``case`` of the point; fill ``row`` (status, reason, time); the path
    or None."""
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
    row.update(load_reached=1.0, seconds=lp.seconds,
               newton_iterations=int(lp.stats.get("newton_iterations", 0)))
    if lp.valid is not None:
        row["valid"] = all(lp.valid)
        row["validity"] = next((v for v in lp.validity or () if v), None)
    return lp


def run_reference(points: list[Point], spec: ModelSpec, cases: tuple[str, ...],
                  info: TaskInfo, use_cache: bool = True) -> dict:
    """The reference on every point and case: {"rows": [...], "paths": {(point, case): path}}.

    Converged reference paths are cached on the worker (:class:`ResultCache`),
    so a resumed sweep does not recompute a reference it already had.
    """
    cache = ResultCache(enabled=use_cache)
    rows, paths = [], {}
    for p in points:
        for case in cases:
            row = base_row(p, spec.id, case, info)
            lp = attempt(p, spec, case, row, cache)
            if lp is not None:
                paths[(p.index, case)] = lp
            rows.append(row)
    return {"rows": rows, "paths": paths}


def run_model_batch(points: list[Point], spec: ModelSpec, cases: tuple[str, ...],
                    info: TaskInfo, references: list[dict]) -> list[dict]:
    """Rows of ``spec`` on every point and case, with errors against the reference paths
    found in ``references`` (results of :func:`run_reference`)."""
    ref_paths: dict = {}
    for r in references:
        ref_paths.update(r["paths"])
    rows = []
    for p in points:
        for case in cases:
            row = base_row(p, spec.id, case, info)
            lp = attempt(p, spec, case, row)
            ref = ref_paths.get((p.index, case))
            if lp is not None and ref is not None:
                row.update(errors(lp, ref))
            elif lp is not None:
                row["reason"] = f"no errors: the reference {info.reference} failed here"
            rows.append(row)
    return rows
