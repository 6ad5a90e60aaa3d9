"""The validation report's run times, in their own files: ``timings.md`` and ``timings.json``.

Everything of the report that depends on the machine, its load and the cache
is written here, so that ``report.md``, ``results.json`` and ``gates.json``
change only when a result does (two runs of the same code write them byte for
byte the same). Here: the median wall time of every load path beside the
paper's and the speed-ups against :data:`~flexval.validation.report.data.PAPER_REFERENCE`,
the cheapest model within each error budget of the findings, the cost of the
plane-strain bracket and of each convergence run, the comparison with
OpenSeesPy (:mod:`flexval.validation.studies.peers`, when asked), the runtime-versus-error
study (``bench_<scene>.md/.png/.json``) and the report's own wall time.

Units: s (ms where stated); speed-ups are ratios of mean seconds.
"""

from __future__ import annotations

import platform
import statistics
from collections.abc import Callable
from pathlib import Path

from flexval.reducedmodels.catalogue import parse_model

from ..outputs import write_json, write_text
from ..studies import batchtiming
from ..studies.bench import write_bench
from ..studies.campaign import available_cores
from ..studies.peers import AGREEMENT_BAR, geometric_mean
from .data import PAPER_REFERENCE, ReportData, SceneResults
from .figurejobs import draw_now
from .tables import sig

#: file names of the run times, beside report.md
TIMINGS_MD, TIMINGS_JSON = "timings.md", "timings.json"
#: error budgets (percent, largest path displacement error) of the findings (which models
#: stay within each) and of the cheapest-model lines here
BUDGETS = (1.0, 5.0)


def _fmt(v: float | None, digits: int = 2) -> str:
    return "–" if v is None else f"{v:.{digits}f}"


def timing_table(res: SceneResults) -> list[str]:
    """Markdown: our median seconds per load path, alone and batched, beside the paper's (for
    the paper's scenes), and the speed-ups against
    :data:`~flexval.validation.report.data.PAPER_REFERENCE`."""
    paper = res.paper.seconds if res.paper else {}
    with_paper = res.paper is not None  # the paper's columns for the paper's scenes only
    per_case = ("ours (s)", "batched (s)", "paper (s)")[: 3 if with_paper else 2]
    lines = [
        "| model | "
        + " | ".join(f"{c} {what}" for c in res.cases for what in per_case)
        + f" | copies | speed-up vs {PAPER_REFERENCE}, ours | "
        f"speed-up vs {PAPER_REFERENCE}, batched |" + (" paper |" if with_paper else ""),
        "|---|" + "---:|" * (len(per_case) * len(res.cases) + 3 + with_paper),
    ]

    def mean_time(m: str, table: dict | None = None) -> float | None:
        if table is not None:
            vals = [table.get(m, {}).get(c) for c in res.cases]
        else:
            vals = [lp.seconds if (lp := res.converged(m, c)) else None for c in res.cases]
        vals = [v for v in vals if v is not None]
        return sum(vals) / len(vals) if vals else None

    batched = {
        m: {c: t.seconds for (mm, c), t in res.batched.items() if mm == m} for m in res.models
    }
    ref_ours, ref_paper = mean_time(PAPER_REFERENCE), mean_time(PAPER_REFERENCE, paper)
    ref_batched = mean_time(PAPER_REFERENCE, batched)
    for m in res.models:
        spec = parse_model(m)
        cells = []
        for c in res.cases:
            lp, fail, t = res.paths.get((m, c)), res.failure(m, c), res.batched.get((m, c))
            cells.append(fail.summary() if fail else f"{lp.seconds:.4f}" if lp else "–")
            cells.append(
                "not batched"
                if not batchtiming.batched(spec)
                else "–"
                if t is None
                else sig(t.seconds, 3) + ("" if t.agrees else " †")
            )
            if with_paper:
                cells.append(_fmt(paper.get(m, {}).get(c)))
        ours, pap, bat = mean_time(m), mean_time(m, paper), mean_time(m, batched)
        copies = sorted({t.copies for (mm, _), t in res.batched.items() if mm == m})
        su = f"{ref_ours / ours:.3g}x" if ours and ref_ours else "–"
        sb = f"{ref_batched / bat:.3g}x" if bat and ref_batched else "–"
        sp = f"{ref_paper / pap:.3g}x" if pap and ref_paper else "–"
        n = "/".join(str(k) for k in copies) or "–"
        tail = f" | {n} | {su} | {sb} |" + (f" {sp} |" if with_paper else "")
        lines.append(f"| {m} | " + " | ".join(cells) + tail)
    lines += [
        f"- † `{t.model}` on `{t.load_case}`: "
        + (
            "a batched copy did not reach full load"
            if t.agreement is None
            else f"the batched copies' end values differ from the path alone by "
            f"{t.agreement:.2g} (more than {batchtiming.AGREEMENT_BAR:g})"
        )
        + ": its batched time is not that of the same path."
        for t in res.batched.values()
        if not t.agrees
    ]
    return lines


