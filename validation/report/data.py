"""The validation report's data: every model run and every figure, computed once.

:func:`compute_report` runs every requested model on every load case of each
scene (cached), the measuring-frame variants, the runtime-versus-error and
convergence studies, and returns a :class:`ReportData`; the renderers of
:mod:`flexval.validation.report.writer` and :mod:`flexval.validation.report.timings` only format
it. Every
load path of every study is listed first (``_Plan.jobs``) and, with several
workers, computed ahead on that many processes
(:func:`flexval.validation.studies.campaign.prefetch`); a path two studies share (the
reference in the campaign, the bench and the convergence study) is computed
once. A model that fails on a load case
is a result (:class:`flexval.validation.failures.Failure`), kept beside the paths.
Everything the report says about a scene comes from its data: the paper's
figures attach to a scene by its name in ``validation/data/paper_results.toml``,
and the chain's topology is the cycle rank of its body graph.

Units: mm, N, N mm, rad; errors in percent; times in s.
"""

from __future__ import annotations

import json
import platform
import time
from dataclasses import dataclass, field
from functools import cached_property
from importlib import metadata
from pathlib import Path

from flexval.geometry import LoadCase, Scene, load_scene
from flexval.geometry.graph import independent_loops
from flexval.reducedmodels import LoadPath
from flexval.reducedmodels.catalogue import REFERENCE, ModelSpec, parse_model

from ..cache import ResultCache, code_version
from ..failures import Failure
from ..studies.batchtiming import BatchMemo, BatchTiming
from ..studies.bench import TIMING_KEYS, runtime_vs_error, sweep_specs
from ..studies.campaign import Job, Progress, RunMemo, prefetch, run_campaign, timed_run
from ..studies.compare import errors, paper_percent, paper_scene, paper_seconds
from ..studies.convergence import ConvergenceStudy, study
from ..studies.measuredcompare import MeasuredComparison, compare_measurement
from ..studies.peers import PeerRow, PeerUnavailable, compare_with_opensees
from .frequencies import FrequencyTable, frequency_data
from .stiffnesstable import StiffnessTable, stiffness_data

DEFAULT_MODELS = ("continuum", "beam:100", "beam:20", "prbm", "dcmm:1", "dcmm:2", "dcmm:3", "ee")
#: the paper's reference (its FEM100): every scene is compared against it
PAPER_REFERENCE = "beam:100"
#: reference of the runtime-versus-error study when no reference model is requested
BENCH_REFERENCE = "beam:400"
NOTCH_COMPARED = ("beam:100", "prbm")
"""Models a scene with notch hinges is also run with plain Euler-Bernoulli hinges (``[eb]``):
the calibrated correction's effect (:mod:`flexval.reducedmodels.notchcorrection`) beside it."""
#: option whose values the frame-sensitivity table compares (DCMM's measuring frame)
FRAME_OPTION = "frame"
#: option of the reference whose other value brackets it (a wide flexure, b >> h, lies
#: between plane stress and plane strain)
PLANE_OPTION = "plane"


@dataclass
class PaperData:
    """The paper's figures for one scene (see
    :func:`flexval.validation.studies.compare.paper_scene`)."""

    percent: dict[str, dict[str, dict[str, float]]]
    seconds: dict[str, dict[str, float]]
    percent_table: str
    seconds_table: str
    relative_rotations_figure: str | None = None

    @classmethod
    def of(cls, scene: Scene) -> PaperData | None:
        """The paper's data attached to ``scene`` by its name, or None."""
        data = paper_scene(scene.name)
        if data is None:
            return None
        cases = [c.name for c in scene.load_cases]
        if list(data["load_cases"]) != cases:
            return None  # a scene of the same name but other load cases
        return cls(
            paper_percent(scene.name, cases),
            paper_seconds(scene.name, cases),
            data["percent_table"],
            data["seconds_table"],
            data.get("relative_rotations_figure"),
        )


@dataclass
class FrameRow:
    """One model with one value of its measuring-frame option, on every load case.

    ``cells`` maps each load case to its errors against :data:`PAPER_REFERENCE`
    (:func:`flexval.validation.studies.compare.errors`), a :class:`Failure`, or None (no
    reference path).
    """

    model: str
    frame: str
    cells: dict[str, dict[str, float] | Failure | None]


