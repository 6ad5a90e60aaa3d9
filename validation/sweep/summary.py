"""Summary of a sweep's results: Markdown, error figures and run-time distributions.

The summary metric of a (point, model) pair is the largest over the sweep's
load cases of the sweep's ``metric`` (``worst`` = max(end_disp_vec,
end_rot), percent); a pair with a failed case has none. The peak-stress
metric is likewise the largest |peak stress error| over the load cases.
``summary.md`` holds only results that do not depend on the machine
(errors, peak stresses, limit loads, regions, failures); run times go to
``timings.md`` and ``runtime.png``.

Figures (``errors.png`` for the summary metric, ``stress.png`` for the
peak-stress error): one swept axis (or zipped axes, against the first) ->
lines; two axes on a grid -> one heat map per model with the 1 % and 5 %
contours; otherwise the error against each parameter as scatter plots.
``limits.png``: the limit loads found, against the first parameter.

Units: errors in percent, stresses in MPa, loads in N or N mm, times in s,
parameters in their field's unit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..outputs import save_figure, write_text
from .spec import Sweep
from .store import PARAM_PREFIX
from .tolerancefiles import FILES as TOLERANCE_FILES
from .tolerancefiles import is_tolerance, write_tolerance
from .tolerancefiles import summary_lines as tolerance_lines

THRESHOLDS = (1.0, 5.0)
"""Error levels (percent) of the "within" regions."""
MAX_LISTED = 30
"""Failures and invalid points listed by name in the summary (the rest are counted)."""

RowValue = Callable[[dict], "float | None"]


def row_metric(row: dict, metric: str) -> float | None:
    """The summary metric of one row (percent), None when it has no errors."""
    if metric == "worst":
        vals = (row["end_disp_vec"], row["end_rot"])
        return None if None in vals else max(vals)
    return row[metric]


def stress_metric(row: dict) -> float | None:
    """|peak stress error| of one row (percent), None when it has none."""
    e = row["peak_stress_error"]
    return None if e is None else abs(e)


def point_values(
    sweep: Sweep, rows: list[dict], value: RowValue
) -> dict[str, dict[int, float | None]]:
    """{model: {point: largest ``value`` over the load cases, or None if a case has none}}
    of the compared models."""
    out: dict[str, dict[int, float | None]] = {s.id: {} for s in sweep.models}
    for r in rows:
        if r["model"] not in out:
            continue
        v = value(r)
        per = out[r["model"]]
        if r["point"] in per and per[r["point"]] is None:
            continue
        per[r["point"]] = None if v is None else max(v, per.get(r["point"]) or 0.0)
    return out


def point_metrics(sweep: Sweep, rows: list[dict]) -> dict[str, dict[int, float | None]]:
    """{model: {point: worst summary metric over the load cases, or None}}."""
    return point_values(sweep, rows, lambda r: row_metric(r, sweep.metric))


def _fmt(x: float | None) -> str:
    return "–" if x is None else f"{x:.3g}"


def _params(sweep: Sweep, index: int) -> str:
    p = sweep.points.params(index)
    return ", ".join(f"{k} = {v:.4g}" for k, v in p.items()) or "base scene"


def _ranges(sweep: Sweep, pts: list[int]) -> str:
    """The span of each parameter (of the first one, for zipped axes) over the points ``pts``."""
    if not pts or not sweep.axes:
        return ""
    spans = []
    for a in sweep.axes[:1] if sweep.combine == "zip" else sweep.axes:
        v = [sweep.points.params(i)[a.path] for i in pts]
        spans.append(f"{a.path} {min(v):.4g}..{max(v):.4g}")
    return "; ".join(spans)


def _agreement(sweep: Sweep, metrics: dict[str, dict[int, float | None]]) -> list[str]:
    """Table rows: per model, the points with a value, its median and largest, and the points
    within each threshold with the span of each parameter over them."""
    n_valid = len(sweep.valid_points)
    lines = []
    for model, per in metrics.items():
        vals = [v for v in per.values() if v is not None]
        cells = []
        for t in THRESHOLDS:
            inside = [i for i, v in per.items() if v is not None and v < t]
            cells.append(f"{len(inside)}/{n_valid} {_ranges(sweep, inside)}".strip())
        lines.append(
            f"| {model} | {len(vals)}/{n_valid} | "
            f"{_fmt(float(np.median(vals)) if vals else None)} | "
            f"{_fmt(max(vals) if vals else None)} | {cells[0]} | {cells[1]} |"
        )
    return lines


def _per_point(sweep: Sweep, metrics: dict, first: tuple[str, dict] | None = None) -> list[str]:
    """Per-point table of ``metrics`` (``first``: an extra leading column, name and values)."""
    extra = [first[0]] if first else []
    lines = [
        "| point | parameters | " + " | ".join(extra + list(metrics)) + " |",
        "|---:|---|" + "---:|" * (len(extra) + len(metrics)),
    ]
    for p in sweep.points.records():
        cells = ([_fmt(first[1].get(p.index))] if first else []) + [
            _fmt(metrics[m].get(p.index)) for m in metrics
        ]
        lines.append(f"| {p.index} | {_params(sweep, p.index)} | " + " | ".join(cells) + " |")
    return lines


def _reference_peaks(sweep: Sweep, rows: list[dict]) -> dict[int, float]:
    """{point: the reference's largest peak stress at full load over the load cases (MPa)}."""
    out: dict[int, float] = {}
    for r in rows:
        if (
            r["model"] == sweep.reference.id
            and r["status"] == "ok"
            and r["peak_stress"] is not None
        ):
            out[r["point"]] = max(r["peak_stress"], out.get(r["point"], 0.0))
    return out


def _stress_section(sweep: Sweep, rows: list[dict]) -> list[str]:
    """Markdown: the peak stresses and their errors against the reference's."""
    ref = sweep.reference.id
    metrics = point_values(sweep, rows, stress_metric)
    peaks = _reference_peaks(sweep, rows)
    lines = [
        "",
        f"## Peak stress against `{ref}`",
        "",
        "Largest outer-fibre normal stress |N|/A + |M| h/(2I) over the flexures at full "
        "load, from each model's own section forces (MPa). Metric: |model - reference| / "
        "reference (percent), the largest over the load cases at each point.",
    ]
    if peaks:
        lines.append(
            f"The reference's peak stress spans {min(peaks.values()):.4g} .. "
            f"{max(peaks.values()):.4g} MPa over the points."
        )
    lines += [
        "",
        "| model | points with errors | median % | max % | within 1 % | within 5 % |",
        "|---|---:|---:|---:|---|---|",
    ] + _agreement(sweep, metrics)
    if len(sweep.points) <= MAX_LISTED:
        lines += [
            "",
            "Per point: the reference's peak stress (MPa) and each model's error (%).",
            "",
        ] + _per_point(sweep, metrics, (f"{ref} MPa", peaks))
    return lines


def _limit_section(sweep: Sweep, rows: list[dict]) -> list[str]:
    """Markdown: the limit loads found (runs that stopped at a limit point below full load)."""
    lines = [
        "",
        f"## Limit loads against `{sweep.reference.id}`",
        "",
        "Runs that stopped below full load were traced by arc length: the first limit "
        "point's load, and its error against the reference's on the same point and case "
        "(percent) where the reference has one too.",
        "",
    ]
    found = [r for r in rows if r["limit_load"] is not None]
    if not found:
        return (
            lines
            + ["No run stopped at a limit point below full load."]
            + _bifurcations(sweep, rows)
        )
    lines += [
        "| model | limit points | with the reference's | median |error| % | max |error| % |",
        "|---|---:|---:|---:|---:|",
    ]
    for model in (sweep.reference.id, *(s.id for s in sweep.models)):
        mine = [r for r in found if r["model"] == model]
        errs = [abs(r["limit_load_error"]) for r in mine if r["limit_load_error"] is not None]
        if mine:
            paired = "–" if model == sweep.reference.id else str(len(errs))
            lines.append(
                f"| {model} | {len(mine)} | {paired} | "
                f"{_fmt(float(np.median(errs)) if errs else None)} | "
                f"{_fmt(max(errs) if errs else None)} |"
            )
    return lines + _bifurcations(sweep, rows)


def _bifurcations(sweep: Sweep, rows: list[dict]) -> list[str]:
    """Markdown: per model and load case, the points whose path has a bifurcation point,
    and its loads."""
    found = [r for r in rows if r["bifurcation_load"] is not None]
    lines = [""]
    if not found:
        return lines + ["No run's path has a bifurcation point."]
    lines += [
        "Bifurcation points (the tangent turns indefinite while the load still rises; "
        "load control stops there): the points whose path has one, and the first one's "
        "load (smallest and largest over those points).",
        "",
        "| model | load case | points with a bifurcation | smallest load | largest load |",
        "|---|---|---:|---:|---:|",
    ]
    for model in (sweep.reference.id, *(s.id for s in sweep.models)):
        for case in sweep.load_cases:
            mine = [r for r in found if r["model"] == model and r["load_case"] == case]
            if mine:
                loads = [r["bifurcation_load"] for r in mine]
                unit = mine[0]["load_unit"] or ""
                lines.append(
                    f"| {model} | {case} | {len({r['point'] for r in mine})} | "
                    f"{min(loads):.5g} {unit} | {max(loads):.5g} {unit} |"
                )
    return lines


def format_summary(sweep: Sweep, rows: list[dict]) -> str:
    """The machine-independent Markdown summary of the sweep's rows."""
    metrics = point_metrics(sweep, rows)
    axes = "\n".join(
        f"- `{a.path}`: {len(a.values)} {'random ' if a.random else ''}values, "
        f"{min(a.values):.4g} .. {max(a.values):.4g}"
        for a in sweep.axes
    )
    n_valid = len(sweep.valid_points)
    intro = [sweep.description, ""] if sweep.description else []
    lines = [
        f"# Sweep `{sweep.name}`",
        "",
        *intro,
        f"Base scene `{sweep.base}`; reference `{sweep.reference.id}`; load cases "
        f"{', '.join(sweep.load_cases)}; axes combined as a {sweep.combine}"
        + (
            f"; loads scaled to a linear end rotation of {sweep.linear_rotation:g} rad"
            if sweep.linear_rotation
            else ""
        )
        + ".",
        "",
        axes or "- no axis: the base scene",
        "",
        f"{len(sweep.points)} points, {n_valid} valid; {len(rows)} result rows.",
        "",
        f"## Agreement with `{sweep.reference.id}`",
        "",
        f"Metric: `{sweep.metric}` (percent), the largest over the load cases at each "
        "point; *within x %* counts the points where it is below x, with the span of "
        "each parameter over those points.",
        "",
        "| model | points with errors | median % | max % | within 1 % | within 5 % |",
        "|---|---:|---:|---:|---|---|",
    ]
    lines += _agreement(sweep, metrics)
    if len(sweep.points) <= MAX_LISTED:
        lines += ["", "## Per point", ""] + _per_point(sweep, metrics)
    if "peak_stress" in sweep.outputs:
        lines += _stress_section(sweep, rows)
    if "limit_load" in sweep.outputs:
        lines += _limit_section(sweep, rows)
    lines += tolerance_lines(sweep, rows)
    failed = [r for r in rows if r["status"] != "ok"]
    lines += ["", "## Failures", ""]
    if not failed:
        lines.append("None: every run reached full load.")
    for r in failed[:MAX_LISTED]:
        reached = (
            f" (load reached {r['load_reached']:.3g}"
            + (
                f"; peak stress {r['peak_stress']:.4g} MPa at load {r['peak_stress_load']:.3g}"
                if r["peak_stress"] is not None
                else ""
            )
            + ")"
            if r["load_reached"] is not None
            else ""
        )
        if r["limit_load"] is not None:
            reached += f" (limit point at {r['limit_load']:.5g} {r['load_unit']})"
        if r.get("bifurcation_load") is not None:
            reached += f" (bifurcation at {r['bifurcation_load']:.5g} {r['load_unit']})"
        lines.append(
            f"- point {r['point']} ({_params(sweep, r['point'])}), {r['model']}, "
            f"{r['load_case']}: {r['status']}{reached}: {r['reason']}"
        )
    if len(failed) > MAX_LISTED:
        lines.append(f"- ... and {len(failed) - MAX_LISTED} more (see the Parquet dataset)")
    flagged = [r for r in rows if r["valid"] is False]
    lines += ["", "## Validity", ""]
    if not flagged:
        lines.append("The validity monitor flagged no converged run.")
    for r in flagged[:MAX_LISTED]:
        lines.append(f"- point {r['point']}, {r['model']}, {r['load_case']}: {r['validity']}")
    if len(flagged) > MAX_LISTED:
        lines.append(f"- ... and {len(flagged) - MAX_LISTED} more (see the Parquet dataset)")
    return "\n".join(lines) + "\n"


def format_timings(sweep: Sweep, rows: list[dict], wall: float | None) -> str:
    """Markdown run-time distribution of each model (s per run of one load case)."""
    lines = [
        f"# Run times of sweep `{sweep.name}` (s per load path)",
        "",
        "Machine-dependent; from the stored rows (a resumed sweep keeps earlier times).",
    ]
    if wall is not None:
        lines.append(f"Wall time of the last `flexval sweep` call: {wall:.1f} s.")
    lines += [
        "",
        "| model | runs | median | 10 % | 90 % | max | total |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for model in (sweep.reference.id, *(s.id for s in sweep.models)):
        t = np.array(
            [r["seconds"] for r in rows if r["model"] == model and r["seconds"] is not None]
        )
        if t.size:
            q = np.percentile(t, [50, 10, 90])
            lines.append(
                f"| {model} | {t.size} | {q[0]:.3g} | {q[1]:.3g} | {q[2]:.3g} | "
                f"{t.max():.3g} | {t.sum():.3g} |"
            )
    return "\n".join(lines) + "\n"


def _save(fig, path: Path) -> None:
    save_figure(fig, path, dpi=90)


def _threshold_lines(ax, horizontal: bool = True) -> None:
    for t, style in zip(THRESHOLDS, (":", "--")):
        (ax.axhline if horizontal else ax.axvline)(t, color="grey", ls=style, lw=0.8)


def _error_axes(ax, xlabel: str, ylabel: str) -> None:
    """An error axis (percent, log scale) with the 1 % / 5 % threshold lines."""
    _threshold_lines(ax)
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)


def _finish(fig, axs, path: Path) -> None:
    """Legend on the first panel, layout, atomic save, figure closed."""
    import matplotlib.pyplot as plt

    if axs[0][0].get_legend_handles_labels()[0]:
        axs[0][0].legend(fontsize=7)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def _lines(sweep: Sweep, rows: list[dict], path: Path, value: RowValue, label: str) -> None:
    """One panel per load case: ``value`` of each row (percent) against the first axis."""
    import matplotlib.pyplot as plt

    axis = sweep.axes[0] if sweep.axes else None
    cases = sweep.load_cases
    fig, axs = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 3.4), squeeze=False)
    column = PARAM_PREFIX + axis.path if axis else None  # each row carries its point's value
    for ax, case in zip(axs[0], cases):
        for spec in sweep.models:
            pts = sorted(
                (r[column] if column else 0.0, y)
                for r in rows
                if r["model"] == spec.id and r["load_case"] == case and (y := value(r)) is not None
            )
            if pts:
                x, y = zip(*pts)
                ax.plot(
                    x,
                    np.maximum(y, 1e-6),
                    "o" if axis and axis.random else "o-",
                    ms=3,
                    label=spec.id,
                )
        ax.set_title(f"load case {case}")
        _error_axes(ax, axis.path if axis else "point", f"{label} vs {sweep.reference.id} (%)")
    _finish(fig, axs, path)


