"""``flexval gate``: the verdicts of a gates file (:mod:`flexval.validation.studies.gatefile`).

Every gated model and the reference run on every load case of every scene;
each (model, scene, case, metric) is one :class:`Check`: the model's error
against the reference (percent, :func:`flexval.validation.studies.compare.errors`,
and the peak fibre stress at full load of
:func:`flexval.validation.report.strength.peak_at_full_load`) and its threshold. A
model that cannot reach full load fails its checks on that case, with the
solver's reason; a reference that cannot is a :class:`ReferenceFailure` (no
verdict is possible).

``limit_load`` compares first critical loads and ``frequency`` natural
frequencies, both found as the report finds them
(:mod:`flexval.validation.studies.gatemetrics`): a limit or bifurcation point below full
load is their subject, not a failure. ``frequency`` is one check per scene and
model (load case ``rest``). Each of these checks says in ``detail`` what was
compared (the loads and their kinds; the worst mode and the flexure density).

Paths come from the result cache (:mod:`flexval.validation.cache`: exact
scene, model id and code), so a CI job that keeps the cache between runs
recomputes nothing that did not change; plug-in families
(:mod:`flexval.reducedmodels.plugins`) are always run, since the cache key
holds flexval's code, not theirs.
"""

from __future__ import annotations

from dataclasses import dataclass

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.reducedmodels import LoadPath, ModelSpec, PluginFailure, SolverError
from flexval.reducedmodels.catalogue import plugin_of

from ..cache import ResultCache
from ..report.frequencies import mode_errors
from .campaign import Job, RunMemo, prefetch, timed_run
from .compare import errors
from .gatefile import (
    FREQUENCY_METRICS,
    LIMIT_METRICS,
    PARASITIC_METRICS,
    PATH_METRICS,
    STRESS_METRICS,
    Gate,
    GateFile,
)
from .gatemetrics import SEARCH_RANGE, Critical, Frequencies, critical_load, natural_frequencies
from .parasitic import largest_parasitic_error


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
        stress, has a critical load where the reference has none); empty otherwise.
    seconds : float
        The model's run time on the case (s; of the run that filled the cache
        when cached).
    detail : str
        What was compared, where the value alone does not say (``limit_load``:
        the two critical loads; ``frequency``: the worst mode, its frequencies
        and the flexure density); empty otherwise.
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
    detail: str = ""

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
            "detail": self.detail,
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


CASE_METRICS = PATH_METRICS + STRESS_METRICS + PARASITIC_METRICS
"""The metrics read from the load-control path at full load (its reference must reach it)."""
REST = "rest"
"""The load case name of a ``frequency`` check (the report's name for the rest state)."""


def _needs(metrics, wanted: tuple[str, ...]) -> bool:
    return any(m in metrics for m in wanted)


def _wanted(gates: GateFile) -> list[tuple[ModelSpec, set[str], set[int]]]:
    """Every model to compute, the reference first: its metrics and the mode counts of its
    ``frequency`` gates (the reference's: the union of every gate's)."""
    own = [
        (g.model, set(g.thresholds), {g.modes} if "frequency" in g.thresholds else set())
        for g in gates.gates
    ]
    metrics = set().union(*(m for _, m, _ in own))
    counts = set().union(*(c for _, _, c in own))
    return [(gates.reference, metrics, counts)] + own


