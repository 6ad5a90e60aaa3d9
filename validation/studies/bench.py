"""Runtime versus error: every model at several resolutions against one reference.

For each model the error is the largest, over the scene's load cases, of the
path displacement error (``path_disp`` of :mod:`flexval.validation.studies.compare`: largest
vector error along the path / largest reference displacement, percent), and
the time is the mean over load cases of the median wall time per load path,
alone and batched (:mod:`flexval.validation.studies.batchtiming`: the same path run as
a batch of identical copies, its cost per path), each also as a speed-up
against :data:`SPEED_REFERENCE`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from flexval.geometry import Scene
from flexval.reducedmodels.catalogue import REFERENCE, ModelSpec, parse_model

from ..cache import ResultCache
from ..failures import Failure
from ..outputs import output_path, write_json, write_text
from ..report.figurejobs import draw_now
from ..report.tables import Column, markdown_table, sig
from .batchtiming import SPEED_REFERENCE, BatchMemo
from .campaign import Progress, RunMemo, run_campaign
from .compare import errors

#: the keys of a row that are run times or depend on them (kept out of a report's results)
TIMING_KEYS = ("seconds", "batched_seconds", "copies", "batches")
#: the reduced models of the study, every resolution of the paper's range and beyond
SWEEP_MODELS = (
    *(f"beam:{n}" for n in (5, 10, 20, 40, 100, 200, 400)),
    *(f"dcmm:{n}" for n in range(1, 9)),
    "prbm",
    "ee",
)


def sweep_specs(reference: ModelSpec | None = None) -> list[ModelSpec]:
    """The models of the runtime-versus-error study.

    :data:`SWEEP_MODELS`, and when ``reference`` is a reference model
    (capability ``reference``, e.g. the continuum) its resolutions below the
    reference's own (e.g. coarser meshes).
    """
    specs = [parse_model(m, "<bench>", "models") for m in SWEEP_MODELS]
    fam = reference.model_family if reference is not None else None
    if fam is not None and fam.has(REFERENCE) and fam.resolution is not None:
        specs += [
            reference.with_resolution(n) for n in range(fam.resolution.low, reference.resolution)
        ]
    return specs


def runtime_vs_error(
    scene: Scene,
    reference: ModelSpec,
    specs: list[ModelSpec],
    repeats: int = 3,
    cache: ResultCache | None = None,
    progress: bool = True,
    record_models: tuple[str, ...] = (),
    batches: BatchMemo | None = None,
) -> tuple[list[dict], list[Failure]]:
    """Rows {model, seconds, batched_seconds, copies, batches, error, per_case} of the
    study, and the failures.

    A model that fails on some load case has no row (its error is not
    defined); its failures are returned. ``record_models`` are run recording
    poses and shapes (as the report runs them, so that their cached paths serve
    both). ``batched_seconds`` is the mean over load cases of the batched cost per
    path, ``copies`` the copies of its batches and ``batches`` how many were timed, on
    each load case (None for a model not batched), read from ``batches`` (default: a
    memo of ``repeats`` batches through ``cache``, timed here).
    """
    if batches is None:
        batches = BatchMemo(repeats, cache.disk if isinstance(cache, RunMemo) else cache)
    cases = list(scene.load_cases)
    all_specs = [reference] + [s for s in specs if s.id != reference.id]
    bar = Progress(len(all_specs) * len(cases), enabled=progress)
    res, failures = run_campaign(
        scene,
        all_specs,
        cases,
        repeats,
        cache,
        bar,
        record_models=record_models,
        repeats_for=lambda s: 1 if s.model_family.has(REFERENCE) else repeats,
    )
    rows = []
    for spec in all_specs:
        if spec.id == reference.id:
            continue
        per_case, secs, ok = {}, [], True
        for case in cases:
            lp, ref = res.get((spec.id, case.name)), res.get((reference.id, case.name))
            if lp is None or ref is None or not lp.converged or not ref.converged:
                ok = False
                break
            per_case[case.name] = errors(lp, ref, scene.mechanism.size())
            secs.append(lp.seconds)
        if ok:
            timed = [batches.get(scene, spec, case) for case in cases]
            whole = all(t is not None for t in timed)
            rows.append(
                {
                    "model": spec.id,
                    "seconds": sum(secs) / len(secs),
                    "batched_seconds": (
                        sum(t.seconds for t in timed) / len(timed) if whole else None
                    ),
                    "copies": [t.copies for t in timed] if whole else None,
                    "batches": [len(t.samples) for t in timed] if whole else None,
                    "error": max(e["path_disp"] for e in per_case.values()),
                    "per_case": per_case,
                }
            )
    return rows, failures


def speed_ups(rows: list[dict], key: str, reference: str = SPEED_REFERENCE) -> list[float | None]:
    """Each row's ``reference`` row's ``key`` (seconds) over its own: how many times
    faster than ``reference`` (None where either has no time)."""
    ref = next((r.get(key) for r in rows if r["model"] == reference), None)
    return [ref / r[key] if ref and r.get(key) else None for r in rows]


def _times(ratio: float) -> str:
    return f"{ratio:.3g}x"


def _copies(per_case: list[int]) -> str:
    """The batch sizes of a row's load cases, each once (``10/100``)."""
    return "/".join(str(n) for n in sorted(set(per_case)))


