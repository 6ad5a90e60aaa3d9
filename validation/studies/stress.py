"""Numerical stress tests of the models on one scene (``flexval stress``).

Three studies per model and load case:

(a) load amplification: the load case scaled by 1, 2, 5, 10, 20, ... until
    the solver fails or the cap (1000, 100 in quick mode) is reached. For
    each multiple reached: the solver's effort, and the error against the
    reference model (``beam:100``; ``beam:40`` in quick mode) at the same
    multiple, as long as the reference reaches it too. A failure records the
    SolverError message (the mode and the last converged load) and, for the
    nonlinear reduced models, whether arc-length continuation finds a limit
    point (the largest load of the equilibrium path: load control cannot go
    further, whatever the solver) and its load.
(b) step count: the case traced with 2, 11, 101 (and 1001 in full mode)
    load levels; path independence asks for the same end state.
(c) invariance: the scene rotated by 2.1 rad about the origin and shifted by
    (-40, 17) mm, and the scene written in metres (lengths x 1e-3, E x 1e6
    so that N/mm^2 becomes N/m^2, forces unchanged, moments x 1e-3); the
    target displacements, transformed back, and the rotations must not change.

Displacements are compared as vectors: relative differences are the
largest over the path of |d - d_base| / max |d_base| (rotations alike), a
maximum near zero measured against its scale instead (the rule of
:func:`flexval.validation.studies.compare.errors`:
:func:`~flexval.validation.studies.compare.scale_of` of
the base path on the mechanism's size, :func:`~flexval.validation.studies.compare.denominator`),
so a rotation that vanishes by symmetry does not turn round-off into a
failed invariance. Errors against the reference are the percentages of
:func:`flexval.validation.studies.compare.errors`.

Units: mm, N, N mm, rad (the metre variant is internal to (c)).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from flexval.geometry import Force, LoadCase, Material, Mechanism, Scene, rotation
from flexval.reducedmodels import LoadPath, SolverError
from flexval.reducedmodels.catalogue import ModelSpec, parse_model

from ..failures import first_limit
from ..outputs import output_path, write_json, write_text
from ..report.tables import Column, markdown_table, sig
from ..run import run_model
from .compare import denominator, errors, scale_of

AMPLIFICATIONS = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)
"""Load multiples of study (a); quick mode stops at :data:`QUICK_CAP`."""
QUICK_CAP = 100
STEP_COUNTS = (2, 11, 101, 1001)
"""Level counts of study (b); quick mode omits 1001."""
RIGID_ANGLE = 2.1  # rad
RIGID_SHIFT = (-40.0, 17.0)  # mm
METRE = 1e-3  # length of 1 mm in the rescaled scene (m)
REFERENCE, QUICK_REFERENCE = "beam:100", "beam:40"


def scale_case(case: LoadCase, factor: float) -> LoadCase:
    """``case`` with every component's value multiplied by ``factor`` (same name and levels)."""
    return dataclasses.replace(
        case,
        components=tuple(dataclasses.replace(c, value=c.value * factor) for c in case.components),
    )


def rescale_lengths(
    mechanism: Mechanism, case: LoadCase, length: float
) -> tuple[Mechanism, LoadCase]:
    """The same problem with the unit of length changed so that 1 mm becomes ``length``.

    Every length (shapes, sections, points) is multiplied by ``length``,
    Young's modulus divided by ``length**2`` (force per area), forces are
    unchanged and moments multiplied by ``length``. The answer is the same
    problem: displacements scale by ``length``, rotations are unchanged.
    """

    def pt(p) -> np.ndarray:
        return np.asarray(p, float) * length

    flexures = tuple(
        dataclasses.replace(
            f,
            shape=f.shape.scaled(length),
            section=f.section.scaled(length),
        )
        for f in mechanism.flexures
    )
    mech = dataclasses.replace(
        mechanism,
        flexures=flexures,
        bodies={
            n: dataclasses.replace(b, points=pt(b.points)) for n, b in mechanism.bodies.items()
        },
        material=Material(
            mechanism.material.youngs_modulus / length**2, mechanism.material.poisson_ratio
        ),
        target_point=pt(mechanism.target_point),
        pins=tuple(dataclasses.replace(p, point=pt(p.point)) for p in mechanism.pins),
    )
    comps = tuple(
        dataclasses.replace(c, point=pt(c.point))
        if isinstance(c, Force)
        else dataclasses.replace(c, value=c.value * length)
        for c in case.components
    )
    return mech, dataclasses.replace(case, components=comps)