def _heatmaps(sweep: Sweep, metrics: dict, path: Path, label: str) -> None:
    """One heat map per model of its point metrics (percent) over the two grid axes."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    ax0, ax1 = sweep.axes
    x, y = np.array(ax0.values), np.array(ax1.values)
    n = len(metrics)
    cols = min(n, 3)
    rws = math.ceil(n / cols)
    fig, axs = plt.subplots(rws, cols, figsize=(4.0 * cols, 3.4 * rws), squeeze=False)
    grids = {}
    for model, per in metrics.items():
        z = np.full((len(y), len(x)), np.nan)
        for p in sweep.points.records():
            v = per.get(p.index)
            if v is not None:
                params = sweep.points.params(p.index)
                i = int(np.argmin(np.abs(y - params[ax1.path])))
                j = int(np.argmin(np.abs(x - params[ax0.path])))
                z[i, j] = max(v, 1e-6)
        grids[model] = z
    finite = np.concatenate([z[np.isfinite(z)] for z in grids.values()] + [np.array([1.0])])
    norm = LogNorm(vmin=max(finite.min(), 1e-3), vmax=max(finite.max(), 10.0))
    for k, (model, z) in enumerate(grids.items()):
        ax = axs[k // cols][k % cols]
        mesh = ax.pcolormesh(
            x, y, np.ma.masked_invalid(z), norm=norm, shading="nearest", cmap="viridis"
        )
        if np.isfinite(z).sum() >= 4 and len(x) > 1 and len(y) > 1:
            ax.contour(
                x,
                y,
                np.ma.masked_invalid(z),
                levels=list(THRESHOLDS),
                colors="w",
                linestyles=[":", "--"],
                linewidths=1.0,
            )
        ax.set_title(model)
        ax.set_xlabel(ax0.path)
        ax.set_ylabel(ax1.path)
        fig.colorbar(mesh, ax=ax, label=f"{label} % (contours 1, 5)")
    for k in range(n, rws * cols):
        axs[k // cols][k % cols].axis("off")
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def _scatter(sweep: Sweep, metrics: dict, path: Path, label: str) -> None:
    """The point metrics (percent) against each parameter."""
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, len(sweep.axes), figsize=(4.2 * len(sweep.axes), 3.4), squeeze=False)
    for ax, a in zip(axs[0], sweep.axes):
        for model, per in metrics.items():
            pts = [(sweep.points.params(i)[a.path], v) for i, v in per.items() if v is not None]
            if pts:
                px, py = zip(*pts)
                ax.plot(px, np.maximum(py, 1e-6), ".", ms=3, label=model)
        _error_axes(ax, a.path, f"{label} (%)")
    _finish(fig, axs, path)


def _error_figure(sweep: Sweep, rows: list[dict], path: Path, value: RowValue, label: str) -> Path:
    """Lines, heat maps or scatter plots (see the module docstring) of ``value`` (percent)."""
    if len(sweep.axes) == 2 and sweep.combine == "grid" and not any(a.random for a in sweep.axes):
        _heatmaps(sweep, point_values(sweep, rows, value), path, label)
    elif len(sweep.axes) <= 1 or sweep.combine == "zip":
        _lines(sweep, rows, path, value, label)
    else:
        _scatter(sweep, point_values(sweep, rows, value), path, label)
    return path


def _limits(sweep: Sweep, rows: list[dict], path: Path) -> Path:
    """The limit loads found (N or N mm), per load case, against the first parameter."""
    import matplotlib.pyplot as plt

    axis = sweep.axes[0] if sweep.axes else None
    cases = sweep.load_cases
    fig, axs = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 3.4), squeeze=False)
    for ax, case in zip(axs[0], cases):
        unit = ""
        for model in (sweep.reference.id, *(s.id for s in sweep.models)):
            found = [
                r
                for r in rows
                if r["model"] == model and r["load_case"] == case and r["limit_load"] is not None
            ]
            if found:
                unit = found[0]["load_unit"]
                pts = sorted(
                    (
                        sweep.points.params(r["point"]).get(axis.path, 0.0) if axis else 0.0,
                        r["limit_load"],
                    )
                    for r in found
                )
                ax.plot(*zip(*pts), "o", ms=3, label=model)
        ax.set_title(f"load case {case}")
        ax.set_xlabel(axis.path if axis else "point")
        ax.set_ylabel(f"first limit load ({unit})" if unit else "first limit load")
        ax.grid(alpha=0.3)
    _finish(fig, axs, path)
    return path


def _runtimes(sweep: Sweep, rows: list[dict], path: Path) -> None:
    import matplotlib.pyplot as plt

    models = [sweep.reference.id, *(s.id for s in sweep.models)]
    data = [
        [r["seconds"] for r in rows if r["model"] == m and r["seconds"] is not None] for m in models
    ]
    keep = [(m, d) for m, d in zip(models, data) if d]
    fig, ax = plt.subplots(figsize=(6, 0.5 * len(keep) + 1.5))
    if keep:
        ax.boxplot([d for _, d in keep], orientation="horizontal", tick_labels=[m for m, _ in keep])
        ax.set_xscale("log")
    ax.set_xlabel("seconds per load path")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


#: figures a sweep writes only sometimes (see :func:`write_outputs`)
OPTIONAL_FIGURES = ("stress.png", "limits.png") + TOLERANCE_FILES


def write_outputs(
    sweep: Sweep, rows: list[dict], out_dir: str | Path, wall: float | None = None
) -> list[Path]:
    """Write summary.md, timings.md, errors.png, runtime.png, stress.png (with the
    ``peak_stress`` output), limits.png (when a limit load was found) and, for a tolerance
    study, tolerance.json and its histograms (:mod:`.tolerancefiles`) into ``out_dir``.

    An optional figure (:data:`OPTIONAL_FIGURES`) that this call does not write is
    removed if an earlier run left it there, so every figure in the folder is this
    summary's; no other file is touched."""
    import matplotlib

    matplotlib.use("Agg")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in (
        ("summary.md", format_summary(sweep, rows)),
        ("timings.md", format_timings(sweep, rows, wall)),
    ):
        written.append(write_text(out / name, text))
    written.append(
        _error_figure(
            sweep,
            rows,
            out / "errors.png",
            lambda r: row_metric(r, sweep.metric),
            f"{sweep.metric} error",
        )
    )
    _runtimes(sweep, rows, out / "runtime.png")
    written.append(out / "runtime.png")
    if "peak_stress" in sweep.outputs:
        written.append(
            _error_figure(sweep, rows, out / "stress.png", stress_metric, "|peak stress error|")
        )
    if any(r["limit_load"] is not None for r in rows):
        written.append(_limits(sweep, rows, out / "limits.png"))
    if is_tolerance(sweep):
        written += write_tolerance(sweep, rows, out)
    for name in OPTIONAL_FIGURES:
        stale = out / name
        if stale not in written and stale.is_file():
            stale.unlink()
    return written
