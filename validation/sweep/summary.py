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
from .columns import Columns, Rows
from .spec import Sweep
from .store import PARAM_PREFIX
from .tolerancefiles import FILES as TOLERANCE_FILES
from .tolerancefiles import is_tolerance, write_tolerance
from .tolerancefiles import summary_lines as tolerance_lines

THRESHOLDS = (1.0, 5.0)
"""Error levels (percent) of the "within" regions."""
MAX_LISTED = 30
"""Failures and invalid points listed by name in the summary (the rest are counted)."""

RowValue = Callable[[Columns], np.ndarray]
"""A value of every row (percent), NaN where a row has none."""


def row_metric(rows: Columns, metric: str) -> np.ndarray:
    """The summary metric of every row (percent), NaN where a row has no errors."""
    if metric == "worst":
        return np.maximum(rows.floats("end_disp_vec"), rows.floats("end_rot"))  # NaN: either
    return rows.floats(metric)


def stress_metric(rows: Columns) -> np.ndarray:
    """|peak stress error| of every row (percent), NaN where a row has none."""
    return np.abs(rows.floats("peak_stress_error"))


def point_values(sweep: Sweep, rows: Rows, value: RowValue) -> dict[str, dict[int, float | None]]:
    """{model: {point: largest ``value`` over the load cases (and 0), or None if a case has
    none}} of the compared models, each model's points in the order of their first row."""
    rows = Columns.of(rows)
    values, points = value(rows), rows.column("point")
    out: dict[str, dict[int, float | None]] = {}
    for spec in sweep.models:
        mine = np.flatnonzero(rows.of_model(spec.id))
        at, first, where = np.unique(
            points[mine].astype(np.int64), return_index=True, return_inverse=True
        )
        largest = np.zeros(at.size)
        np.fmax.at(largest, where, values[mine])  # NaN: a case without a value, below
        missing = np.zeros(at.size, dtype=bool)
        np.logical_or.at(missing, where, np.isnan(values[mine]))
        order = np.argsort(first, kind="stable")
        out[spec.id] = {
            int(at[k]): None if missing[k] else float(largest[k]) for k in order.tolist()
        }
    return out


def point_metrics(sweep: Sweep, rows: Rows) -> dict[str, dict[int, float | None]]:
    """{model: {point: worst summary metric over the load cases, or None}}."""
    return point_values(sweep, rows, lambda table: row_metric(table, sweep.metric))


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


def _reference_peaks(sweep: Sweep, rows: Columns) -> dict[int, float]:
    """{point: the reference's largest peak stress at full load over the load cases (MPa)}."""
    out: dict[int, float] = {}
    peaks, points = rows.column("peak_stress"), rows.column("point")
    chosen = rows.of_model(sweep.reference.id) & rows.ok() & rows.present("peak_stress")
    for k in np.flatnonzero(chosen).tolist():
        out[points[k]] = max(peaks[k], out.get(points[k], 0.0))
    return out


def _stress_section(sweep: Sweep, rows: Columns) -> list[str]:
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


def _limit_section(sweep: Sweep, rows: Columns) -> list[str]:
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
    found = rows.take(np.flatnonzero(rows.present("limit_load")))
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


def _bifurcations(sweep: Sweep, rows: Columns) -> list[str]:
    """Markdown: per model and load case, the points whose path has a bifurcation point,
    and its loads."""
    found = rows.take(np.flatnonzero(rows.present("bifurcation_load")))
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


def format_summary(sweep: Sweep, rows: Rows) -> str:
    """The machine-independent Markdown summary of the sweep's rows."""
    rows = Columns.of(rows)
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
    failing = np.flatnonzero(~rows.ok())
    failed = rows.take(failing[:MAX_LISTED])
    lines += ["", "## Failures", ""]
    if not failed:
        lines.append("None: every run reached full load.")
    for r in failed:
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
    if failing.size > MAX_LISTED:
        lines.append(f"- ... and {failing.size - MAX_LISTED} more (see the Parquet dataset)")
    flagging = np.flatnonzero(np.equal(rows.column("valid"), False))
    lines += ["", "## Validity", ""]
    if not flagging.size:
        lines.append("The validity monitor flagged no converged run.")
    for r in rows.take(flagging[:MAX_LISTED]):
        lines.append(f"- point {r['point']}, {r['model']}, {r['load_case']}: {r['validity']}")
    if flagging.size > MAX_LISTED:
        lines.append(f"- ... and {flagging.size - MAX_LISTED} more (see the Parquet dataset)")
    return "\n".join(lines) + "\n"