def _batches(row: dict) -> str:
    """``copies × batches`` of a row (``100 × 3``), or – for a model not batched."""
    if row.get("copies") is None:
        return "–"
    return f"{_copies(row['copies'])} × {_copies(row['batches'])}"


def _cell(value, fmt: Callable) -> str:
    """``fmt(value)``, or – for None (not timed)."""
    return "–" if value is None else fmt(value)


def write_bench(
    scene: Scene,
    rows: list[dict],
    reference: str,
    out: Path,
    failures: list[Failure] = (),
    draw: Callable = draw_now,
) -> Path:
    """Table (Markdown), plot (PNG) and JSON of a runtime-versus-error study in ``out``.

    The files are ``bench_<scene>.md/.png/.json`` with the scene name made
    safe (:func:`flexval.validation.outputs.safe_name`); returns the Markdown path.
    ``failures`` are listed below the table (a model that fails has no row).
    The plot is drawn with ``draw(fn, *args)`` (see :mod:`flexval.validation.report.figurejobs`).
    """
    from ..report.figures import pareto_front
    from ..report.figures import runtime_vs_error as plot

    out.mkdir(parents=True, exist_ok=True)
    stem = f"bench_{scene.name}"
    front = set(pareto_front([(r["seconds"], r["error"]) for r in rows]))
    timed = [k for k, r in enumerate(rows) if r.get("batched_seconds") is not None]
    batched_front = {
        timed[j]
        for j in pareto_front([(rows[k]["batched_seconds"], rows[k]["error"]) for k in timed])
    }
    single_up, batched_up = speed_ups(rows, "seconds"), speed_ups(rows, "batched_seconds")
    lines = [
        f"# Runtime versus error: {scene.name}",
        "",
        f"Reference: `{reference}`. Error: largest over load cases of the path "
        "displacement error (percent); time: mean over load cases of the median wall "
        "time per load path (s), alone and batched: one batch of identical copies of the "
        "path (`copies`) run together, its wall time per path, median of the `batches` "
        "timed on each load case (`flexval.validation.studies.batchtiming`; – for a model not "
        "batched). Speed-ups: "
        f"`{SPEED_REFERENCE}`'s time over the model's. Pareto: not both slower and less "
        "accurate than another model, alone and batched.",
        "",
    ]
    lines += markdown_table(
        [
            Column("model", "<"),
            Column("seconds"),
            Column("batched (s/path)"),
            Column("copies × batches"),
            Column(f"speed-up vs {SPEED_REFERENCE}"),
            Column("batched speed-up"),
            Column("error (%)"),
            Column("Pareto", "<"),
            Column("Pareto, batched", "<"),
        ],
        [
            [
                r["model"],
                sig(r["seconds"], 3),
                _cell(r.get("batched_seconds"), lambda v: sig(v, 3)),
                _batches(r),
                _cell(up, _times),
                _cell(bup, _times),
                sig(r["error"], 3),
                "yes" if k in front else "",
                "yes" if k in batched_front else "",
            ]
            for k, (r, up, bup) in enumerate(zip(rows, single_up, batched_up))
        ],
    )
    png = output_path(out, stem, ".png")
    draw(plot, rows, f"{scene.name}: runtime vs error (reference {reference})", png)
    if failures:
        lines += ["", "Failures (no row above):", ""]
        lines += [f"- `{f.model}` on `{f.load_case}`: {f.summary()}" for f in failures]
    lines += ["", f"![runtime vs error]({png.name})", ""]
    write_json(
        output_path(out, stem, ".json"),
        {
            "scene": scene.name,
            "reference": reference,
            "rows": rows,
            "failures": [f.to_dict() for f in failures],
        },
    )
    return write_text(output_path(out, stem, ".md"), "\n".join(lines))
