"""Summary of a sweep's results: Markdown, error figures and run-time distributions.

The summary metric of a (point, model) pair is the largest over the sweep's
load cases of the sweep's ``metric`` (``worst`` = max(end_disp_vec,
end_rot), percent); a pair with a failed case has none. ``summary.md`` holds
only results that do not depend on the machine (errors, regions, failures);
run times go to ``timings.md`` and ``runtime.png``.

Figures: one swept axis (or zipped axes, against the first) -> error lines;
two axes on a grid -> one heat map per model with the 1 % and 5 % contours;
otherwise the error against each parameter as scatter plots.

Units: errors in percent, times in s, parameters in their field's unit.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..outputs import save_figure, write_text
from .spec import Sweep

THRESHOLDS = (1.0, 5.0)
"""Error levels (percent) of the "within" regions."""
MAX_LISTED = 30
"""Failures and invalid points listed by name in the summary (the rest are counted)."""


def row_metric(row: dict, metric: str) -> float | None:
    """The summary metric of one row (percent), None when it has no errors."""
    if metric == "worst":
        vals = (row["end_disp_vec"], row["end_rot"])
        return None if None in vals else max(vals)
    return row[metric]


def point_metrics(sweep: Sweep, rows: list[dict]) -> dict[str, dict[int, float | None]]:
    """{model: {point: worst metric over the load cases, or None}} of the compared models."""
    out: dict[str, dict[int, float | None]] = {s.id: {} for s in sweep.models}
    for r in rows:
        if r["model"] not in out:
            continue
        v = row_metric(r, sweep.metric)
        per = out[r["model"]]
        if r["point"] in per and per[r["point"]] is None:
            continue
        per[r["point"]] = None if v is None else max(v, per.get(r["point"]) or 0.0)
    return out


def _fmt(x: float | None) -> str:
    return "–" if x is None else f"{x:.3g}"


def _point(sweep: Sweep, index: int):
    return next(p for p in sweep.points if p.index == index)


def _params(sweep: Sweep, index: int) -> str:
    p = _point(sweep, index).params
    return ", ".join(f"{k} = {v:.4g}" for k, v in p.items()) or "base scene"


def _ranges(sweep: Sweep, pts: list[int]) -> str:
    """The span of each parameter (of the first one, for zipped axes) over the points ``pts``."""
    if not pts or not sweep.axes:
        return ""
    spans = []
    for a in (sweep.axes[:1] if sweep.combine == "zip" else sweep.axes):
        v = [_point(sweep, i).params[a.path] for i in pts]
        spans.append(f"{a.path} {min(v):.4g}..{max(v):.4g}")
    return "; ".join(spans)


def format_summary(sweep: Sweep, rows: list[dict]) -> str:
    """The machine-independent Markdown summary of the sweep's rows."""
    metrics = point_metrics(sweep, rows)
    axes = "\n".join(f"- `{a.path}`: {len(a.values)} {'random ' if a.random else ''}values, "
                     f"{min(a.values):.4g} .. {max(a.values):.4g}" for a in sweep.axes)
    n_valid = len(sweep.valid_points)
    lines = [f"# Sweep `{sweep.name}`", "", sweep.description, "",
             f"Base scene `{sweep.base}`; reference `{sweep.reference.id}`; load cases "
             f"{', '.join(sweep.load_cases)}; axes combined as a {sweep.combine}"
             + (f"; loads scaled to a linear end rotation of {sweep.linear_rotation:g} rad"
                if sweep.linear_rotation else "") + ".", "", axes or "- no axis: the base scene",
             "", f"{len(sweep.points)} points, {n_valid} valid; {len(rows)} result rows.", "",
             f"## Agreement with `{sweep.reference.id}`", "",
             f"Metric: `{sweep.metric}` (percent), the largest over the load cases at each "
             "point; *within x %* counts the points where it is below x, with the span of "
             "each parameter over those points.", "",
             "| model | points with errors | median % | max % | within 1 % | within 5 % |",
             "|---|---:|---:|---:|---|---|"]
    for model, per in metrics.items():
        vals = [v for v in per.values() if v is not None]
        cells = []
        for t in THRESHOLDS:
            inside = [i for i, v in per.items() if v is not None and v < t]
            cells.append(f"{len(inside)}/{n_valid} {_ranges(sweep, inside)}".strip())
        lines.append(f"| {model} | {len(vals)}/{n_valid} | "
                     f"{_fmt(float(np.median(vals)) if vals else None)} | "
                     f"{_fmt(max(vals) if vals else None)} | {cells[0]} | {cells[1]} |")
    if len(sweep.points) <= MAX_LISTED:
        lines += ["", "## Per point", "",
                  "| point | parameters | " + " | ".join(metrics) + " |",
                  "|---:|---|" + "---:|" * len(metrics)]
        for p in sweep.points:
            lines.append(f"| {p.index} | {_params(sweep, p.index)} | "
                         + " | ".join(_fmt(metrics[m].get(p.index)) for m in metrics) + " |")
    failed = [r for r in rows if r["status"] != "ok"]
    lines += ["", "## Failures", ""]
    if not failed:
        lines.append("None: every run reached full load.")
    for r in failed[:MAX_LISTED]:
        reached = (f" (load reached {r['load_reached']:.3g})"
                   if r["load_reached"] is not None else "")
        lines.append(f"- point {r['point']} ({_params(sweep, r['point'])}), {r['model']}, "
                     f"{r['load_case']}: {r['status']}{reached}: {r['reason']}")
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
    lines = [f"# Run times of sweep `{sweep.name}` (s per load path)", "",
             "Machine-dependent; from the stored rows (a resumed sweep keeps earlier times)."]
    if wall is not None:
        lines.append(f"Wall time of the last `flexval sweep` call: {wall:.1f} s.")
    lines += ["", "| model | runs | median | 10 % | 90 % | max | total |",
              "|---|---:|---:|---:|---:|---:|---:|"]
    for model in (sweep.reference.id, *(s.id for s in sweep.models)):
        t = np.array([r["seconds"] for r in rows if r["model"] == model
                      and r["seconds"] is not None])
        if t.size:
            q = np.percentile(t, [50, 10, 90])
            lines.append(f"| {model} | {t.size} | {q[0]:.3g} | {q[1]:.3g} | {q[2]:.3g} | "
                         f"{t.max():.3g} | {t.sum():.3g} |")
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

    axs[0][0].legend(fontsize=7)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def _lines(sweep: Sweep, rows: list[dict], path: Path) -> None:
    import matplotlib.pyplot as plt

    axis = sweep.axes[0] if sweep.axes else None
    cases = sweep.load_cases
    fig, axs = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 3.4), squeeze=False)
    for ax, case in zip(axs[0], cases):
        for spec in sweep.models:
            pts = sorted((_point(sweep, r["point"]).params.get(axis.path, 0.0) if axis else 0.0,
                          row_metric(r, sweep.metric)) for r in rows
                         if r["model"] == spec.id and r["load_case"] == case
                         and row_metric(r, sweep.metric) is not None)
            if pts:
                x, y = zip(*pts)
                ax.plot(x, np.maximum(y, 1e-6), "o" if axis and axis.random else "o-",
                        ms=3, label=spec.id)
        ax.set_title(f"load case {case}")
        _error_axes(ax, axis.path if axis else "point",
                    f"{sweep.metric} error vs {sweep.reference.id} (%)")
    _finish(fig, axs, path)