@dataclass
class PlaneBracket:
    """The continuum reference with its other plane assumption, on every load case.

    ``paths`` maps each load case to the path of ``model`` (the reference with
    :data:`PLANE_OPTION` switched, e.g. ``continuum:1[plane=strain]``); a
    failure is listed in ``failures`` instead.
    """

    model: str
    paths: dict[str, LoadPath]
    failures: list[Failure]

    def seconds(self) -> float:
        """Wall time of its runs (s): what the bracket adds to the report."""
        return sum(lp.seconds for lp in self.paths.values())


@dataclass
class SceneResults:
    """Everything the report says about one scene (computed by :func:`compute_report`).

    ``paths`` holds every model's path on every case, partial for a model that
    failed; ``failures`` the failures (a list, in run order).
    """

    scene: Scene
    paths: dict[tuple[str, str], LoadPath]
    failures: list[Failure]
    models: list[str]
    reference: str | None = None
    frames: list[FrameRow] = field(default_factory=list)
    bench_rows: list[dict] = field(default_factory=list)
    bench_reference: str = ""
    bench_failures: list[Failure] = field(default_factory=list)
    convergence: list[ConvergenceStudy] = field(default_factory=list)
    frequencies: FrequencyTable | None = None
    stiffness: StiffnessTable | None = None
    bracket: PlaneBracket | None = None
    peers: list[PeerRow] | str | None = None  # the OpenSees comparison, why not, or not asked
    measured: list[MeasuredComparison] = field(default_factory=list)  # [[measurements]]
    #: {(model, case): batched cost per path} of the batched models (not the reference)
    batched: dict[tuple[str, str], BatchTiming] = field(default_factory=dict)

    @property
    def cases(self) -> list[str]:
        """Load case names, in the scene's order."""
        return [c.name for c in self.scene.load_cases]

    @cached_property
    def paper(self) -> PaperData | None:
        """The paper's figures for this scene, or None."""
        return PaperData.of(self.scene)

    @cached_property
    def loops(self) -> int:
        """Independent closed loops of the mechanism (0: open chain)."""
        return independent_loops(self.scene.mechanism)

    def failure(self, model: str, case: str) -> Failure | None:
        """The failure of ``model`` on ``case``, or None."""
        return next((f for f in self.failures if f.model == model and f.load_case == case), None)

    def bifurcations(self) -> list[tuple[str, str, dict, str]]:
        """(model, case, first bifurcation ``{"load", "fraction"}``, load unit) of every
        load-control path that has one (passed, or where it stopped), in model and case order."""
        return [
            (m, c, lp.bifurcations[0], lp.load_unit)
            for m in self.models
            for c in self.cases
            if (lp := self.paths.get((m, c))) is not None and lp.bifurcations
        ]

    def past_reference_bifurcation(self) -> list[tuple[str, str, dict, str]]:
        """(model, case, the reference's first bifurcation, load unit) of every model that
        reached the full load on a case where the reference stops at (or passes) a
        bifurcation below it: a path the mechanism does not follow stably (in model and
        case order; the reference itself excluded)."""
        reference = {c: (b, unit) for m, c, b, unit in self.bifurcations() if m == self.reference}
        return [
            (m, c, *reference[c])
            for m in self.models
            for c in self.cases
            if m != self.reference
            and c in reference
            and reference[c][0]["fraction"] < 1.0
            and (lp := self.converged(m, c)) is not None
            and not lp.bifurcations
        ]

    def traces(self, case: str) -> dict[str, LoadPath]:
        """{model: arc-length path through its limit point} of the models failing on ``case``."""
        return {
            f.model: f.trace for f in self.failures if f.load_case == case and f.trace is not None
        }

    def converged(self, model: str, case: str) -> LoadPath | None:
        """The path of ``model`` on ``case`` if it reached full load, else None."""
        lp = self.paths.get((model, case))
        return lp if lp is not None and lp.converged else None

    def error_table(self, reference: str) -> dict[str, dict[str, dict[str, float]]]:
        """{model: {case: metrics}} against ``reference`` (only paths both reached in full)."""
        out: dict[str, dict[str, dict[str, float]]] = {}
        for m in self.models:
            if m == reference:
                continue
            for c in self.cases:
                lp, ref = self.converged(m, c), self.converged(reference, c)
                if lp is not None and ref is not None:
                    out.setdefault(m, {})[c] = errors(lp, ref, self.scene.mechanism.size())
        return out

    def worst_errors(self, reference: str) -> list[tuple[str, float, str]]:
        """(model, largest path displacement error in percent, its load case) of every
        model that reached full load on every case, in the report's model order."""
        failed = {f.model for f in self.failures}
        rows = []
        for m, per_case in self.error_table(reference).items():
            if m in failed or len(per_case) < len(self.cases):
                continue
            worst_case = max(per_case, key=lambda c: per_case[c]["path_disp"])
            rows.append((m, per_case[worst_case]["path_disp"], worst_case))
        return rows

    def bracket_rows(self) -> dict[str, dict[str, float]]:
        """{case: end |d| (mm) and rotation (rad) in both planes, and their spreads (%)}.

        Keys ``disp``/``disp_other``/``rot``/``rot_other`` (reference, then the
        bracket's other plane) and ``disp_spread``/``rot_spread``: the other
        plane's ``end_disp`` and ``end_rot`` errors against the reference
        (:func:`flexval.validation.studies.compare.errors`, percent: |other - reference| /
        |reference|, or of the scale where the reference is near zero), so they
        compare with the models' errors by the same rule. Cases where either path
        did not reach full load are left out.
        """
        out: dict[str, dict[str, float]] = {}
        if self.bracket is None or self.reference is None:
            return out
        for c in self.cases:
            ref, other = self.converged(self.reference, c), self.bracket.paths.get(c)
            if ref is None or other is None or not other.converged:
                continue
            e = errors(other, ref, self.scene.mechanism.size())
            out[c] = {
                "disp": float(ref.displacement[-1]),
                "disp_other": float(other.displacement[-1]),
                "rot": float(ref.rotation[-1]),
                "rot_other": float(other.rotation[-1]),
                "disp_spread": float(e["end_disp"]),
                "rot_spread": float(e["end_rot"]),
            }
        return out

    def has_reference(self) -> bool:
        """Whether the reference model ran on this scene."""
        return self.reference is not None and any(k[0] == self.reference for k in self.paths)


