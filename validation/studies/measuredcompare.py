"""Models against a measured load–displacement record: each path traced through the
measured loads, then scored.

A :class:`~flexval.geometry.measured.Measurement` (a test rig's CSV, read and checked by
:mod:`flexval.geometry.measured`) is compared with each model in three steps:

1. **Trace.** The load case is scaled so that its full load is the measured load of
   largest magnitude, and the model's path is traced by the one dispatcher
   (:func:`flexval.validation.run.run_model`) through the requested load factors
   0 and every measured load over that full load: every measured load is a level of the
   path, so the model's value there is its own converged state, never an
   interpolation between levels. Paths are kept in the result cache under the
   measured loads.
2. **Stop.** A model whose path stops before the largest measured load (a limit
   point, a bifurcation, the solver's failure: :func:`flexval.validation.failures.failure_of`
   says which) is scored on the measured points it reached; the rest are reported
   as beyond its path, never extrapolated.
3. **Score.** With r_k the difference between the model and the measurement at
   measured point k (the vector (dx, dy) where both are measured, else the one
   measured component; the rotation), and R the *measured range*:

   - ``disp_rms`` = 100 sqrt(mean_k r_k^2) / R, ``disp_max`` = 100 max_k r_k / R
     (percent), and ``rot_rms``, ``rot_max`` likewise for the rotation;
   - R is the largest distance between two measured values over the whole file:
     max_{j,k} |m_j - m_k|, for the displacement vector the diameter of the measured
     points (for a file that starts at rest, the largest measured |d|), for a scalar
     its largest minus its smallest value. It is the same for every model, whatever
     each reached, and does not depend on where the rig's zero lies;
   - ``within_2u``: the share (0 to 1) of the scored points where the model lies
     within twice the standard uncertainty of every measured component of the
     quantity (needs a ``_std`` column for each; else None).

A score is None where the file does not measure the quantity, where no point was
reached, or where the measured range is zero. Units: mm, N or N mm, rad inside;
scores in percent.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.geometry.measured import Measurement
from flexval.reducedmodels import LoadPath, SolverError
from flexval.reducedmodels.catalogue import ModelSpec

from ..failures import Failure, failure_of
from ..run import run_model

SCORES = ("disp_rms", "disp_max", "rot_rms", "rot_max")
"""The scores of each model, in percent of the measured range (see the module docstring)."""
REACHED_RTOL = 1e-9
"""A measured load counts as reached when its load factor is at most the path's last one
times 1 + this (the factors are the same numbers divided and multiplied back)."""
_DIAMETER_BLOCK = 256
"""Rows per block of the pairwise distances of the measured range (bounded memory)."""


@dataclass(frozen=True)
class AtLoads(LoadCase):
    """A load case traced through given load factors instead of equal levels.

    ``at`` are the requested factors, increasing from 0; every family's runner asks the
    case for them (:meth:`LoadCase.factors`), so the path's levels are these factors.
    """

    at: tuple[float, ...] = ()

    def factors(self, levels: int | None = None) -> np.ndarray:
        """The requested load factors (``levels`` is ignored: they are given)."""
        return np.asarray(self.at, dtype=float)


def traced_case(case: LoadCase, measurement: Measurement) -> tuple[AtLoads, np.ndarray]:
    """The case scaled to the largest measured load, through every measured load; with the
    load factor of each measured row (file order).

    Factor 1 is the measured load of largest magnitude (the scaled case's full load), so
    a limit point below it is below "full load" for :func:`failure_of`.
    """
    load = np.asarray(measurement.load, dtype=float)
    peak = float(load[np.argmax(np.abs(load))])
    scale = peak / case.magnitude  # > 0: the file's loads have the case's sign
    row_factors = load / peak
    levels = np.unique(np.concatenate(([0.0], row_factors)))
    components = tuple(dataclasses.replace(c, value=c.value * scale) for c in case.components)
    return (
        AtLoads(case.name, components, len(levels), case.time_law, tuple(levels.tolist())),
        row_factors,
    )


def trace_at_measured(
    scene: Scene,
    spec: ModelSpec,
    measurement: Measurement,
    cache=None,
    unmodelled_is_failure: bool = False,
) -> tuple[LoadPath | None, Failure | None]:
    """The path of ``spec`` through the measured loads, and its failure if it stops early.

    Parameters
    ----------
    cache : ResultCache or RunMemo, optional
        Where converged paths are kept and found (key: the scene, the model and the
        measured load factors).
    unmodelled_is_failure : bool
        A model that cannot represent the scene (SceneError, e.g. a PRBM of a spline) is
        a failure at load 0 (the report) instead of an error (the command line).

    Returns
    -------
    (LoadPath or None, Failure or None)
        The path (partial when the model stopped; None if nothing converged) and why it
        stopped (None when it reached the largest measured load).
    """
    from ..cache import result_key

    case = scene.load_case(measurement.load_case)
    traced, _ = traced_case(case, measurement)
    caught = (SolverError, SceneError) if unmodelled_is_failure else (SolverError,)
    try:
        if cache is None:
            return run_model(scene, spec, traced), None
        extra = {"measured_factors": list(traced.at), "full_load": traced.magnitude}
        key = result_key(scene, spec.id, case.name, None, extra)
        return cache.path(key, lambda: run_model(scene, spec, traced)), None
    except caught as exc:
        path = exc.path if isinstance(exc, SolverError) else None
        return path, failure_of(exc, scene, spec, traced)


def measured_range(values: np.ndarray) -> float:
    """The largest distance between two measured values: of the points (n, 2) or the
    scalars (n,) (mm or rad)."""
    v = np.asarray(values, dtype=float)
    if v.ndim == 1:
        return float(v.max() - v.min()) if v.size else 0.0
    unit = float(np.abs(v).max(initial=0.0))  # squares of tiny or huge values under- or overflow
    if unit == 0.0:
        return 0.0
    v = v / unit
    best = 0.0
    for start in range(0, len(v), _DIAMETER_BLOCK):
        block = v[start : start + _DIAMETER_BLOCK]
        d2 = sum((block[:, None, i] - v[None, :, i]) ** 2 for i in range(v.shape[1]))
        best = max(best, float(d2.max()))
    return unit * math.sqrt(best)


def _lengths(diff: np.ndarray) -> np.ndarray:
    """The Euclidean length of each row of ``diff`` (mm or rad), without the under- or
    overflow of squaring values near the ends of double precision."""
    unit = float(np.abs(diff).max(initial=0.0))
    if unit == 0.0:
        return np.zeros(len(diff))
    return unit * np.sqrt(((diff / unit) ** 2).sum(axis=1))


@dataclass
class ModelScore:
    """One model against the measurement.

    Attributes
    ----------
    model : str
    path : LoadPath or None
        Traced through the measured loads (partial when it stopped).
    failure : Failure or None
        Why the path stopped before the largest measured load (None: it did not).
    reached : numpy.ndarray of bool
        Per measured row (file order): within the model's traced path.
    at_measured : dict
        The model's ``dx``, ``dy`` (mm) and ``rotation`` (rad) at each measured row,
        NaN beyond its path.
    errors : dict
        :data:`SCORES` in percent (None where not defined).
    within_2u : dict
        ``disp`` and ``rot``: share (0 to 1) of the reached points within twice the
        standard uncertainty, or None.
    """

    model: str
    path: LoadPath | None
    failure: Failure | None
    reached: np.ndarray
    at_measured: dict[str, np.ndarray]
    errors: dict[str, float | None]
    within_2u: dict[str, float | None]

    @property
    def scored(self) -> int:
        """How many measured rows the model was scored on."""
        return int(self.reached.sum())


def _model_values(lp: LoadPath | None, peak: float, factors: np.ndarray) -> tuple:
    """(reached mask, {dx, dy, rotation} at ``factors``, NaN where not reached)."""
    nan = np.full(len(factors), np.nan)
    if lp is None or not lp.load:
        return np.zeros(len(factors), bool), {k: nan.copy() for k in ("dx", "dy", "rotation")}
    path_factors = np.asarray(lp.load, dtype=float) / peak
    last = float(path_factors[-1])
    reached = factors <= last * (1.0 + REACHED_RTOL)
    values = {}
    for k in ("dx", "dy", "rotation"):
        v = np.interp(factors, path_factors, np.asarray(getattr(lp, k), dtype=float))
        values[k] = np.where(reached, v, np.nan)
    return reached, values


def _quantity(m: Measurement, quantity: str) -> list[str]:
    """The measured columns of ``quantity`` ('disp': dx and/or dy; 'rot': rotation)."""
    wanted = ("dx", "dy") if quantity == "disp" else ("rotation",)
    return [c for c in wanted if c in m.columns]


def score_model(
    m: Measurement, spec_id: str, lp: LoadPath | None, failure: Failure | None, scene: Scene
) -> ModelScore:
    """Score one model's path against the measurement (see the module docstring)."""
    case = scene.load_case(m.load_case)
    traced, factors = traced_case(case, m)
    reached, values = _model_values(lp, traced.magnitude, factors)
    errors: dict[str, float | None] = dict.fromkeys(SCORES)
    within: dict[str, float | None] = {"disp": None, "rot": None}
    for quantity in ("disp", "rot"):
        cols = _quantity(m, quantity)
        if not cols:
            continue
        measured = np.column_stack([np.asarray(getattr(m, c)) for c in cols])
        span = measured_range(measured if len(cols) > 1 else measured[:, 0])
        if not reached.any():
            continue
        model = np.column_stack([values[c] for c in cols])[reached]
        diff = model - measured[reached]
        r = _lengths(diff)
        largest = float(r.max())
        if span > 0.0:
            rms = largest * math.sqrt(float(np.mean((r / largest) ** 2))) if largest > 0.0 else 0.0
            errors[f"{quantity}_rms"] = 100.0 * (rms / span)
            errors[f"{quantity}_max"] = 100.0 * (largest / span)
        stds = [m.std(c) for c in cols]
        if all(s is not None for s in stds):
            u = np.column_stack([np.asarray(s) for s in stds])[reached]
            within[quantity] = float(np.mean(np.all(np.abs(diff) <= 2.0 * u, axis=1)))
    return ModelScore(spec_id, lp, failure, reached, values, errors, within)


@dataclass
class MeasuredComparison:
    """Every requested model against one measurement of one scene."""

    scene: Scene
    measurement: Measurement
    scores: list[ModelScore]

    @property
    def case(self) -> LoadCase:
        """The measured load case (as the scene gives it)."""
        return self.scene.load_case(self.measurement.load_case)

    def ranges(self) -> dict[str, float | None]:
        """The measured ranges: ``disp`` (mm) and ``rot`` (deg), None where not measured."""
        m, out = self.measurement, {}
        for quantity in ("disp", "rot"):
            cols = _quantity(m, quantity)
            if not cols:
                out[quantity] = None
                continue
            data = np.column_stack([np.asarray(getattr(m, c)) for c in cols])
            span = measured_range(data if len(cols) > 1 else data[:, 0])
            out[quantity] = math.degrees(span) if quantity == "rot" else span
        return out

    def stopped(self) -> list[ModelScore]:
        """The models whose path stops before the largest measured load."""
        return [s for s in self.scores if s.failure is not None]

    def beyond_text(self, s: ModelScore) -> str:
        """Where a stopped model's path ends and from which measured row on the loads lie
        beyond it ('' for a model that reached the largest measured load)."""
        if s.failure is None:
            return ""
        m = self.measurement
        stop = f"stops at {self.reached_load(s):.4g} {m.unit} ({s.failure.reason})"
        beyond = np.flatnonzero(~s.reached)
        if beyond.size == 0:
            return stop
        first = int(beyond[np.argmin(np.abs(np.asarray(m.load)[beyond]))])
        plural = "s" if beyond.size > 1 else ""
        return (
            f"{stop}; {beyond.size} measured load{plural} beyond its path, from line "
            f"{m.lines[first]} ({m.load[first]:.4g} {m.unit}), not scored"
        )

    def reached_load(self, s: ModelScore) -> float:
        """The load (N or N mm) of the failure: the limit or bifurcation load, else the last
        converged load."""
        return float(s.failure.load) if s.failure is not None else float(s.path.load[-1])

    def record(self) -> dict:
        """JSON-ready: the measurement, its ranges and each model's scores and values at
        the measured loads (rotations in degrees), with its traced path."""
        m = self.measurement
        ranges = self.ranges()
        results = []
        for s in self.scores:
            beyond = None
            if s.failure is not None:
                rows = np.flatnonzero(~s.reached).tolist()
                beyond = {
                    "rows": len(rows),
                    "lines": [m.lines[k] for k in rows],
                    "reached_load": self.reached_load(s),
                    "reason": s.failure.reason,
                    "message": s.failure.message,
                }
            results.append(
                {
                    "model": s.model,
                    "scored": s.scored,
                    "errors": s.errors,
                    "within_2std": s.within_2u,
                    "beyond": beyond,
                    "at_measured": {
                        "dx": s.at_measured["dx"],
                        "dy": s.at_measured["dy"],
                        "rotation_deg": np.degrees(s.at_measured["rotation"]),
                    },
                    "path": s.path.to_dict() if s.path is not None else None,
                }
            )
        return {
            "scene": self.scene.name,
            "load_case": m.load_case,
            "measured": {
                "file": m.source,
                "load_unit": m.unit,
                "columns": list(m.columns),
                "load": list(m.load),
                "lines": list(m.lines),
                **{c: list(getattr(m, c)) for c in ("dx", "dy") if c in m.columns},
                **(
                    {"rotation_deg": np.degrees(m.rotation).tolist()}
                    if m.rotation is not None
                    else {}
                ),
                "range": {"disp_mm": ranges["disp"], "rot_deg": ranges["rot"]},
            },
            "results": results,
        }


def compare_measurement(
    scene: Scene,
    measurement: Measurement,
    specs: list[ModelSpec],
    cache=None,
    unmodelled_is_failure: bool = False,
) -> MeasuredComparison:
    """Trace and score every model of ``specs`` against ``measurement`` (module docstring)."""
    scores = []
    for spec in specs:
        lp, failure = trace_at_measured(scene, spec, measurement, cache, unmodelled_is_failure)
        scores.append(score_model(measurement, spec.id, lp, failure, scene))
    return MeasuredComparison(scene, measurement, scores)