def _finite(lp: LoadPath) -> bool:
    """True if every load and target value of the path is finite."""
    return bool(np.all(np.isfinite(np.concatenate([lp.load, lp.dx, lp.dy, lp.rotation]))))


def _attempt(run: Callable[[], LoadPath]) -> tuple[LoadPath | None, dict | None]:
    """Run a model; (path, None) on success, (partial path or None, failure record) otherwise.

    A SolverError is the honest failure the core promises; any other
    exception, or a non-finite result, is a defect and is recorded as such.
    """
    try:
        lp = run()
    except SolverError as exc:
        return exc.path, {"kind": "solver", "message": str(exc), "load_factor": exc.load_factor}
    except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        return None, {
            "kind": "error",
            "message": f"{type(exc).__name__}: {exc}",
            "load_factor": None,
        }
    if not _finite(lp):
        return None, {
            "kind": "non-finite",
            "message": "non-finite values in a converged path",
            "load_factor": None,
        }
    return lp, None


def _path_difference(
    a: LoadPath, b: LoadPath, size: float, turn: float = 0.0, length: float = 1.0
) -> dict[str, float]:
    """Largest relative differences of path ``b`` from ``a`` (same levels).

    ``b``'s displacements are turned back by ``-turn`` (rad) and divided by
    ``length`` first, so a rigidly moved or rescaled copy compares equal.
    ``size`` (mm) is the mechanism's: a maximum of ``a`` near zero is replaced
    by its scale (:func:`flexval.validation.studies.compare.denominator`).
    """
    back = rotation(-turn) @ np.array([b.dx, b.dy]) / length
    da = np.array([a.dx, a.dy])
    ra, rb = np.asarray(a.rotation), np.asarray(b.rotation)
    scale = scale_of(a, size)
    return {
        "disp_rel": float(
            np.hypot(*(back - da)).max() / denominator(np.hypot(*da).max(), scale["disp"])
        ),
        "rot_rel": float(np.abs(rb - ra).max() / denominator(np.abs(ra).max(), scale["rot"])),
    }


class _Reference:
    """The reference model's paths at each load multiple, computed once per scene.

    After the reference fails at a multiple it is not run at larger ones.
    """

    def __init__(self, scene: Scene, spec: ModelSpec):
        self.scene, self.spec = scene, spec
        self.paths: dict[tuple[str, float], LoadPath] = {}
        self.failed: dict[str, dict] = {}

    def get(self, case: LoadCase, factor: float) -> tuple[LoadPath | None, dict | None]:
        """(path, None) or (None, failure record) of the reference at ``factor`` x ``case``."""
        failure = self.failed.get(case.name)
        if failure is not None and failure["factor"] <= factor:
            return None, failure
        key = (case.name, factor)
        if key not in self.paths:
            lp, failure = _attempt(
                lambda: run_model(self.scene, self.spec, scale_case(case, factor))
            )
            if failure is not None:
                self.failed[case.name] = {**failure, "factor": factor}
                return None, self.failed[case.name]
            self.paths[key] = lp
        return self.paths[key], None


def _amplification(
    scene: Scene,
    spec: ModelSpec,
    case: LoadCase,
    factors: Sequence[float],
    reference: _Reference,
    progress: Callable[[str], None] | None,
) -> tuple[dict, LoadPath | None]:
    """Study (a) of one model and case; also returns the path at multiple 1 (or None)."""
    rows, failure, first = [], None, None
    reached = 0.0
    for k in factors:
        if progress:
            progress(f"stress {scene.name}: {spec.id} on {case.name} x{k:g}")
        lp, failure = _attempt(lambda k=k: run_model(scene, spec, scale_case(case, k)))
        if failure is not None:
            failure["factor"] = k
            if failure["kind"] == "solver":
                limit = first_limit(scene, spec, scale_case(case, k))
                failure["limit_load"] = limit[0] if limit else None
            break
        first = lp if first is None else first
        reached = k
        ref, ref_failure = reference.get(case, k)
        row = {
            "factor": k,
            "load": k * case.magnitude,
            "seconds": lp.seconds,
            "newton_iterations": lp.stats.get("newton_iterations", 0),
            "step_cuts": lp.stats.get("step_cuts", 0),
            "errors": (errors(lp, ref, scene.mechanism.size()) if ref is not None else None),
            "reference_failure": ref_failure["message"] if ref_failure else None,
        }
        rows.append(row)
    return {
        "largest_factor": reached,
        "largest_load": reached * case.magnitude,
        "unit": case.unit,
        "failure": failure,
        "rows": rows,
    }, first