@dataclass
class ReportData:
    """Everything the report says: the scenes' results and the run's setting."""

    scenes: list[SceneResults]
    models: list[str]
    reference: str | None
    repeats: int
    versions: str
    code: str
    workers: int = 1
    wall_seconds: dict[str, float] = field(default_factory=dict)

    @property
    def references(self) -> list[str]:
        """The references every error table is computed against."""
        return [PAPER_REFERENCE] + ([self.reference] if self.reference else [])

    def gates(self) -> dict:
        """{scene: {reference: error table}}: the baseline of the CI accuracy gates."""
        return {
            r.scene.name: {ref: r.error_table(ref) for ref in self.references} for r in self.scenes
        }

    def results(self) -> dict:
        """Every LoadPath, failure and bench row, JSON-ready, without run times.

        Each path is its :meth:`~reducedmodels.LoadPath.to_dict` without the
        fields of :data:`LEFT_OUT` and the statistics of :data:`TIMING_STATS`;
        bench rows lose their ``seconds``. The same code gives the same text,
        whatever the machine's load (:func:`timings` holds the times).
        """
        return {
            "code_version": self.code,
            "scenes": {
                r.scene.name: {
                    "results": [_stable(lp) for lp in r.paths.values()],
                    "failures": [f.to_dict() for f in r.failures],
                    "bench": [
                        {k: v for k, v in row.items() if k not in TIMING_KEYS}
                        for row in r.bench_rows
                    ],
                }
                for r in self.scenes
            },
        }

    def timings(self) -> dict:
        """Every run time of the report, JSON-ready (s): per path the median and its
        samples and whether it came from the cache; the batched cost per path
        (:mod:`flexval.validation.studies.batchtiming`); the bench rows, the plane
        bracket's and the convergence studies' runs; the report's wall times."""
        scenes = {}
        for r in self.scenes:
            scenes[r.scene.name] = {
                "paths": [
                    {
                        "model": lp.model,
                        "load_case": lp.load_case,
                        "seconds": lp.seconds,
                        "samples": lp.stats.get("seconds_samples", [lp.seconds]),
                        "cached": bool(lp.stats.get("cached", False)),
                    }
                    for lp in r.paths.values()
                ],
                "batched": [t.to_dict() for t in r.batched.values()],
                "bench": [
                    {"model": row["model"], **{k: row.get(k) for k in TIMING_KEYS}}
                    for row in r.bench_rows
                ],
                "bracket": (
                    {"model": r.bracket.model, "seconds": r.bracket.seconds()}
                    if r.bracket
                    else None
                ),
                "convergence": [
                    {
                        "family": st.family,
                        "load_case": st.load_case,
                        "rows": [
                            {"model": row["model"], "seconds": row["seconds"]} for row in st.rows
                        ],
                    }
                    for st in r.convergence
                ],
                "peers": (
                    r.peers
                    if isinstance(r.peers, str) or r.peers is None
                    else [row.to_dict() for row in r.peers]
                ),
            }
        return {
            "code_version": self.code,
            "repeats": self.repeats,
            "workers": self.workers,
            "wall_seconds": self.wall_seconds,
            "scenes": scenes,
        }


