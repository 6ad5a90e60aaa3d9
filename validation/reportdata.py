"""The validation report's data: every model run and every figure, computed once.

:func:`compute_report` runs every requested model on every load case of each
scene (cached), the measuring-frame variants, the runtime-versus-error and
convergence studies, and returns a :class:`ReportData`; the renderers of
:mod:`validation.report` only format it. A model that fails on a load case
is a result (:class:`validation.failures.Failure`), kept beside the paths.
Everything the report says about a scene comes from its data: the paper's
figures attach to a scene by its name in ``validation/data/paper_results.toml``,
and the chain's topology is the cycle rank of its body graph.

Units: mm, N, N mm, rad; errors in percent; times in s.
"""

from __future__ import annotations

import platform
from dataclasses import dataclass, field
from functools import cached_property
from importlib import metadata

from geometry import Scene, load_scene
from geometry.graph import independent_loops
from reducedmodels import LoadPath
from reducedmodels.catalogue import REFERENCE, ModelSpec, parse_model

from .bench import runtime_vs_error, sweep_specs
from .cache import ResultCache, code_version
from .campaign import Progress, run_campaign
from .compare import errors, paper_percent, paper_scene, paper_seconds
from .convergence import ConvergenceStudy, study
from .failures import Failure
from .frequencies import FrequencyTable, frequency_data

DEFAULT_MODELS = ("continuum", "beam:100", "beam:20", "prbm", "dcmm:1", "dcmm:2", "dcmm:3", "ee")
#: the paper's reference (its FEM100): every scene is compared against it
PAPER_REFERENCE = "beam:100"
#: reference of the runtime-versus-error study when no reference model is requested
BENCH_REFERENCE = "beam:400"
#: option whose values the frame-sensitivity table compares (DCMM's measuring frame)
FRAME_OPTION = "frame"
#: option of the reference whose other value brackets it (a wide flexure, b >> h, lies
#: between plane stress and plane strain)
PLANE_OPTION = "plane"


@dataclass
class PaperData:
    """The paper's figures for one scene (see :func:`validation.compare.paper_scene`)."""

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
            return None                 # a scene of the same name but other load cases
        return cls(paper_percent(scene.name, cases), paper_seconds(scene.name, cases),
                   data["percent_table"], data["seconds_table"],
                   data.get("relative_rotations_figure"))


