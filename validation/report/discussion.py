"""The report's discussion: statements whose every number is read from the report's data.

Each function takes the :class:`~flexval.validation.report.data.ReportData` and returns
one bullet (or nothing when the data it needs is absent: no paper figures, no
continuum reference ...), so the text cannot go stale when a model changes.
Errors in percent, loads as a percentage of the full load.
"""

from __future__ import annotations

import numpy as np

from ..failures import Failure
from .data import PAPER_REFERENCE, ReportData, SceneResults

#: how many entries the "paper far above ours" statement names
N_LISTED = 2
#: the paper prints percentages to 0.1: ours "match" a figure within half of that
PRINTED = 0.05
#: percent: a gap between the fine beam and the continuum below this is "small" (the
#: finest band of the sweeps' agreement maps)
SMALL_GAP = 1.0


def _pct(x: float) -> str:
    return f"{x:.1f} %"


def _reference_bullet(data: ReportData) -> list[str]:
    parts, ratios, wide = [], [], []
    for r in data.scenes:
        if not r.has_reference():
            continue
        e = r.error_table(r.reference).get(PAPER_REFERENCE, {})
        if len(e) < len(r.cases):
            continue
        disp = max(v["path_disp"] for v in e.values())
        rot = max(v["path_rot"] for v in e.values())
        parts.append(
            f"{_pct(disp)} (displacement) and {_pct(rot)} (rotation) along every "
            f"path of {r.scene.name}"
        )
        if max(disp, rot) > SMALL_GAP:
            wide.append((r.scene.name, max(disp, rot)))
        ratios += [
            f.section.thickness / f.shape.radius
            for f in r.scene.mechanism.flexures
            if hasattr(f.shape, "radius")
        ]
    if not parts:
        return []
    slender = (
        f" for arcs with h/r = {min(ratios):.2g} to {max(ratios):.2g}, where it enters "
        f"at order (h/r)^2 = {min(ratios) ** 2:.1g} to {max(ratios) ** 2:.1g}"
        if ratios
        else ""
    )
    if not wide:
        verdict = (
            f": the continuum's extra physics (shear, Poisson, finite thickness) is small{slender}."
        )
    else:
        named = ", ".join(f"{name} (up to {_pct(gap)})" for name, gap in wide)
        verdict = (
            f": the continuum's extra physics (shear, Poisson, finite thickness) is not small "
            f"on {named}. There a section is thick for its length or changes fast along it "
            "(a notch), beam theory's plane sections and uniaxial stress no longer hold, and "
            "every reduced model, built on the same beam compliance, inherits the gap."
        )
    return [
        f"- **The reference.** `{PAPER_REFERENCE}` and the continuum `{data.reference}` "
        "differ by at most "
        + "; ".join(parts)
        + verdict
        + " Mesh convergence of the continuum is reported per scene with its observed order "
        "and GCI."
    ]


def _paper_entries(data: ReportData):
    """(scene results, model, case, our errors, paper figures) of every paper entry we have."""
    for r in data.scenes:
        if r.paper is None:
            continue
        ours = r.error_table(PAPER_REFERENCE)
        for m, per_case in r.paper.percent.items():
            for c, p in per_case.items():
                e = ours.get(m, {}).get(c)
                if e is not None:
                    yield r, m, c, e, p


def _metric_bullet(data: ReportData) -> list[str]:
    entries = list(_paper_entries(data))
    if not entries:
        return []
    closer = [
        x
        for x in entries
        if abs(x[3]["end_disp_vec"] - x[4]["disp"]) <= abs(x[3]["end_disp"] - x[4]["disp"])
    ]
    text = (
        f"- **The metric.** The paper's 'disp' column is as close or closer to our "
        f"end-of-ramp error of the displacement *vector* than to that of its magnitude in "
        f"{len(closer)} of {len(entries)} entries"
    )
    matched = [x for x in entries if abs(x[3]["end_disp_vec"] - x[4]["disp"]) <= PRINTED]
    if matched:
        r, m, c, e, p = max(matched, key=lambda x: abs(x[3]["end_disp"] - x[4]["disp"]))
        text += (
            f"; e.g. `{m}` on `{c}` of {r.scene.name}: vector {_pct(e['end_disp_vec'])}, "
            f"magnitude {_pct(e['end_disp'])}, paper {_pct(p['disp'])}"
        )
    return [text + "."]


