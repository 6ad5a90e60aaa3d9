"""The validation report: the paper's comparison, reproduced and extended.

``build_report`` = :func:`flexval.validation.report.data.compute_report` (every model
run, every error, every study, into a :class:`~flexval.validation.report.data.ReportData`)
followed by :func:`write_report`, whose renderers only format that data into
``report.md`` and its PNG figures, ``results.json`` (every LoadPath and
failure) and ``gates.json`` (every error figure, the baseline of the CI
accuracy gates). Every number in the text is filled in from the data: the
tables against ``beam:100`` (with the paper's figures beside ours where the
paper has the scene) and against the continuum reference, failures ("fails at
84 % (limit point, 0.126 N)") wherever the model appears, the natural
frequencies at rest, the findings and the discussion. The continuum
reference's stress picture at full load is the one figure that computes: it
solves its load case again on a figure worker (a load path keeps no state).
The run times are written apart (:mod:`flexval.validation.report.timings`), so that the
report, results.json and gates.json are the same from one run of the same
code to the next.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path

from flexval.reducedmodels.catalogue import FIELDS, parse_model

from ..failures import Failure
from ..outputs import output_path, write_json, write_text
from ..studies import parasitic
from ..studies.convergence import order_text
from . import drivereaction, figures, frequencies, stiffnesstable, strength
from . import measured as measuredreport
from .data import (
    DEFAULT_MODELS,
    PAPER_REFERENCE,
    FrameRow,
    ReportData,
    SceneResults,
    compute_report,
)
from .figurejobs import Figures, draw_now
from .protocol import PROTOCOL_SCENE, protocol_section
from .tables import sig
from .threed import threed_section
from .timings import BUDGETS, TIMINGS_MD, write_benches, write_timings

__all__ = [
    "DEFAULT_MODELS",
    "PAPER_REFERENCE",
    "SceneResults",
    "build_report",
    "render_markdown",
    "write_report",
]

#: how many largest errors the findings list
N_LARGEST = 3


def _fmt(v: float | None, digits: int = 1) -> str:
    return "–" if v is None else f"{v:.{digits}f}"


def _paper_table(res: SceneResults) -> list[str]:
    """Markdown: errors against beam:100, ours beside the paper's (where the paper has them)."""
    ours = res.error_table(PAPER_REFERENCE)
    paper = res.paper.percent if res.paper else {}
    head = "| model | " + " | ".join(f"{c} disp | {c} rot" for c in res.cases) + " |"
    lines = [head, "|---|" + "---:|" * (2 * len(res.cases))]
    for m in res.models:
        if m in (PAPER_REFERENCE, res.reference):
            continue
        if m not in ours and not any(res.failure(m, c) for c in res.cases):
            continue
        cells = []
        for c in res.cases:
            e, p, fail = ours.get(m, {}).get(c), paper.get(m, {}).get(c), res.failure(m, c)
            for key, pk in (("end_disp_vec", "disp"), ("end_rot", "rot")):
                txt = (
                    fail.summary()
                    if fail and key == "end_disp_vec"
                    else _fmt(e[key] if e else None)
                )
                txt += f" ({_fmt(p[pk])})" if p else ""
                cells.append(txt)
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return lines