@dataclass
class FrameRow:
    """One model with one value of its measuring-frame option, on every load case.

    ``cells`` maps each load case to its errors against :data:`PAPER_REFERENCE`
    (:func:`validation.compare.errors`), a :class:`Failure`, or None (no
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
    bracket: PlaneBracket | None = None

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
        return next((f for f in self.failures if f.model == model and f.load_case == case),
                    None)

    def traces(self, case: str) -> dict[str, LoadPath]:
        """{model: arc-length path through its limit point} of the models failing on ``case``."""
        return {f.model: f.trace for f in self.failures
                if f.load_case == case and f.trace is not None}

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
                    out.setdefault(m, {})[c] = errors(lp, ref)
        return out

    def bracket_rows(self) -> dict[str, dict[str, float]]:
        """{case: end |d| (mm) and rotation (rad) in both planes, and their spreads (%)}.

        Keys ``disp``/``disp_other``/``rot``/``rot_other`` (reference, then the
        bracket's other plane) and ``disp_spread``/``rot_spread``: the relative
        difference |other - reference| / |reference| in percent, comparable with
        the ``end_disp`` and ``end_rot`` errors. Cases where either path did not
        reach full load are left out.
        """
        out: dict[str, dict[str, float]] = {}
        if self.bracket is None or self.reference is None:
            return out
        for c in self.cases:
            ref, other = self.converged(self.reference, c), self.bracket.paths.get(c)
            if ref is None or other is None or not other.converged:
                continue
            d, d2 = float(ref.displacement[-1]), float(other.displacement[-1])
            r, r2 = float(ref.rotation[-1]), float(other.rotation[-1])
            out[c] = {"disp": d, "disp_other": d2, "rot": r, "rot_other": r2,
                      "disp_spread": 100 * abs(d2 - d) / abs(d),
                      "rot_spread": 100 * abs(r2 - r) / abs(r)}
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

    @property
    def references(self) -> list[str]:
        """The references every error table is computed against."""
        return [PAPER_REFERENCE] + ([self.reference] if self.reference else [])

    def gates(self) -> dict:
        """{scene: {reference: error table}}: the baseline of the CI accuracy gates."""
        return {r.scene.name: {ref: r.error_table(ref) for ref in self.references}
                for r in self.scenes}

    def results(self) -> dict:
        """Every LoadPath, failure and bench row, JSON-ready."""
        return {"code_version": self.code, "scenes": {
            r.scene.name: {"results": [lp.to_dict() for lp in r.paths.values()],
                           "failures": [f.to_dict() for f in r.failures],
                           "bench": r.bench_rows}
            for r in self.scenes}}


def versions() -> str:
    """Python, the numerical packages and the code version (for reproducibility)."""
    vs = []
    for p in ["numpy", "scipy", "scikit-fem", "gmsh", "meshio", "pyvista", "matplotlib"]:
        try:
            vs.append(f"{p} {metadata.version(p)}")
        except metadata.PackageNotFoundError:
            vs.append(f"{p} (not installed)")
    return f"Python {platform.python_version()}; " + ", ".join(vs) + f"; flexval code {code_version()}"


def _frame_rows(res: SceneResults, specs: list[ModelSpec], cache: ResultCache | None
                ) -> list[FrameRow]:
    """Every model with a measuring-frame option (at its default) with each frame's value."""
    rows = []
    for spec in specs:
        opt = spec.model_family.option(FRAME_OPTION)
        if opt is None or FRAME_OPTION in dict(spec.options):
            continue
        for frame in opt.allowed:
            variant = spec.with_options(**{FRAME_OPTION: frame})
            if variant.id == spec.id:
                paths, fails = res.paths, res.failures
            else:
                paths, fails = run_campaign(res.scene, [variant], list(res.scene.load_cases), 1,
                                            cache)
            cells: dict = {}
            for c in res.cases:
                ref = res.converged(PAPER_REFERENCE, c)
                lp = paths.get((variant.id, c))
                fail = next((f for f in fails if f.model == variant.id and f.load_case == c),
                            None)
                cells[c] = (None if ref is None else fail if fail is not None
                            else errors(lp, ref) if lp is not None else None)
            rows.append(FrameRow(spec.id, frame, cells))
    return rows


def _plane_bracket(res: SceneResults, reference: ModelSpec, cache: ResultCache | None
                   ) -> PlaneBracket | None:
    """The reference with its other :data:`PLANE_OPTION` value on every case, or None
    (a reference without that option)."""
    opt = reference.model_family.option(PLANE_OPTION)
    if opt is None:
        return None
    own = dict(reference.options).get(PLANE_OPTION, opt.default)
    other = next(v for v in opt.allowed if v != own)
    variant = reference.with_options(**{PLANE_OPTION: other})
    paths, fails = run_campaign(res.scene, [variant], list(res.scene.load_cases), 1, cache)
    failed = {f.load_case for f in fails}
    return PlaneBracket(variant.id, {c: lp for (_, c), lp in paths.items() if c not in failed},
                        fails)


def compute_report(scene_names: list[str], models: list[str] | None = None, repeats: int = 3,
                   use_cache: bool = True, progress: bool = True, bench: bool = True,
                   converge: bool = True) -> ReportData:
    """Run and compare everything the report shows (see the module docstring).

    Raises
    ------
    geometry.SceneError
        For a bad scene or model id (nothing is run). Solver failures are
        results, never raised.
    """
    specs = [parse_model(m, "<report>", "models") for m in (models or DEFAULT_MODELS)]
    scenes = [load_scene(n) for n in scene_names]
    cache = ResultCache(enabled=use_cache)
    reference = next((s for s in specs if s.model_family.has(REFERENCE)), None)
    ref_id = reference.id if reference else None
    bar = Progress(sum(len(specs) * len(s.load_cases) for s in scenes), enabled=progress)
    out: list[SceneResults] = []
    for sc in scenes:
        record = tuple(m for m in (PAPER_REFERENCE, ref_id) if m)
        paths, failures = run_campaign(
            sc, specs, list(sc.load_cases), repeats, cache, bar, record_models=record,
            repeats_for=lambda s: 1 if s.model_family.has(REFERENCE) else repeats)
        res = SceneResults(sc, paths, failures, [s.id for s in specs], ref_id)
        res.frames = _frame_rows(res, specs, cache)
        res.frequencies = frequency_data(sc, res.models, ref_id or PAPER_REFERENCE)
        if reference:
            res.bracket = _plane_bracket(res, reference, cache)
        if bench:
            bref = reference or parse_model(BENCH_REFERENCE)
            res.bench_rows, res.bench_failures = runtime_vs_error(
                sc, bref, sweep_specs(bref), repeats, cache, progress)
            res.bench_reference = bref.id
        if converge and reference:
            low = reference.model_family.resolution.low
            res.convergence.append(study(sc, reference, list(range(low, reference.resolution + 2)),
                                         sc.load_cases[0]))
        out.append(res)
    return ReportData(out, [s.id for s in specs], ref_id, repeats, versions(), code_version())