#: LoadPath fields left out of results.json: the run time (in timings.json) and the
#: per-level drawing data (deformed shapes, section forces and stress profiles along the
#: flexures: drawn in the figures, kept in the result cache, recorded again by
#: ``flexval run``)
LEFT_OUT = ("seconds", "shapes", "section_forces", "stress_profile")
#: solver statistics that are run times or cache state (in timings.json)
TIMING_STATS = ("seconds_median", "seconds_samples", "cached")


def _stable(lp: LoadPath) -> dict:
    """``lp`` as results.json holds it (see :meth:`ReportData.results`)."""
    d = {k: v for k, v in lp.to_dict().items() if k not in LEFT_OUT}
    d["stats"] = {k: v for k, v in lp.stats.items() if k not in TIMING_STATS}
    return d


def read_results(folder: Path) -> dict[str, dict[tuple[str, str], LoadPath]]:
    """The LoadPaths of a written report, {scene: {(model, case): path}}, from its
    ``results.json`` with each path's seconds from ``timings.json`` (the fields of
    :data:`LEFT_OUT` but ``seconds`` stay empty)."""
    results = json.loads((folder / "results.json").read_text(encoding="utf-8"))["scenes"]
    times = json.loads((folder / "timings.json").read_text(encoding="utf-8"))["scenes"]
    out: dict[str, dict[tuple[str, str], LoadPath]] = {}
    for scene, data in results.items():
        secs = {(t["model"], t["load_case"]): t["seconds"] for t in times[scene]["paths"]}
        out[scene] = {
            (r["model"], r["load_case"]): LoadPath.from_dict(
                {**r, "seconds": secs[(r["model"], r["load_case"])]}
            )
            for r in data["results"]
        }
    return out


def versions() -> str:
    """Python, the numerical packages and the code version (for reproducibility)."""
    vs = []
    for p in ["numpy", "scipy", "scikit-fem", "gmsh", "meshio", "pyvista", "matplotlib"]:
        try:
            vs.append(f"{p} {metadata.version(p)}")
        except metadata.PackageNotFoundError:
            vs.append(f"{p} (not installed)")
    return (
        f"Python {platform.python_version()}; " + ", ".join(vs) + f"; flexval code {code_version()}"
    )


def _frame_variants(spec: ModelSpec) -> list[tuple[str, ModelSpec]]:
    """(frame, variant) of a model with a measuring-frame option at its default, else []."""
    opt = spec.model_family.option(FRAME_OPTION)
    if opt is None or FRAME_OPTION in dict(spec.options):
        return []
    return [(frame, spec.with_options(**{FRAME_OPTION: frame})) for frame in opt.allowed]


def _frame_rows(res: SceneResults, specs: list[ModelSpec], cache: RunMemo) -> list[FrameRow]:
    """Every model with a measuring-frame option (at its default) with each frame's value."""
    rows = []
    for spec in specs:
        for frame, variant in _frame_variants(spec):
            if variant.id == spec.id:
                paths, fails = res.paths, res.failures
            else:
                paths, fails = run_campaign(
                    res.scene, [variant], list(res.scene.load_cases), 1, cache
                )
            cells: dict = {}
            for c in res.cases:
                ref = res.converged(PAPER_REFERENCE, c)
                lp = paths.get((variant.id, c))
                fail = next((f for f in fails if f.model == variant.id and f.load_case == c), None)
                cells[c] = (
                    None
                    if ref is None
                    else fail
                    if fail is not None
                    else errors(lp, ref, res.scene.mechanism.size())
                    if lp is not None
                    else None
                )
            rows.append(FrameRow(spec.id, frame, cells))
    return rows


def _plane_variant(reference: ModelSpec) -> ModelSpec | None:
    """The reference with its other :data:`PLANE_OPTION` value, or None (no such option)."""
    opt = reference.model_family.option(PLANE_OPTION)
    if opt is None:
        return None
    own = dict(reference.options).get(PLANE_OPTION, opt.default)
    other = next(v for v in opt.allowed if v != own)
    return reference.with_options(**{PLANE_OPTION: other})