def _step_count(scene: Scene, spec: ModelSpec, case: LoadCase, counts: Sequence[int]) -> dict:
    """Study (b): end states with each number of levels and their largest relative spread
    (against the scales of the first path that converged where an end value is near zero)."""
    ends, failures, scale = [], [], None
    for n in counts:
        lp, failure = _attempt(lambda n=n: run_model(scene, spec, case, levels=n))
        if failure is not None:
            failures.append({"levels": n, **failure})
            continue
        scale = scale or scale_of(lp, scene.mechanism.size())
        ends.append(
            {
                "levels": n,
                "dx": lp.dx[-1],
                "dy": lp.dy[-1],
                "rotation": lp.rotation[-1],
                "newton_iterations": lp.stats.get("newton_iterations", 0),
                "seconds": lp.seconds,
            }
        )
    out: dict = {"ends": ends, "failures": failures, "disp_rel": None, "rot_rel": None}
    if len(ends) >= 2:
        d = np.array([[e["dx"], e["dy"]] for e in ends])
        r = np.array([e["rotation"] for e in ends])
        spread = np.hypot(*(d[:, None, :] - d[None, :, :]).transpose(2, 0, 1)).max()
        out["disp_rel"] = float(spread / denominator(np.hypot(*d.T).max(), scale["disp"]))
        out["rot_rel"] = float(np.ptp(r) / denominator(np.abs(r).max(), scale["rot"]))
    return out


def _invariance(scene: Scene, spec: ModelSpec, case: LoadCase, base: LoadPath | None) -> dict:
    """Study (c): path differences of the rigidly moved and of the metre copy from ``base``."""
    if base is None:
        return {"rigid_motion": None, "metres": None, "failure": "base case failed"}
    shift = np.array(RIGID_SHIFT)
    moved_scene = dataclasses.replace(
        scene, mechanism=scene.mechanism.transformed(RIGID_ANGLE, shift)
    )
    moved, f1 = _attempt(lambda: run_model(moved_scene, spec, case.transformed(RIGID_ANGLE, shift)))
    mech_m, case_m = rescale_lengths(scene.mechanism, case, METRE)
    metres, f2 = _attempt(
        lambda: run_model(dataclasses.replace(scene, mechanism=mech_m, data=None), spec, case_m)
    )
    fails = [f["message"] for f in (f1, f2) if f is not None]
    size = scene.mechanism.size()
    return {
        "rigid_motion": (_path_difference(base, moved, size, turn=RIGID_ANGLE) if moved else None),
        "metres": _path_difference(base, metres, size, length=METRE) if metres else None,
        "failure": "; ".join(fails) or None,
    }