def _heatmaps(sweep: Sweep, metrics: dict, path: Path) -> None:
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
        for p in sweep.points:
            v = per.get(p.index)
            if v is not None:
                i = int(np.argmin(np.abs(y - p.params[ax1.path])))
                j = int(np.argmin(np.abs(x - p.params[ax0.path])))
                z[i, j] = max(v, 1e-6)
        grids[model] = z
    finite = np.concatenate([z[np.isfinite(z)] for z in grids.values()] + [np.array([1.0])])
    norm = LogNorm(vmin=max(finite.min(), 1e-3), vmax=max(finite.max(), 10.0))
    for k, (model, z) in enumerate(grids.items()):
        ax = axs[k // cols][k % cols]
        mesh = ax.pcolormesh(x, y, np.ma.masked_invalid(z), norm=norm, shading="nearest",
                             cmap="viridis")
        if np.isfinite(z).sum() >= 4 and len(x) > 1 and len(y) > 1:
            ax.contour(x, y, np.ma.masked_invalid(z), levels=list(THRESHOLDS), colors="w",
                       linestyles=[":", "--"], linewidths=1.0)
        ax.set_title(model)
        ax.set_xlabel(ax0.path)
        ax.set_ylabel(ax1.path)
        fig.colorbar(mesh, ax=ax, label=f"{sweep.metric} % (contours 1, 5)")
    for k in range(n, rws * cols):
        axs[k // cols][k % cols].axis("off")
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def _scatter(sweep: Sweep, metrics: dict, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, len(sweep.axes), figsize=(4.2 * len(sweep.axes), 3.4),
                            squeeze=False)
    for ax, a in zip(axs[0], sweep.axes):
        for model, per in metrics.items():
            pts = [(_point(sweep, i).params[a.path], v) for i, v in per.items() if v is not None]
            if pts:
                px, py = zip(*pts)
                ax.plot(px, np.maximum(py, 1e-6), ".", ms=3, label=model)
        _error_axes(ax, a.path, f"{sweep.metric} error (%)")
    _finish(fig, axs, path)


def _runtimes(sweep: Sweep, rows: list[dict], path: Path) -> None:
    import matplotlib.pyplot as plt

    models = [sweep.reference.id, *(s.id for s in sweep.models)]
    data = [[r["seconds"] for r in rows if r["model"] == m and r["seconds"] is not None]
            for m in models]
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


def write_outputs(sweep: Sweep, rows: list[dict], out_dir: str | Path,
                  wall: float | None = None) -> list[Path]:
    """Write summary.md, timings.md, errors.png and runtime.png into ``out_dir``."""
    import matplotlib

    matplotlib.use("Agg")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in (("summary.md", format_summary(sweep, rows)),
                       ("timings.md", format_timings(sweep, rows, wall))):
        written.append(write_text(out / name, text))
    metrics = point_metrics(sweep, rows)
    errors_png = out / "errors.png"
    if len(sweep.axes) == 2 and sweep.combine == "grid" and not any(a.random for a in sweep.axes):
        _heatmaps(sweep, metrics, errors_png)
    elif len(sweep.axes) <= 1 or sweep.combine == "zip":
        _lines(sweep, rows, errors_png)
    else:
        _scatter(sweep, metrics, errors_png)
    _runtimes(sweep, rows, out / "runtime.png")
    return written + [errors_png, out / "runtime.png"]