def _jobs(gates: GateFile, cacheable_only: bool) -> list[Job]:
    """The load-control paths to compute ahead (those of the path, stress and limit-load
    gates)."""
    return [
        Job(scene, spec, scene.load_case(c), 1, False)
        for spec, metrics, _ in _wanted(gates)
        if _needs(metrics, CASE_METRICS + LIMIT_METRICS)
        and (not cacheable_only or _cacheable(spec))
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
    """Compute every cacheable result of ``gates`` into ``cache`` (no verdict): the load
    paths, and the critical loads and natural frequencies that ``limit_load`` and
    ``frequency`` gates compare.

    Returns the number of results now cached and the lines of those that failed
    (model, scene, case, reason).
    """
    memo = RunMemo(cache)
    _prefetch(_jobs(gates, cacheable_only=True), memo, workers, progress)
    done, failed = 0, []
    for spec, metrics, counts in _wanted(gates):
        if not _cacheable(spec):
            continue
        for scene in gates.scenes:
            for c in (
                gates.cases[scene.name] if _needs(metrics, CASE_METRICS + LIMIT_METRICS) else ()
            ):
                case = scene.load_case(c)
                if _needs(metrics, CASE_METRICS):
                    try:
                        _path(scene, spec, case, memo)
                        done += 1
                    except (SolverError, SceneError) as exc:
                        failed.append(f"{spec.id} {scene.name} {c}: {exc}")
                if _needs(metrics, LIMIT_METRICS):
                    found = critical_load(scene, spec, case, memo)
                    if found.failure:
                        failed.append(f"{spec.id} {scene.name} {c}: {found.failure}")
                    else:
                        done += 1
            for count in sorted(counts):
                modes = natural_frequencies(scene, spec, count, cache)
                if modes.failure:
                    failed.append(f"{spec.id} {scene.name} {REST}: {modes.failure}")
                else:
                    done += 1
    return done, failed


def _peak(lp: LoadPath) -> float | None:
    """The largest peak fibre stress over the flexures at full load (MPa), or None: the
    ``stress`` of :func:`flexval.validation.report.strength.peak_at_full_load`, read here without
    that module's plotting imports (half a warm gate's time)."""
    if not lp.peak_stress:
        return None
    return float(max(values[-1] for values in lp.peak_stress.values()))


NOTHING_PARASITIC = (
    "nothing to score: the load case has no parasitic component, or the reference's is round-off"
)


def _values(
    lp: LoadPath, ref: LoadPath, scene: Scene, case: LoadCase, metrics
) -> dict[str, float | None]:
    out: dict[str, float | None] = {}
    if "parasitic" in metrics:
        out["parasitic"] = largest_parasitic_error(lp, ref, scene, case)
    if any(m in PATH_METRICS for m in metrics):
        out.update({k: float(v) for k, v in errors(lp, ref, scene.mechanism.size()).items()})
    if "peak_stress" in metrics:
        peak, ref_peak = _peak(lp), _peak(ref)
        out["peak_stress"] = (
            None if peak is None or not ref_peak else 100.0 * abs(peak - ref_peak) / ref_peak
        )
    return out


@dataclass
class _References:
    """The reference's results that the gates compare with, by scene and case."""

    paths: dict[tuple[str, str], LoadPath]
    critical: dict[tuple[str, str], Critical]
    frequencies: dict[tuple[str, int], Frequencies]


def _references(gates: GateFile, memo: RunMemo) -> _References:
    """The reference's paths, critical loads and natural frequencies that the gates need.

    Raises
    ------
    ReferenceFailure
        If the reference cannot reach full load where a path or stress gate needs it,
        finds neither full load nor a critical load where a limit-load gate needs one, or
        its modal analysis fails.
    """
    spec, metrics, counts = _wanted(gates)[0]
    refs = _References({}, {}, {})
    cacheable = _cacheable(spec)
    for scene in gates.scenes:
        for c in gates.cases[scene.name]:
            case = scene.load_case(c)
            where = f"reference {spec.id} on {scene.name} {c}"
            if _needs(metrics, CASE_METRICS):
                try:
                    refs.paths[scene.name, c] = _path(scene, spec, case, memo)
                except (SolverError, SceneError) as exc:
                    raise ReferenceFailure(f"{where}: {exc}") from None
            if _needs(metrics, LIMIT_METRICS):
                found = critical_load(scene, spec, case, memo, cacheable)
                if found.failure:
                    raise ReferenceFailure(f"{where}: {found.failure}")
                refs.critical[scene.name, c] = found
        for count in sorted(counts):
            modes = natural_frequencies(scene, spec, count, memo.disk, cacheable)
            if modes.failure or not modes.values:
                why = modes.failure or "no mode"
                raise ReferenceFailure(
                    f"reference {spec.id} on {scene.name}: modal analysis failed: {why}"
                )
            refs.frequencies[scene.name, count] = modes
    return refs


def _path_checks(gate: Gate, scene: Scene, case: LoadCase, ref: LoadPath, memo: RunMemo):
    """The path and stress checks of ``gate`` on ``case``."""
    reason, values, seconds = "", {}, 0.0
    try:
        lp = _path(scene, gate.model, case, memo)
        values, seconds = _values(lp, ref, scene, case, gate.thresholds), lp.seconds
    except PluginFailure:
        raise  # the plug-in's code, not the model's accuracy: no verdict
    except SolverError as exc:
        reason = f"did not reach full load ({100 * exc.load_factor:.0f} %): {exc}"
    except SceneError as exc:
        reason = f"cannot model the scene: {exc.reason}"
    for metric, threshold in gate.thresholds.items():
        if metric not in CASE_METRICS:
            continue
        value = values.get(metric)
        if metric == "parasitic" and value is None and not reason:
            yield Check(
                gate.model.id,
                scene.name,
                case.name,
                metric,
                None,
                threshold,
                True,
                NOTHING_PARASITIC,
                seconds,
            )
            continue
        why = reason or ("" if value is not None else NO_PEAK.format(gate.model.id))
        passed = bool(value is not None and value <= threshold)
        yield Check(
            gate.model.id, scene.name, case.name, metric, value, threshold, passed, why, seconds
        )


def _none_within(case: LoadCase) -> str:
    return (
        f"no critical load within {SEARCH_RANGE:g} times the load "
        f"({SEARCH_RANGE * case.magnitude:.5g} {case.unit})"
    )


def _limit_check(gate: Gate, scene: Scene, case: LoadCase, ref: Critical, memo: RunMemo) -> Check:
    """The ``limit_load`` check of ``gate`` on ``case``: the first critical loads compared."""
    own = critical_load(scene, gate.model, case, memo, _cacheable(gate.model))
    threshold = gate.thresholds["limit_load"]

    def check(value: float | None, passed: bool, reason: str = "", detail: str = "") -> Check:
        return Check(
            gate.model.id,
            scene.name,
            case.name,
            "limit_load",
            value,
            threshold,
            passed,
            reason,
            own.seconds,
            detail,
        )

    if own.failure:
        return check(None, False, own.failure)
    if own.kind is None and ref.kind is None:
        return check(None, True, detail=_none_within(case))
    if own.kind is None or ref.kind is None:
        text = (
            f"{gate.model.id}: {own.describe() if own.kind else _none_within(case)}; "
            f"the reference: {ref.describe() if ref.kind else _none_within(case)}"
        )
        return check(None, False, text, text)
    signed = 100.0 * (own.load - ref.load) / ref.load
    detail = f"{own.describe()} against the reference's {ref.describe()} ({signed:+.4g} %)"
    return check(abs(signed), abs(signed) <= threshold, detail=detail)


def _frequency_check(gate: Gate, scene: Scene, ref: Frequencies, cache: ResultCache) -> Check:
    """The ``frequency`` check of ``gate`` on ``scene``: the worst of its lowest modes."""
    own = natural_frequencies(scene, gate.model, gate.modes, cache, _cacheable(gate.model))
    threshold = gate.thresholds["frequency"]
    density = own.density.describe()

    def check(value: float | None, reason: str = "", detail: str = "") -> Check:
        passed = bool(value is not None and value <= threshold)
        return Check(
            gate.model.id,
            scene.name,
            REST,
            "frequency",
            value,
            threshold,
            passed,
            reason,
            own.seconds,
            detail,
        )

    if own.failure:
        return check(None, f"modal analysis failed: {own.failure}", density)
    n = min(gate.modes, len(ref.values))
    if len(own.values) < n:
        text = f"{gate.model.id} has {len(own.values)} modes, the reference {n}"
        return check(None, text, f"{text}; {density}")
    errs = mode_errors(own.values[:n], ref.values[:n])
    k = max(range(n), key=lambda j: abs(errs[j]))
    detail = (
        f"mode {k + 1} of {n}: {own.values[k]:.6g} Hz against the reference's "
        f"{ref.values[k]:.6g} Hz ({errs[k]:+.4g} %); {density}"
    )
    return check(abs(errs[k]), detail=detail)


def evaluate(
    gates: GateFile, cache: ResultCache, workers: int = 1, progress: bool = True
) -> list[Check]:
    """Every check of ``gates``, in the order model, scene, case, metric (a scene's
    ``frequency`` check after its load cases').

    Raises
    ------
    ReferenceFailure
        If the reference cannot give what a gate compares with (see
        :func:`_references`), or cannot represent a scene.
    flexval.reducedmodels.PluginFailure
        If a gated plug-in family's code raises: no verdict is given on it.
    """
    memo = RunMemo(cache)
    _prefetch(_jobs(gates, cacheable_only=True), memo, workers, progress)
    refs = _references(gates, memo)
    checks: list[Check] = []
    for gate in gates.gates:
        for scene in gates.scenes:
            for c in gates.cases[scene.name]:
                case = scene.load_case(c)
                if _needs(gate.thresholds, CASE_METRICS):
                    checks += _path_checks(gate, scene, case, refs.paths[scene.name, c], memo)
                if _needs(gate.thresholds, LIMIT_METRICS):
                    checks.append(
                        _limit_check(gate, scene, case, refs.critical[scene.name, c], memo)
                    )
            if _needs(gate.thresholds, FREQUENCY_METRICS):
                ref = refs.frequencies[scene.name, gate.modes]
                checks.append(_frequency_check(gate, scene, ref, cache))
    return checks


def summary_record(gates: GateFile, checks: list[Check]) -> dict:
    """The JSON document of ``flexval gate --json``."""
    from ..cache import code_version

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