def _seconds(rows: Columns, model: str) -> np.ndarray:
    """The run times (s) of ``model``'s rows that have one, in row order."""
    seconds = rows.floats("seconds")
    return seconds[rows.of_model(model) & rows.present("seconds")]


def format_timings(sweep: Sweep, rows: Rows, wall: float | None) -> str:
    """Markdown run-time distribution of each model (s per run of one load case)."""
    rows = Columns.of(rows)
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
        t = _seconds(rows, model)
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


def _lines(sweep: Sweep, rows: Columns, path: Path, value: RowValue, label: str) -> None:
    """One panel per load case: ``value`` of each row (percent) against the first axis."""
    import matplotlib.pyplot as plt

    axis = sweep.axes[0] if sweep.axes else None
    cases = sweep.load_cases
    fig, axs = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 3.4), squeeze=False)
    # each row carries its point's value
    along = rows.floats(PARAM_PREFIX + axis.path) if axis else np.zeros(len(rows))
    values = value(rows)
    for ax, case in zip(axs[0], cases):
        for spec in sweep.models:
            mine = rows.rows_of(spec.id, case)
            mine = mine[~np.isnan(values[mine])]
            if mine.size:
                order = np.lexsort((values[mine], along[mine]))  # by x, then y
                x, y = along[mine][order], values[mine][order]
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


def _error_figure(sweep: Sweep, rows: Columns, path: Path, value: RowValue, label: str) -> Path:
    """Lines, heat maps or scatter plots (see the module docstring) of ``value`` (percent)."""
    if len(sweep.axes) == 2 and sweep.combine == "grid" and not any(a.random for a in sweep.axes):
        _heatmaps(sweep, point_values(sweep, rows, value), path, label)
    elif len(sweep.axes) <= 1 or sweep.combine == "zip":
        _lines(sweep, rows, path, value, label)
    else:
        _scatter(sweep, point_values(sweep, rows, value), path, label)
    return path


def _limits(sweep: Sweep, rows: Columns, path: Path) -> Path:
    """The limit loads found (N or N mm), per load case, against the first parameter."""
    import matplotlib.pyplot as plt

    axis = sweep.axes[0] if sweep.axes else None
    cases = sweep.load_cases
    fig, axs = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 3.4), squeeze=False)
    limited = rows.present("limit_load")
    for ax, case in zip(axs[0], cases):
        unit = ""
        for model in (sweep.reference.id, *(s.id for s in sweep.models)):
            mine = rows.rows_of(model, case)
            found = rows.take(mine[limited[mine]])
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


def _runtimes(sweep: Sweep, rows: Columns, path: Path) -> None:
    import matplotlib.pyplot as plt

    models = [sweep.reference.id, *(s.id for s in sweep.models)]
    keep = [(m, d) for m in models if (d := _seconds(rows, m)).size]
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
    sweep: Sweep, rows: Rows, out_dir: str | Path, wall: float | None = None
) -> list[Path]:
    """Write summary.md, timings.md, errors.png, runtime.png, stress.png (with the
    ``peak_stress`` output), limits.png (when a limit load was found) and, for a tolerance
    study, tolerance.json and its histograms (:mod:`.tolerancefiles`) into ``out_dir``.

    An optional figure (:data:`OPTIONAL_FIGURES`) that this call does not write is
    removed if an earlier run left it there, so every figure in the folder is this
    summary's; no other file is touched."""
    from ..outputs import use_file_backend

    use_file_backend()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = Columns.of(rows)  # every table and figure reads the same columns
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
            lambda table: row_metric(table, sweep.metric),
            f"{sweep.metric} error",
        )
    )
    _runtimes(sweep, rows, out / "runtime.png")
    written.append(out / "runtime.png")
    if "peak_stress" in sweep.outputs:
        written.append(
            _error_figure(sweep, rows, out / "stress.png", stress_metric, "|peak stress error|")
        )
    if rows.present("limit_load").any():
        written.append(_limits(sweep, rows, out / "limits.png"))
    if is_tolerance(sweep):
        written += write_tolerance(sweep, rows, out)
    for name in OPTIONAL_FIGURES:
        stale = out / name
        if stale not in written and stale.is_file():
            stale.unlink()
    return written