def _cheapest_lines(res: SceneResults, reference: str) -> list[str]:
    """The cheapest model (mean seconds per load path) within each of :data:`BUDGETS`, alone
    and, where every such model was timed in batches, batched."""
    rows = res.worst_errors(reference)
    out = []
    for budget in BUDGETS:
        within = [(m, e) for m, e, _ in rows if e <= budget]
        ok = [
            (sum(res.paths[(m, c)].seconds for c in res.cases) / len(res.cases), m, e)
            for m, e in within
        ]
        if ok:
            s, m, e = min(ok)
            out.append(
                f"- Cheapest model within {budget:g} % of `{reference}` on every load "
                f"case (largest path displacement error): **{m}** ({e:.2f} %, "
                f"{s * 1e3:.1f} ms per load path)."
            )
        timed = [[res.batched.get((m, c)) for c in res.cases] for m, _ in within]
        if within and all(t is not None for ts in timed for t in ts):
            s, m, e = min(
                (sum(t.seconds for t in ts) / len(ts), m, e) for ts, (m, e) in zip(timed, within)
            )
            out.append(
                f"- Batched, the cheapest within {budget:g} %: **{m}** ({e:.2f} %, "
                f"{s * 1e3:.2f} ms per load path)."
            )
    return out


def _convergence_lines(res: SceneResults) -> list[str]:
    L = []
    for st in res.convergence:
        L += [
            f"{st.family} convergence ({st.load_case}), wall time of each run:",
            "",
            "| model | unknowns | seconds |",
            "|---|---:|---:|",
        ]
        L += [f"| {r['model']} | {r['unknowns']} | {r['seconds']:.2f} |" for r in st.rows]
        L += [""]
    return L