def _plane_bracket(res: SceneResults, reference: ModelSpec, cache: RunMemo) -> PlaneBracket | None:
    """The reference with its other :data:`PLANE_OPTION` value on every case, or None
    (a reference without that option)."""
    variant = _plane_variant(reference)
    if variant is None:
        return None
    paths, fails = run_campaign(res.scene, [variant], list(res.scene.load_cases), 1, cache)
    failed = {f.load_case for f in fails}
    return PlaneBracket(
        variant.id, {c: lp for (_, c), lp in paths.items() if c not in failed}, fails
    )


def convergence_specs(reference: ModelSpec) -> list[ModelSpec]:
    """The reference's resolutions of the convergence study: its lowest to one above its own."""
    low = reference.model_family.resolution.low
    return [reference.with_resolution(n) for n in range(low, reference.resolution + 2)]


@dataclass(frozen=True)
class _Plan:
    """What :func:`compute_report` runs on every scene, and how."""

    specs: list[ModelSpec]
    reference: ModelSpec | None
    bench_reference: ModelSpec | None
    converge: bool
    repeats: int

    @property
    def record(self) -> tuple[str, ...]:
        """Models run recording poses and shapes (for the figures), in every study."""
        return tuple(m for m in (PAPER_REFERENCE, self.reference and self.reference.id) if m)

    def repeats_for(self, spec: ModelSpec) -> int:
        """Timing repeats of ``spec``: one for a reference model (its runs are long)."""
        return 1 if spec.model_family.has(REFERENCE) else self.repeats

    def scene_specs(self, scene: Scene) -> list[ModelSpec]:
        """The models of ``scene``'s tables: the requested ones and, where the scene has notch
        hinges, the :data:`NOTCH_COMPARED` among them with plain Euler-Bernoulli hinges."""
        notched = any(
            f.section.profile is not None and f.section.profile.kind == "notch"
            for f in scene.mechanism.flexures
        )
        if not notched:
            return list(self.specs)
        have = {s.id for s in self.specs}
        plain = [parse_model(f"{s.id}[eb]") for s in self.specs if s.id in NOTCH_COMPARED]
        return [*self.specs, *(v for v in plain if v.id not in have)]

    def jobs(self, scene: Scene) -> list[Job]:
        """Every load path the report computes on ``scene`` (with repeats), some twice."""
        cases = list(scene.load_cases)
        per_case = self.scene_specs(scene)
        per_case += [v for s in self.specs for _, v in _frame_variants(s) if v.id != s.id]
        plane = _plane_variant(self.reference) if self.reference is not None else None
        per_case += [plane] if plane is not None else []
        if self.bench_reference is not None:
            per_case += [self.bench_reference] + sweep_specs(self.bench_reference)
        runs = [(s, c) for s in per_case for c in cases]
        if self.converge and self.reference is not None:
            runs += [(s, cases[0]) for s in convergence_specs(self.reference)]
        return [Job(scene, s, c, self.repeats_for(s), s.id in self.record) for s, c in runs]

    def batch_tasks(self, scene: Scene) -> list[tuple[Scene, ModelSpec, LoadCase]]:
        """Every (scene, model, case) whose batched cost per path the run times show: the
        models of the tables and of the runtime-versus-error study on every case."""
        specs = self.scene_specs(scene)
        if self.bench_reference is not None:
            specs += sweep_specs(self.bench_reference)
        return [(scene, s, c) for s in specs for c in scene.load_cases]


def _longest_first(jobs: list[Job]) -> list[Job]:
    """``jobs`` ordered for a process pool: the reference family's finest resolutions
    first (a continuum level costs several times the one below; reduced models take
    milliseconds), otherwise as listed."""

    def cost(job: Job) -> tuple[int, int]:
        fam = job.spec.model_family
        return (1, job.spec.resolution) if fam.has(REFERENCE) else (0, 0)

    return sorted(jobs, key=cost, reverse=True)


