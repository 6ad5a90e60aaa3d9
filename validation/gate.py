"""``flexval gate``: the verdicts of a gates file (:mod:`flexval.validation.gatefile`).

Every gated model and the reference run on every load case of every scene;
each (model, scene, case, metric) is one :class:`Check`: the model's error
against the reference (percent, :func:`flexval.validation.compare.errors`,
and the peak fibre stress at full load of
:func:`flexval.validation.strength.peak_at_full_load`) and its threshold. A
model that cannot reach full load fails its checks on that case, with the
solver's reason; a reference that cannot is a :class:`ReferenceFailure` (no
verdict is possible).

Paths come from the result cache (:mod:`flexval.validation.cache`: exact
scene, model id and code), so a CI job that keeps the cache between runs
recomputes nothing that did not change; plug-in families
(:mod:`flexval.reducedmodels.plugins`) are always run, since the cache key
holds flexval's code, not theirs.
"""

from __future__ import annotations

from dataclasses import dataclass

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.reducedmodels import LoadPath, ModelSpec, SolverError
from flexval.reducedmodels.catalogue import plugin_of

from .cache import ResultCache
from .campaign import Job, RunMemo, prefetch, timed_run
from .compare import errors
from .gatefile import PATH_METRICS, GateFile


@dataclass(frozen=True)
class Check:
    """One gate on one load case: a model's error in one metric and its threshold.

    Attributes
    ----------
    model, scene, case, metric : str
    value : float or None
        The error, percent (None when the model has no result: see ``reason``).
    threshold : float
        The largest error allowed, percent.
    passed : bool
    reason : str
        Why there is no value (the model did not reach full load, has no peak
        stress); empty otherwise.
    seconds : float
        The model's run time on the case (s; of the run that filled the cache
        when cached).
    """

    model: str
    scene: str
    case: str
    metric: str
    value: float | None
    threshold: float
    passed: bool
    reason: str = ""
    seconds: float = 0.0

    def to_dict(self) -> dict:
        """JSON form."""
        return {
            "model": self.model,
            "scene": self.scene,
            "case": self.case,
            "metric": self.metric,
            "value_percent": self.value,
            "threshold_percent": self.threshold,
            "passed": self.passed,
            "reason": self.reason,
            "seconds": self.seconds,
        }


NO_PEAK = "{} or the reference gives no peak stress"
"""The reason of a ``peak_stress`` check without a value."""


class ReferenceFailure(Exception):
    """The reference did not reach full load on a case: no verdict is possible."""


def _cacheable(spec: ModelSpec) -> bool:
    return plugin_of(spec.family) is None


def _path(scene: Scene, spec: ModelSpec, case: LoadCase, memo: RunMemo) -> LoadPath:
    """One path, from the memo or the disk cache or run now (stored when cacheable)."""
    return timed_run(scene, spec, case, 1, memo if _cacheable(spec) else None)


def _jobs(gates: GateFile, cacheable_only: bool) -> list[Job]:
    specs = [gates.reference] + [g.model for g in gates.gates]
    return [
        Job(scene, spec, scene.load_case(c), 1, False)
        for spec in specs
        if not cacheable_only or _cacheable(spec)
        for scene in gates.scenes
        for c in gates.cases[scene.name]
    ]


def _prefetch(jobs: list[Job], memo: RunMemo, workers: int, progress: bool) -> None:
    """Compute the jobs whose paths are not in the cache on ``workers`` processes (no process
    is started when the cache holds every path)."""
    missing = []
    for job in jobs:
        hit = memo.disk.get(job.key)
        if hit is None:
            missing.append(job)
        else:
            hit.stats["cached"] = True
            memo.remember(job.key, hit)
    prefetch(missing, memo, workers, progress)