def _metrics_table(res: SceneResults, reference: str) -> list[str]:
    """Markdown: all metrics against ``reference`` per model and load case (failures too)."""
    table = res.error_table(reference)
    lines = [
        "| model | case | end disp vec (%) | end disp magnitude (%) | end rot (%) | "
        "path disp (%) | path rot (%) |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for m in res.models:
        if m == reference:
            continue
        for c in res.cases:
            e, fail = table.get(m, {}).get(c), res.failure(m, c)
            if e is not None:
                lines.append(
                    f"| {m} | {c} | {e['end_disp_vec']:.2f} | {e['end_disp']:.2f} | "
                    f"{e['end_rot']:.2f} | {e['path_disp']:.2f} | {e['path_rot']:.2f} |"
                )
            elif fail is not None:
                lines.append(f"| {m} | {c} | {fail.summary()} | – | – | – | – |")
    return lines


def _frame_table(rows: list[FrameRow], cases: list[str]) -> list[str]:
    """Markdown: end-of-ramp errors against beam:100 with each measuring frame (percent)."""
    lines = [
        "| model | frame | " + " | ".join(f"{c} disp | {c} rot" for c in cases) + " |",
        "|---|---|" + "---:|" * (2 * len(cases)),
    ]
    for r in rows:
        cells = []
        for c in cases:
            v = r.cells.get(c)
            if isinstance(v, Failure):
                cells += [v.summary(), "–"]
            elif v is None:
                cells += ["–", "–"]
            else:
                cells += [f"{v['end_disp_vec']:.1f}", f"{v['end_rot']:.1f}"]
        lines.append(f"| {r.model} | {r.frame} | " + " | ".join(cells) + " |")
    return lines


def _bracket_lines(res: SceneResults) -> list[str]:
    """Markdown: the continuum reference in plane stress and plane strain (a wide flexure
    lies between), and whether each reduced model's error exceeds the bracket's width."""
    rows = res.bracket_rows()
    if not rows:
        return _failure_lines(res.bracket.failures) if res.bracket else []
    other = res.bracket.model
    L = [
        f"### Plane-stress / plane-strain bracket (`{res.reference}` and `{other}`)",
        "",
        "A flexure much wider than thick (b >> h) lies between plane stress and plane strain: "
        "end-of-ramp target displacement |d| and rotation with both, and their relative "
        "spread (percent of the reference's value).",
        "",
        f"| case | disp. `{res.reference}` (mm) | disp. `{other}` (mm) | spread (%) | "
        f"rotation `{res.reference}` (deg) | rotation `{other}` (deg) | spread (%) |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for c, b in rows.items():
        L.append(
            f"| {c} | {b['disp']:.6g} | {b['disp_other']:.6g} | {b['disp_spread']:.3g} | "
            f"{math.degrees(b['rot']):.6g} | {math.degrees(b['rot_other']):.6g} | "
            f"{b['rot_spread']:.3g} |"
        )
    L += _failure_lines(res.bracket.failures)
    return L + ["", _bracket_verdict(res, rows), ""]


def _bracket_verdict(res: SceneResults, rows: dict[str, dict[str, float]]) -> str:
    """One sentence: is each reduced model's end |d| and rotation error (against the
    reference) larger or smaller than the plane bracket's spread on the same case?"""
    larger: dict[str, list[str]] = {}
    smaller: dict[str, list[str]] = {}
    for m, per_case in res.error_table(res.reference).items():
        for c, e in per_case.items():
            if c not in rows:
                continue
            for key, spread, what in (
                ("end_disp", "disp_spread", "|d|"),
                ("end_rot", "rot_spread", "rotation"),
            ):
                side = larger if e[key] > rows[c][spread] else smaller
                side.setdefault(m, []).append(f"{c} {what}")
    against = f"(end |d| and rotation, against `{res.reference}`)"
    if not larger and not smaller:
        return "No reduced model reached full load on a case where both planes did."
    if not smaller:
        return (
            f"Every reduced model's error {against} is larger than the bracket's width: "
            "the plane assumption does not explain the differences from the continuum."
        )
    if not larger:
        return (
            f"Every reduced model's error {against} is smaller than the bracket's width: "
            "the plane assumption matters more than the choice among these models."
        )
    parts = []
    below = [f"`{m}`" for m in smaller if m not in larger]
    above = [f"`{m}`" for m in larger if m not in smaller]
    mixed = [f"`{m}` (larger on {', '.join(larger[m])})" for m in larger if m in smaller]
    if below:
        parts.append("smaller on every case: " + ", ".join(below))
    if above:
        parts.append("larger on every case: " + ", ".join(above))
    if mixed:
        parts.append("mixed: " + "; ".join(mixed))
    return (
        f"Reduced models' errors {against} against the bracket's width: " + "; ".join(parts) + "."
    )


def _failure_lines(failures: list[Failure]) -> list[str]:
    return [f"- `{f.model}` on `{f.load_case}` {f.summary()}." for f in failures]


def _bifurcation_lines(res: SceneResults) -> list[str]:
    """One line per model and load case whose path has a bifurcation point: the first."""
    return [
        f"- `{m}` on `{c}` has a bifurcation point at {b['load']:.5g} {unit} "
        f"({100 * b['fraction']:.2f} % of the full load): the tangent turns indefinite "
        "while the load still rises, another branch crosses the path there."
        for m, c, b, unit in res.bifurcations()
    ]


def _validity_lines(res: SceneResults) -> list[str]:
    """One line per model and load case whose path leaves the model's range of meaning.

    From the validity monitor's verdict per level (``LoadPath.valid``): the
    first level judged invalid, its load and the reason, so that an error
    figure computed there is read as what it is.
    """
    out = []
    for (model, case), lp in sorted(res.paths.items()):
        bad = [k for k, ok in enumerate(lp.valid or []) if ok is False]
        if bad:
            k = bad[0]
            out.append(
                f"- `{model}` on `{case}` leaves its range of validity from "
                f"{lp.load[k]:.4g} {lp.load_unit} ({len(bad)} of {len(lp.valid)} "
                f"levels): {lp.validity[k]}."
            )
    return out


def _findings(res: SceneResults, reference: str) -> list[str]:
    """Plain-words findings computed from the error and timing tables, the failures and
    the validity monitor."""
    failed = {f.model for f in res.failures}
    out = _failure_lines(res.failures) + _bifurcation_lines(res) + _validity_lines(res)
    rows = res.worst_errors(reference)
    if not rows:
        return out + [f"- No model could be compared with `{reference}` on every load case."]
    note = " (models that fail on a load case are not counted)" if failed else ""
    for budget in BUDGETS:
        ok = sorted((r for r in rows if r[1] <= budget), key=lambda r: r[1])
        if ok:
            out.append(
                f"- Within {budget:g} % of `{reference}` on every load case (largest "
                f"path displacement error){note}: "
                + ", ".join(f"`{m}` ({e:.2f} %)" for m, e, _ in ok)
                + "; the cheapest of them is named in [timings.md](timings.md)."
            )
        else:
            out.append(
                f"- No model stays within {budget:g} % of `{reference}` on every case{note}."
            )
    for m, e, c in sorted(rows, key=lambda r: -r[1])[:N_LARGEST]:
        out.append(f"- Largest error: `{m}` on `{c}`, {e:.1f} % (path displacement).")
    return out


def _convergence_lines(res: SceneResults, out: Path, draw: Callable) -> list[str]:
    L = []
    name = res.scene.name
    for st in res.convergence:
        fibre = any(r.get("fibre_stress") is not None for r in st.rows)
        L += [
            f"### {st.family} convergence ({st.load_case})",
            "",
            "| model | unknowns | disp. (mm) | rotation (deg) |"
            + (" fibre stress (MPa) |" if fibre else ""),
            "|---|---:|---:|---:|" + ("---:|" if fibre else ""),
        ]
        for r in st.rows:
            L.append(
                f"| {r['model']} | {r['unknowns']} | "
                f"{r['displacement']:.6f} | {math.degrees(r['rotation']):.6f} |"
                + (f" {sig(r.get('fibre_stress'), 6)} |" if fibre else "")
            )
        L += [f"| {f.model} | {f.summary()} | | |" + (" |" if fibre else "") for f in st.failures]
        for key, s in st.summary.items():
            gci = "n/a" if s["gci_percent"] is None else f"{s['gci_percent']:.3g} %"
            L.append(
                f"\n{key}: observed order {order_text(s)}, Richardson value "
                f"{s['extrapolated']:.6g}, GCI {gci}."
            )
        if st.rows:
            png = output_path(out, f"{name}_{st.load_case}_{st.family}_convergence", ".png")
            draw(
                figures.convergence,
                st.rows,
                {k: v["extrapolated"] for k, v in st.summary.items()},
                f"{name} {st.load_case}: {st.family} convergence",
                png,
            )
            L += ["", f"![convergence]({png.name})"]
        L += [""]
    return L


def _field_picture_lines(res: SceneResults, out: Path, draw: Callable) -> list[str]:
    """Markdown: the continuum reference's stress picture at full load on every load case,
    or a sentence saying why it is not drawn (no reference with stress fields, or one that
    does not reach full load on the case).

    The report's load paths keep no state, so each picture solves its case again
    (:func:`flexval.validation.report.figures.field_picture`, on the figure workers).
    """
    L = ["### Continuum stress at full load", ""]
    ref = res.reference
    if ref is None:
        return L + [
            "Not drawn: the report's models include no continuum reference "
            "(a model with stress fields, e.g. `continuum`).",
            "",
        ]
    if not parse_model(ref).model_family.has(FIELDS):
        return L + [f"Not drawn: the reference `{ref}` computes no stress field.", ""]
    L += [
        f"Each load case solved again with `{ref}` up to full load (the tables' path; "
        "the stored paths keep no state): the mechanism deformed at true scale over its "
        "undeformed outline (grey), each flexure at its true thickness coloured by the "
        "fibre stress along it (MPa, tension positive), and a zoom on the most stressed "
        "section (at a notch, its neck). The colour range is the largest stress beyond the "
        "boundary layers at each flexure's clamped end faces, where the continuum's stress "
        "is singular; the colour bar says how high those layers reach.",
        "",
    ]
    name = res.scene.name
    for c in res.cases:
        if res.converged(ref, c) is None:
            fail = res.failure(ref, c)
            why = fail.summary() if fail else "does not reach full load"
            L += [f"`{c}`: not drawn, `{ref}` {why}: there is no state at full load.", ""]
            continue
        png = output_path(out, f"{name}_{c}_continuum_stress", ".png")
        draw(figures.field_picture, res.scene, ref, c, png)
        L += [f"![{name} {c}: continuum stress]({png.name})", ""]
    return L


def _levels_text(data: ReportData) -> str:
    levels = sorted({lc.levels for r in data.scenes for lc in r.scene.load_cases})
    return " or ".join(str(n) for n in levels)


def _loads_text(data: ReportData) -> str:
    """'dead loads', and prescribed motions where a scene's load case has one."""
    driven = any(case.drive is not None for r in data.scenes for case in r.scene.load_cases)
    return "dead loads and prescribed motions (the reaction the answer)" if driven else "dead loads"


def _thickness_words(section) -> str:
    """``h = 0.5 mm``, or a varying section's law (a taper's ends, a notch's t and H)."""
    profile = section.profile
    if profile is None:
        return f"h = {section.thickness:g} mm"
    if profile.kind == "notch":
        return (
            f"{profile.contour} notch t = {profile.min_thickness:g} mm, "
            f"H = {profile.max_thickness:g} mm"
        )
    start, end = profile.parameters()["thickness"]
    return f"h = {start:g} to {end:g} mm (taper)"


def _scene_section(
    res: SceneResults, out: Path, draw: Callable, threed: Path | None, code: str
) -> list[str]:
    """Markdown of one scene; draws its figures into ``out`` with ``draw(fn, *args)``."""
    from .drawing import plot_mechanism

    sc, name = res.scene, res.scene.name
    mechanism_png = output_path(out, f"{name}_mechanism", ".png")
    draw(plot_mechanism, sc, mechanism_png)
    mech = sc.mechanism
    chain = (
        "an open chain"
        if res.loops == 0
        else f"a closed chain ({res.loops} independent loop{'s' if res.loops > 1 else ''})"
    )
    L = [
        f"## {name}",
        "",
        sc.description,
        "",
        f"![{name}]({mechanism_png.name})",
        "",
        f"{len(mech.flexures)} flexures, {len(mech.pins)} pins, {len(mech.bodies)} bodies "
        f"(ground included): {chain}. "
        f"E = {mech.material.youngs_modulus:g} MPa, nu = {mech.material.poisson_ratio:g}; "
        + "; ".join(
            f"{f.name}: b = {f.section.depth:g} mm, {_thickness_words(f.section)}, "
            f"L = {f.shape.length:.3f} mm"
            for f in mech.flexures
        )
        + ".",
        "",
    ]
    if res.failures:
        L += [
            "**Failures** (the model's path up to its last converged load is kept in the "
            "load-path figures and results.json; a path traced by arc length through a limit "
            "point is drawn dashed in the load-path figure):",
            "",
        ]
        L += [
            f"- `{f.model}` on `{f.load_case}` {f.summary()}: {f.message}" for f in res.failures
        ] + [""]
    paper_note = (
        f"; the paper's {res.paper.percent_table} value in parentheses" if res.paper else ""
    )
    L += [
        f"### Errors against `{PAPER_REFERENCE}` "
        + ("(the paper's convention)" if res.paper else "(the fine beam model)"),
        "",
        f"End-of-ramp displacement-vector error and rotation error in percent{paper_note}.",
        "",
    ]
    L += _paper_table(res) + [""]
    L += [f"All metrics against `{PAPER_REFERENCE}`:", ""]
    L += _metrics_table(res, PAPER_REFERENCE) + [""]
    if res.frames:
        L += [
            "Models with a measuring-frame option, each element's relative displacement "
            "measured in the displaced frame of its leading body (body i of e_ij, the paper's "
            "text and our default) or of the following body j (end-of-ramp errors against "
            f"`{PAPER_REFERENCE}`, percent):",
            "",
        ]
        L += _frame_table(res.frames, res.cases) + [""]
    if res.has_reference():
        L += [f"### Errors against the continuum reference `{res.reference}`", ""]
        L += _metrics_table(res, res.reference) + [""]
        L += _bracket_lines(res)
    L += parasitic.section(res, res.reference if res.has_reference() else PAPER_REFERENCE)
    L += drivereaction.section(res, res.reference if res.has_reference() else PAPER_REFERENCE)
    if res.stiffness is not None:
        L += stiffnesstable.section(res.stiffness)
    if threed is not None or res.paper:
        L += threed_section(threed, res.scene.name, code)
    L += strength.section(
        sc,
        res.paths,
        res.failures,
        res.models,
        res.reference if res.has_reference() else PAPER_REFERENCE,
        out,
        draw,
        res.convergence,
    )
    if res.frequencies is not None:
        L += frequencies.section(res.frequencies)
    seconds_note = f" ({res.paper.seconds_table})" if res.paper else ""
    L += [
        f"### Run times{seconds_note}",
        "",
        f"In [{TIMINGS_MD}]({TIMINGS_MD}), with the speed-ups"
        + (" and the paper's" if res.paper else "")
        + ": they change from run to run, the results above do not.",
        "",
    ]
    L += ["### Load paths", ""]
    for c in res.cases:
        paths = {m: res.paths[(m, c)] for m in res.models if (m, c) in res.paths}
        png = output_path(out, f"{name}_{c}_paths", ".png")
        draw(figures.load_paths, sc, c, paths, png, res.traces(c))
        L += [f"![{name} {c}]({png.name})", ""]
    rec = [
        m
        for m in (res.reference, PAPER_REFERENCE)
        if m and res.converged(m, res.cases[0]) and res.paths[(m, res.cases[0])].poses
    ]
    if rec:
        L += [f"### Deformed configurations (`{rec[-1]}`)", ""]
        for c in res.cases:
            lp = res.converged(rec[-1], c)
            if lp and lp.poses and lp.shapes:
                png = output_path(out, f"{name}_{c}_deformed", ".png")
                draw(figures.deformed, sc, c, lp, png)
                L += [f"![{c}]({png.name})", ""]
        if res.loops > 0:
            fig_note = (
                f" (paper {res.paper.relative_rotations_figure})"
                if res.paper and res.paper.relative_rotations_figure
                else ""
            )
            L += [f"Relative rotations of the links{fig_note}:", ""]
            for c in res.cases:
                lp = res.converged(rec[-1], c)
                if lp and lp.poses:
                    png = output_path(out, f"{name}_{c}_relrot", ".png")
                    draw(figures.relative_rotations, sc, c, lp, png)
                    L += [f"![{c}]({png.name})", ""]
    L += _field_picture_lines(res, out, draw)
    L += measuredreport.section(res.measured, out, draw)
    if res.bench_rows or res.bench_failures:
        L += [
            "### Runtime versus error",
            "",
            f"Every model and resolution against `{res.bench_reference}`: in "
            f"[{TIMINGS_MD}]({TIMINGS_MD}).",
            "",
        ]
        L += _failure_lines(res.bench_failures) + [""]
    L += _convergence_lines(res, out, draw)
    ref = res.reference if res.has_reference() else PAPER_REFERENCE
    L += [f"### Findings ({name}, against `{ref}`)", ""]
    L += _findings(res, ref) + [""]
    return L


def render_markdown(
    data: ReportData,
    out: Path,
    draw: Callable = draw_now,
    protocol: Path | None = None,
    threed: Path | None = None,
) -> str:
    """The report's Markdown, drawing its figures into ``out`` with ``draw(fn, *args)``
    (default: at once; :meth:`flexval.validation.report.figurejobs.Figures.draw` on worker
    processes);
    ``protocol`` is the ``protocol.json`` of ``benchmarks/paper_protocol.py`` (None: not given),
    summarised in its own section when the scenes include the open chain; ``threed`` the
    ``threed.json`` of ``benchmarks/threed_study.py`` (None: not given), each scene's section
    "2D idealisation against 3D"."""
    from .discussion import discussion

    if any(r.paper for r in data.scenes):
        scope = (
            "Flexibility models of planar compliant mechanisms with curved flexures: "
            "the comparison of Sorgonà, Cirelli, Giannini, Verotti (Multibody Syst. Dyn., "
            f"2024) reproduced with `{PAPER_REFERENCE}` as reference (the paper's "
            "convention), and extended with a continuum reference (2D plane-stress solid, "
            "geometrically nonlinear hyperelastic, scikit-fem)."
        )
    else:
        scope = (
            "Flexibility models of planar compliant mechanisms against a continuum reference "
            "(2D plane-stress solid of each flexure's true outline, geometrically nonlinear "
            "hyperelastic, scikit-fem), with the paper's fine beam model "
            f"`{PAPER_REFERENCE}` as a second reference: the models and tables of Sorgonà, "
            "Cirelli, Giannini, Verotti (Multibody Syst. Dyn., 2024) applied to mechanisms "
            "of their own."
        )
    lines = [
        "# flexval validation report",
        "",
        scope,
        "",
        "## Setup",
        "",
        f"- Models: {', '.join(f'`{m}`' for m in data.models)}.",
        f"- Loads: {_loads_text(data)} ramped from zero in {_levels_text(data)} equal "
        "levels; errors are compared at matched load levels.",
        "- Error metrics (percent): **end disp vec** = |d_model − d_ref| / |d_ref| at full "
        "load (d = target point displacement vector); **end |d|** = relative difference of "
        "the displacement magnitudes; **end rot** = |θ_model − θ_ref| / |θ_ref| at full load "
        "(θ = target body rotation); **path disp** = max over levels of |d_model − d_ref| / "
        "max over levels of |d_ref|; **path rot** likewise. *End disp vec* and *end rot* "
        "are the metrics of the paper tables (see the discussion for how they compare "
        "with the paper's figures).",
        f"- Run times: in [{TIMINGS_MD}]({TIMINGS_MD}) with `timings.json`, apart from "
        "the results (report.md, results.json and gates.json are the same from one run of "
        "the same code to the next).",
        "- A model that fails on a load case is reported where it appears: how far it got "
        "(percent of the load), why (a limit point found by arc length, a bifurcation, or "
        "the solver's reason) and the load.",
        f"- Tools: {data.versions}.",
        "",
    ]
    for res in data.scenes:
        lines += _scene_section(res, out, draw, threed, data.code)
    if any(res.scene.name == PROTOCOL_SCENE for res in data.scenes):
        lines += protocol_section(protocol, out, data.code)
    lines += discussion(data)
    return "\n".join(lines) + "\n"


def write_report(
    data: ReportData,
    out: Path,
    protocol: Path | None = None,
    threed: Path | None = None,
    timings: Path | None = None,
) -> Path:
    """Write ``report.md`` (with figures), ``results.json`` and ``gates.json`` into ``out``,
    and the run times (:mod:`flexval.validation.report.timings`) into ``timings`` (default: ``out``;
    report.md links the ``timings.md`` beside it either way); the figures are drawn on
    ``data.workers`` processes while the text is written. ``protocol``, ``threed``: as in
    :func:`render_markdown`."""
    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    timings = out if timings is None else timings
    timings.mkdir(parents=True, exist_ok=True)
    with Figures(data.workers) as figs:
        md = write_text(out / "report.md", render_markdown(data, out, figs.draw, protocol, threed))
        write_json(out / "results.json", data.results())
        write_json(out / "gates.json", data.gates())
        benches = write_benches(data, timings, figs.draw)
        figs.wait()
    write_timings(data, timings, benches, time.perf_counter() - t0)
    return md


def build_report(
    scene_names: list[str],
    out: Path,
    models: list[str] | None = None,
    repeats: int = 3,
    use_cache: bool = True,
    progress: bool = True,
    bench: bool = True,
    converge: bool = True,
    workers: int = 1,
    protocol: Path | None = None,
    peers: bool = False,
    batched: bool = True,
    threed: Path | None = None,
) -> Path:
    """Compute everything (on ``workers`` processes), then write ``out/report.md``, its
    figures, JSON files and run times; ``protocol``, ``threed``: as in :func:`render_markdown`;
    ``peers``: time beam:100 against OpenSeesPy too; ``batched``: time the models in
    batches of identical copies too (both :func:`compute_report`)."""
    data = compute_report(
        scene_names, models, repeats, use_cache, progress, bench, converge, workers, peers, batched
    )
    return write_report(data, out, protocol, threed)