def stress_report(
    scene: Scene,
    models: Sequence[ModelSpec | str],
    quick: bool = False,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Run the three stress studies of every model on every load case of ``scene``.

    Parameters
    ----------
    scene : Scene
    models : sequence of ModelSpec or str
        Models to stress (``"dcmm:2"``, ``parse_model("prbm")``, ...).
    quick : bool
        Cap the amplification at 100, use ``beam:40`` as the reference and
        skip the 1001-level run.
    progress : callable, optional
        Called with a short line before each run of a model on a load case.

    Returns
    -------
    dict
        JSON-ready: ``scene``, ``quick``, ``reference``, ``amplifications``,
        ``step_counts``, ``seconds`` and ``models``: {model id: {load case:
        {"amplification": {largest_factor, largest_load, unit, failure,
        rows: [{factor, load, seconds, newton_iterations, step_cuts, errors,
        reference_failure}]}, "step_count": {ends, failures, disp_rel,
        rot_rel}, "invariance": {rigid_motion: {disp_rel, rot_rel}, metres:
        {...}, failure}}}}. A failure is {kind: "solver" | "error" |
        "non-finite", message, load_factor, factor} plus, for a solver failure,
        ``limit_load``: the load at the path's first limit point or None.
    """
    t0 = time.perf_counter()
    specs = [
        m if isinstance(m, ModelSpec) else parse_model(m, "<stress>", "models") for m in models
    ]
    ref_spec = parse_model(QUICK_REFERENCE if quick else REFERENCE)
    factors = [k for k in AMPLIFICATIONS if not quick or k <= QUICK_CAP]
    counts = [n for n in STEP_COUNTS if not quick or n < 1001]
    reference = _Reference(scene, ref_spec)

    out_models: dict[str, dict] = {}
    for spec in specs:
        per_case = {}
        for case in scene.load_cases:
            amp, base = _amplification(scene, spec, case, factors, reference, progress)
            if progress:
                progress(f"stress {scene.name}: {spec.id} on {case.name}: step count, invariance")
            per_case[case.name] = {
                "amplification": amp,
                "step_count": _step_count(scene, spec, case, counts),
                "invariance": _invariance(scene, spec, case, base),
            }
        out_models[spec.id] = per_case
    return {
        "scene": scene.name,
        "quick": quick,
        "reference": ref_spec.id,
        "amplifications": factors,
        "step_counts": counts,
        "models": out_models,
        "seconds": time.perf_counter() - t0,
    }


def format_markdown(report: dict) -> str:
    """The stress report as Markdown: one table per study."""
    models = report["models"]
    lines = [
        f"# Stress tests: {report['scene']}",
        "",
        f"Reference: `{report['reference']}`; load multiples "
        f"{', '.join(str(k) for k in report['amplifications'])}; "
        f"{'quick' if report['quick'] else 'full'} mode; "
        f"{report['seconds']:.1f} s.",
        "",
        "## (a) Load amplification",
        "",
        "Largest multiple of each load case reached, the failure that stopped the "
        "next one, and the error against the reference at the largest multiple both "
        "reached (`path_disp`, `path_rot`, percent).",
        "",
    ]
    rows = []
    for model, cases in models.items():
        for case, r in cases.items():
            amp = r["amplification"]
            last = next((row for row in reversed(amp["rows"]) if row["errors"]), None)
            fail = amp["failure"]
            fail_text = f"×{fail['factor']:g}: {fail['message']}" if fail else "none up to the cap"
            if fail and fail.get("limit_load") is not None:
                fail_text = (
                    f"limit point at {sig(fail['limit_load'])} {amp['unit']} "
                    f"(arc-length); {fail_text}"
                )
            at = f" (×{last['factor']:g})" if last else ""
            rows.append(
                [
                    model,
                    case,
                    f"{amp['largest_factor']:g}",
                    f"{sig(amp['largest_load'])} {amp['unit']}",
                    sig(last["errors"]["path_disp"] if last else None, 3) + at,
                    sig(last["errors"]["path_rot"] if last else None, 3),
                    fail_text,
                ]
            )
    lines += markdown_table(
        [
            Column("model", "<"),
            Column("case", "<"),
            Column("largest ×"),
            Column("load"),
            Column("path_disp %"),
            Column("path_rot %"),
            Column("failure", "<"),
        ],
        rows,
    )
    lines += [
        "",
        "## (b) Step count",
        "",
        "End state with "
        + ", ".join(str(n) for n in report["step_counts"])
        + " load levels: largest relative spread of the end displacement vector and "
        "rotation (path independence asks for round-off).",
        "",
    ]
    rows = []
    for model, cases in models.items():
        for case, r in cases.items():
            sc = r["step_count"]
            its = ", ".join(f"{e['levels']}: {e['newton_iterations']}" for e in sc["ends"])
            fails = "; ".join(f"{f['levels']} levels: {f['message']}" for f in sc["failures"])
            rows.append(
                [model, case, sig(sc["disp_rel"], 3), sig(sc["rot_rel"], 3), its, fails or "none"]
            )
    lines += markdown_table(
        [
            Column("model", "<"),
            Column("case", "<"),
            Column("disp spread"),
            Column("rot spread"),
            Column("iterations per run", "<"),
            Column("failures", "<"),
        ],
        rows,
    )
    lines += [
        "",
        "## (c) Invariance",
        "",
        f"Largest relative path difference after a rigid motion ({RIGID_ANGLE} rad, "
        f"{RIGID_SHIFT} mm) and after rewriting the scene in metres.",
        "",
    ]
    rows = []
    for model, cases in models.items():
        for case, r in cases.items():
            inv = r["invariance"]
            rm, me = inv["rigid_motion"] or {}, inv["metres"] or {}
            rows.append(
                [
                    model,
                    case,
                    sig(rm.get("disp_rel"), 3),
                    sig(rm.get("rot_rel"), 3),
                    sig(me.get("disp_rel"), 3),
                    sig(me.get("rot_rel"), 3),
                    inv["failure"] or "none",
                ]
            )
    lines += markdown_table(
        [
            Column("model", "<"),
            Column("case", "<"),
            Column("rigid disp"),
            Column("rigid rot"),
            Column("metres disp"),
            Column("metres rot"),
            Column("failures", "<"),
        ],
        rows,
    )
    return "\n".join(lines) + "\n"


def write_stress(report: dict, out_dir: str | Path) -> tuple[Path, Path]:
    """Write ``stress_<scene>.md`` and ``stress_<scene>.json`` into ``out_dir`` (created)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"stress_{report['scene']}"
    md = write_text(output_path(out, stem, ".md"), format_markdown(report))
    return md, write_json(output_path(out, stem, ".json"), report)