def prepare(
    gates: GateFile, cache: ResultCache, workers: int = 1, progress: bool = True
) -> tuple[int, list[str]]:
    """Compute every cacheable path of ``gates`` into ``cache`` (no verdict).

    Returns the number of paths now cached and the lines of the paths that
    failed (model, scene, case, reason).
    """
    jobs = _jobs(gates, cacheable_only=True)
    memo = RunMemo(cache)
    _prefetch(jobs, memo, workers, progress)
    failed = []
    for job in jobs:
        try:
            _path(job.scene, job.spec, job.case, memo)
        except (SolverError, SceneError) as exc:
            failed.append(f"{job.spec.id} {job.scene.name} {job.case.name}: {exc}")
    return len(jobs) - len(failed), failed


def _peak(lp: LoadPath) -> float | None:
    """The largest peak fibre stress over the flexures at full load (MPa), or None: the
    ``stress`` of :func:`flexval.validation.strength.peak_at_full_load`, read here without
    that module's plotting imports (half a warm gate's time)."""
    if not lp.peak_stress:
        return None
    return float(max(values[-1] for values in lp.peak_stress.values()))


def _values(lp: LoadPath, ref: LoadPath, scene: Scene, metrics) -> dict[str, float | None]:
    out: dict[str, float | None] = {}
    if any(m in PATH_METRICS for m in metrics):
        out.update({k: float(v) for k, v in errors(lp, ref, scene.mechanism.size()).items()})
    if "peak_stress" in metrics:
        peak, ref_peak = _peak(lp), _peak(ref)
        out["peak_stress"] = (
            None if peak is None or not ref_peak else 100.0 * abs(peak - ref_peak) / ref_peak
        )
    return out


def evaluate(
    gates: GateFile, cache: ResultCache, workers: int = 1, progress: bool = True
) -> list[Check]:
    """Every check of ``gates``, in the order model, scene, case, metric.

    Raises
    ------
    ReferenceFailure
        If the reference cannot reach full load on a case (or cannot
        represent a scene).
    """
    memo = RunMemo(cache)
    _prefetch(_jobs(gates, cacheable_only=True), memo, workers, progress)
    refs: dict[tuple[str, str], LoadPath] = {}
    for scene in gates.scenes:
        for c in gates.cases[scene.name]:
            try:
                refs[scene.name, c] = _path(scene, gates.reference, scene.load_case(c), memo)
            except (SolverError, SceneError) as exc:
                raise ReferenceFailure(
                    f"reference {gates.reference.id} on {scene.name} {c}: {exc}"
                ) from None
    checks = []
    for gate in gates.gates:
        for scene in gates.scenes:
            for c in gates.cases[scene.name]:
                reason, values, seconds = "", {}, 0.0
                try:
                    lp = _path(scene, gate.model, scene.load_case(c), memo)
                    values, seconds = (
                        _values(lp, refs[scene.name, c], scene, gate.thresholds),
                        lp.seconds,
                    )
                except SolverError as exc:
                    reason = f"did not reach full load ({100 * exc.load_factor:.0f} %): {exc}"
                except SceneError as exc:
                    reason = f"cannot model the scene: {exc.reason}"
                for metric, threshold in gate.thresholds.items():
                    value = values.get(metric)
                    why = reason or ("" if value is not None else NO_PEAK.format(gate.model.id))
                    checks.append(
                        Check(
                            gate.model.id,
                            scene.name,
                            c,
                            metric,
                            value,
                            threshold,
                            bool(value is not None and value <= threshold),
                            why,
                            seconds,
                        )
                    )
    return checks


def summary_record(gates: GateFile, checks: list[Check]) -> dict:
    """The JSON document of ``flexval gate --json``."""
    from .cache import code_version

    failed = [c for c in checks if not c.passed]
    return {
        "gates_file": gates.source,
        "reference": gates.reference.id,
        "code_version": code_version(),
        "passed": not failed,
        "checks": len(checks),
        "failures": len(failed),
        "results": [c.to_dict() for c in checks],
    }