def _softest_stretch(
    ref_load: list[float], ref_dx: list[float], ref_dy: list[float]
) -> tuple[float, float]:
    """Load interval (percent of full load) of the largest displacement increment per load."""
    lam = np.abs(np.asarray(ref_load)) / max(abs(ref_load[-1]), np.finfo(float).tiny)
    d = np.hypot(ref_dx, ref_dy)
    rate = np.abs(np.diff(d)) / np.maximum(np.diff(lam), np.finfo(float).tiny)
    k = int(np.argmax(rate))
    return 100 * lam[k], 100 * lam[k + 1]


def _path_bullet(data: ReportData) -> list[str]:
    best = None
    for r in data.scenes:
        for m, per_case in r.error_table(PAPER_REFERENCE).items():
            for c, e in per_case.items():
                gap = e["path_disp"] - e["end_disp_vec"]
                if best is None or gap > best[0]:
                    best = (gap, r, m, c, e)
    if best is None or best[0] <= 0:
        return []
    _, r, m, c, e = best
    ref = r.converged(PAPER_REFERENCE, c)
    lo, hi = _softest_stretch(ref.load, ref.dx, ref.dy)
    return [
        f"- **Path maxima.** The largest gap between a path maximum and the end-of-ramp "
        f"error is `{m}` on `{c}` of {r.scene.name}: {_pct(e['path_disp'])} along the path, "
        f"{_pct(e['end_disp_vec'])} at the end. There the reference is softest between "
        f"{lo:.0f} % and {hi:.0f} % of the load (its largest displacement increment per "
        "load step), where models disagree most."
    ]


def _paper_above_bullet(data: ReportData) -> list[str]:
    entries = sorted(_paper_entries(data), key=lambda x: x[3]["end_disp_vec"] - x[4]["disp"])
    above = [x for x in entries if x[4]["disp"] > x[3]["end_disp_vec"]][:N_LISTED]
    if not above:
        return []
    named = "; ".join(
        f"`{m}` on `{c}` of {r.scene.name} (paper {_pct(p['disp'])}, ours "
        f"{_pct(e['end_disp_vec'])} at the end and {_pct(e['path_disp'])} at most "
        "along the path)"
        for r, m, c, e, p in above
    )
    return [
        f"- **Where the paper's figures are above ours.** Most: {named}. A dynamic "
        "quasi-static simulation (the paper used RecurDyn with damping) lags behind a steep "
        "stretch of the path, so its errors can approach our path maxima rather than our "
        "end-of-ramp errors."
    ]


def _frame_bullet(data: ReportData) -> list[str]:
    per_model: dict[str, list] = {}
    spread: dict[str, list[float]] = {}
    other = ""
    for r in data.scenes:
        rows: dict[str, dict[str, dict]] = {}
        for row in r.frames:
            rows.setdefault(row.model, {})[row.frame] = row.cells
        for m, by_frame in rows.items():
            frames = list(by_frame)
            if len(frames) != 2:
                continue
            default, other = frames
            for c in r.cases:
                a, b = by_frame[default].get(c), by_frame[other].get(c)
                if not isinstance(a, dict) or not isinstance(b, dict):
                    continue
                spread.setdefault(m, []).append(abs(a["end_disp_vec"] - b["end_disp_vec"]))
                p = r.paper.percent.get(m, {}).get(c) if r.paper else None
                if p is not None:
                    gap_a = abs(a["end_disp_vec"] - p["disp"]) + abs(a["end_rot"] - p["rot"])
                    gap_b = abs(b["end_disp_vec"] - p["disp"]) + abs(b["end_rot"] - p["rot"])
                    per_model.setdefault(m, []).append(gap_b < gap_a)
    if not spread:
        return []
    text = (
        "- **Measuring frame.** The paper's text measures each element in its leading "
        "body's displaced frame (our default)."
    )
    if per_model:
        counts = ", ".join(f"`{m}` on {sum(v)} of {len(v)}" for m, v in per_model.items())
        text += (
            f" Measuring in the `{other}` frame brings the end-of-ramp errors closer to "
            f"the paper's figures for {counts} entries."
        )
    means = {m: float(np.mean(v)) for m, v in spread.items()}
    text += " The two frames' displacement errors differ on average by " + ", ".join(
        f"{v:.2g} points for `{m}`" for m, v in means.items()
    )
    vals = list(means.values())
    if len(vals) > 1 and all(x > y for x, y in zip(vals, vals[1:])):
        text += ": the choice fades as the resolution grows"
    return [text + "."]