def _peer_lines(res: SceneResults) -> list[str]:
    """Markdown: :data:`PAPER_REFERENCE` against OpenSeesPy
    (:mod:`flexval.validation.studies.peers`), or why not."""
    if res.peers is None:
        return []
    title = f"### {PAPER_REFERENCE} against OpenSeesPy"
    if isinstance(res.peers, str):
        return [title, "", f"Not timed: {res.peers}.", ""]
    L = [
        title,
        "",
        "The same mechanism in OpenSeesPy (corotational `elasticBeamColumn`, the same "
        "elements per flexure, rigid bodies as very stiff corotational spokes, load control "
        "with the fewest sub-steps per level that converge), timed in this process after "
        "everything else (`validation/studies/peers.py`, `benchmarks/bench_peers.py`). "
        "Interleaved: "
        "the two codes alternate, each run with the other's caches; back to back: all of "
        "one code's runs, then the other's. Median wall times, model build included; "
        f"agreement of the end values (the bar: {AGREEMENT_BAR} %).",
        "",
        "| case | ours (ms) | OpenSees (ms) | sub-steps | OpenSees / ours | back to back | "
        "agreement (%) |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    timed = [r for r in res.peers if r.substeps is not None]
    for r in res.peers:
        if r.substeps is None:
            L.append(f"| {r.case} | – | – | – | {r.reason} | – | – |")
            continue
        L.append(
            f"| {r.case} | {1e3 * statistics.median(r.ours):.1f} | "
            f"{1e3 * statistics.median(r.theirs):.1f} | {r.substeps} | {r.ratio:.2f}x | "
            f"{r.b2b_ratio:.2f}x | {r.agreement:.4f} |"
        )
    if timed:
        L += [
            "",
            f"- Geometric mean OpenSees / ours: "
            f"{geometric_mean([r.ratio for r in timed]):.2f}x interleaved, "
            f"{geometric_mean([r.b2b_ratio for r in timed]):.2f}x back to back.",
        ]
    return L + [""]


def _scene_lines(res: SceneResults, bench_md: Path | None) -> list[str]:
    """Markdown of one scene's run times (``bench_md``: its runtime-versus-error table)."""
    seconds_note = f" (the paper's {res.paper.seconds_table})" if res.paper else ""
    levels = " or ".join(str(n) for n in sorted({lc.levels for lc in res.scene.load_cases}))
    L = [
        f"## {res.scene.name}",
        "",
        f"### Run times{seconds_note}",
        "",
        f"Ours: median wall time of the whole load path ({levels} levels, model build "
        "included) on this machine"
        + (
            "; the paper's: RecurDyn quasi-static simulations (compare the speed-up columns, "
            "not the seconds)."
            if res.paper
            else "."
        ),
        "",
        "Batched: the same path run as one batch of `copies` identical copies traced "
        "together, the batch's wall time divided by the copies, median of the same "
        "repeats: what a path of the model costs when many are run, the per-path costs "
        f"that every model shares spread over the batch. `copies`: "
        f"{batchtiming.BATCH_COPIES}, where the cost per path of the small models stops "
        f"falling, fewer for a larger model (at most {batchtiming.BATCH_UNKNOWNS} unknowns "
        "in a batch), whose own arithmetic already outweighs the shared costs, and "
        f"{batchtiming.REFERENCE_COPIES} for `{batchtiming.SPEED_REFERENCE}`, where its "
        "cost per path is flat. The continuum reference is not batched. Speed-ups: "
        f"`{PAPER_REFERENCE}`'s mean time over the model's, alone and batched.",
        "",
    ]
    L += timing_table(res) + [""]
    ref = res.reference if res.has_reference() else PAPER_REFERENCE
    L += _cheapest_lines(res, ref)
    if res.bracket and res.bracket.paths:
        L += [
            f"- Computing the `{res.bracket.model}` paths (the plane bracket) takes "
            f"{res.bracket.seconds():.3g} s (wall time of its runs, the report's added cost "
            "when they are not cached)."
        ]
    L += [""] + _peer_lines(res) + _convergence_lines(res)
    if bench_md is not None:
        L += [
            "### Runtime versus error",
            "",
            f"Every model and resolution against `{res.bench_reference}`; details in "
            f"[{bench_md.name}]({bench_md.name}).",
            "",
            f"![runtime vs error]({bench_md.with_suffix('.png').name})",
            "",
        ]
    return L


def write_benches(data: ReportData, out: Path, draw: Callable = draw_now) -> dict[str, Path]:
    """Each scene's runtime-versus-error files
    (:func:`flexval.validation.studies.bench.write_bench`, the
    plot drawn with ``draw``): {scene: its Markdown path}, for the scenes that have one."""
    return {
        res.scene.name: write_bench(
            res.scene, res.bench_rows, res.bench_reference, out, res.bench_failures, draw
        )
        for res in data.scenes
        if res.bench_rows or res.bench_failures
    }


def render_timings(data: ReportData, benches: dict[str, Path], render_seconds: float) -> str:
    """The Markdown of ``timings.md``.

    ``benches``: {scene: runtime-versus-error Markdown} (:func:`write_benches`);
    ``render_seconds``: wall time of writing report.md, its figures and JSON files.
    """
    wall, peers = data.wall_seconds.get("models"), data.wall_seconds.get("peers")
    batched = data.wall_seconds.get("batched")
    total = f"{wall:.1f} s computing, " if wall is not None else ""
    total += f"{batched:.1f} s of it timing batches, " if batched is not None else ""
    total += f"{peers:.1f} s timing OpenSeesPy, " if peers is not None else ""
    lines = [
        "# flexval validation report: run times",
        "",
        "The run times of [report.md](report.md), apart from its results because they "
        "change from run to run (machine, load, cache).",
        "",
        f"- Ours: median of {data.repeats} runs per load path (reference models: one run), "
        f"wall clock, on {data.workers} worker process(es) at a time "
        f"({available_cores()} cores, {platform.machine()}, Python "
        f"{platform.python_version()}). A path read from the result cache keeps the time "
        "of the run that computed it (`cached` in timings.json).",
        f"- This report: {total}{render_seconds:.1f} s writing report.md, its figures "
        "and JSON files.",
        "",
    ]
    for res in data.scenes:
        lines += _scene_lines(res, benches.get(res.scene.name))
    return "\n".join(lines) + "\n"


def write_timings(
    data: ReportData, out: Path, benches: dict[str, Path], render_seconds: float
) -> Path:
    """Write ``timings.md`` (linking the ``benches`` files) and ``timings.json`` into ``out``."""
    md = write_text(out / TIMINGS_MD, render_timings(data, benches, render_seconds))
    write_json(
        out / TIMINGS_JSON,
        {**data.timings(), "wall_seconds": {**data.wall_seconds, "render": render_seconds}},
    )
    return md