def compute_report(
    scene_names: list[str],
    models: list[str] | None = None,
    repeats: int = 3,
    use_cache: bool = True,
    progress: bool = True,
    bench: bool = True,
    converge: bool = True,
    workers: int = 1,
    peers: bool = False,
    batched: bool = True,
    load_cases: list[str] | None = None,
) -> ReportData:
    """Run and compare everything the report shows (see the module docstring).

    With ``batched``, every model but the reference is also timed as a batch of
    identical copies of each path (:mod:`flexval.validation.studies.batchtiming`, on ``workers``
    processes after the paths), for the run times: ``repeats`` batches (median) for
    the models of the tables, one per load case for the bench's other resolutions
    (the bench averages it over the load cases), which keeps the report's added time
    to about half.

    With ``peers``, :data:`PAPER_REFERENCE` is also timed against OpenSeesPy
    on every load case (:func:`flexval.validation.studies.peers.compare_with_opensees`, in
    this process once everything else is computed, ``repeats`` times each);
    where OpenSeesPy is missing the run times say so.

    With ``workers`` > 1 every load path of every study is first computed on
    that many processes (:func:`flexval.validation.studies.campaign.prefetch`); the studies
    then read them, so the results are those of a serial run.

    With ``load_cases``, only those load cases of each scene are studied
    (:meth:`flexval.geometry.Scene.with_load_cases`).

    Raises
    ------
    geometry.SceneError
        For a bad scene or model id, or a load case a scene has not (nothing is
        run). Solver failures are results, never raised.
    """
    t0 = time.perf_counter()
    specs = [parse_model(m, "<report>", "models") for m in (models or DEFAULT_MODELS)]
    scenes = [load_scene(n) for n in scene_names]
    if load_cases:  # only these cases of each scene (``--load-case``)
        scenes = [s.with_load_cases(load_cases) for s in scenes]
    memo = RunMemo(ResultCache(enabled=use_cache))
    reference = next((s for s in specs if s.model_family.has(REFERENCE)), None)
    ref_id = reference.id if reference else None
    plan = _Plan(
        specs,
        reference,
        (reference or parse_model(BENCH_REFERENCE)) if bench else None,
        converge,
        repeats,
    )
    prefetch(_longest_first([j for sc in scenes for j in plan.jobs(sc)]), memo, workers, progress)
    tables = {s.id for s in specs}  # the other resolutions of the bench: one batch per case
    batches = BatchMemo(repeats, memo.disk, batched, lambda s: repeats if s.id in tables else 1)
    batches.prefetch([t for sc in scenes for t in plan.batch_tasks(sc)], workers, progress)
    bar = Progress(
        sum(len(plan.scene_specs(s)) * len(s.load_cases) for s in scenes), enabled=progress
    )
    out: list[SceneResults] = []
    for sc in scenes:
        scene_specs = plan.scene_specs(sc)
        paths, failures = run_campaign(
            sc,
            scene_specs,
            list(sc.load_cases),
            repeats,
            memo,
            bar,
            record_models=plan.record,
            repeats_for=plan.repeats_for,
        )
        res = SceneResults(sc, paths, failures, [s.id for s in scene_specs], ref_id)
        res.batched = {
            (s.id, c.name): t
            for s in scene_specs
            for c in sc.load_cases
            if (t := batches.get(sc, s, c)) is not None
        }
        res.frames = _frame_rows(res, specs, memo)
        res.frequencies = frequency_data(sc, res.models, ref_id or PAPER_REFERENCE)
        res.stiffness = stiffness_data(sc, res.models, ref_id or PAPER_REFERENCE)
        res.measured = [
            compare_measurement(sc, m, specs, memo, unmodelled_is_failure=True)
            for m in sc.measurements
        ]
        if reference:
            res.bracket = _plane_bracket(res, reference, memo)
        if plan.bench_reference is not None:
            bref = plan.bench_reference
            res.bench_rows, res.bench_failures = runtime_vs_error(
                sc, bref, sweep_specs(bref), repeats, memo, progress, plan.record, batches
            )
            res.bench_reference = bref.id
        if converge and reference:
            case = sc.load_cases[0]
            res.convergence.append(
                study(
                    sc,
                    reference,
                    [s.resolution for s in convergence_specs(reference)],
                    case,
                    run=lambda spec, sc=sc, case=case: timed_run(
                        sc, spec, case, 1, memo, record=spec.id in plan.record
                    ),
                )
            )
        out.append(res)
    wall = {"models": time.perf_counter() - t0}
    if batched:
        wall["batched"] = batches.wall  # part of "models"
    if peers:
        t1 = time.perf_counter()
        n = parse_model(PAPER_REFERENCE).resolution
        for res in out:
            try:
                res.peers = compare_with_opensees(res.scene, n, repeats)
            except PeerUnavailable as exc:
                res.peers = str(exc)
        wall["peers"] = time.perf_counter() - t1
    return ReportData(
        out, [s.id for s in specs], ref_id, repeats, versions(), code_version(), workers, wall
    )