def _at_or_below_bullet(data: ReportData) -> list[str]:
    counts: dict[str, list[bool]] = {}
    for _, m, _, e, p in _paper_entries(data):
        if m == PAPER_REFERENCE:
            continue
        counts.setdefault(m, []).append(
            e["end_disp_vec"] <= p["disp"] + PRINTED and e["end_rot"] <= p["rot"] + PRINTED
        )
    if not counts:
        return []
    return [
        "- **Ours against the paper's.** Entries where both our end-of-ramp errors are at "
        "or below the paper's figures (within its rounding to 0.1): "
        + ", ".join(f"`{m}` {sum(v)} of {len(v)}" for m, v in counts.items())
        + "."
    ]


def _times_bullet(data: ReportData) -> list[str]:
    if not any(r.paper for r in data.scenes):
        return []
    return [
        "- **Run times.** Ours are static Newton solutions on one core path in Python, the "
        "paper's are dynamic quasi-static runs in a commercial multibody code: compare the "
        "speed-up columns of [timings.md](timings.md), not the seconds."
    ]


def _failures_bullet(data: ReportData) -> list[str]:
    fails: list[tuple[SceneResults, Failure]] = [(r, f) for r in data.scenes for f in r.failures]
    if not fails:
        return ["- **Failures.** Every model reached the full load on every load case."]
    return [
        "- **Failures.** "
        + "; ".join(
            f"`{f.model}` on `{f.load_case}` of {r.scene.name} {f.summary()}" for r, f in fails
        )
        + ". Their paths up to the last converged load are in the figures and "
        "results.json; the tables show the failure in their place."
    ]


def _bifurcations_bullet(data: ReportData) -> list[str]:
    found = [(r, *b) for r in data.scenes for b in r.bifurcations()]
    if not found:
        return []
    bullets = [
        "- **Bifurcations.** "
        + "; ".join(
            f"`{m}` on `{c}` of {r.scene.name} at {b['load']:.5g} {unit} "
            f"({100 * b['fraction']:.2f} % of the full load)"
            for r, m, c, b, unit in found
        )
        + ". Load control cannot pass one (beyond it the path it follows is unstable); "
        "`flexval run --arclength` traces on along it, `--branch-switch` onto the crossing "
        "branch."
    ]
    missed = [(r, *b) for r in data.scenes for b in r.past_reference_bifurcation()]
    if missed:
        bullets.append(
            "- **Buckling missed.** "
            + "; ".join(
                f"`{m}` on `{c}` of {r.scene.name} reaches the full load past the "
                f"reference's bifurcation at {b['load']:.5g} {unit}"
                for r, m, c, b, unit in missed
            )
            + ". These models have no geometric stiffness in the buckling mode (a linear "
            "model, or a chain too coarse to bend in it): their results beyond that load "
            "describe a state the mechanism does not reach stably, and no error is computed "
            "for them."
        )
    return bullets


def discussion(data: ReportData) -> list[str]:
    """The report's discussion section (Markdown lines)."""
    bullets = []
    for make in (
        _reference_bullet,
        _metric_bullet,
        _path_bullet,
        _paper_above_bullet,
        _frame_bullet,
        _at_or_below_bullet,
        _times_bullet,
        _failures_bullet,
        _bifurcations_bullet,
    ):
        bullets += make(data)
    return ["## Discussion", ""] + bullets + [""]
