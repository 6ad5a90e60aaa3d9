"""The files of a sweep's tolerance study: ``tolerance.json`` and a histogram per quantity.

A sweep whose every axis is random (:func:`is_tolerance`) gets, beside its summary,
``tolerance.json`` (:func:`flexval.validation.sweep.tolerance.study`, numbers rounded to
:data:`~flexval.validation.sweep.tolerance.SIGNIFICANT` significant digits, null where
undefined) and ``tolerance_<quantity>.png`` for each output and error metric some row
carries: a panel per model (rows of panels, the reference first) and load case (columns),
the histogram of the values with the mean (solid), the median (dotted) and the 1st and 99th
percentiles (dashed). Matplotlib, Agg; model colours from
:func:`flexval.validation.report.figures.style`.

Units: those of each quantity (mm, deg, MPa, N or N mm, percent).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..outputs import write_figure, write_json
from .columns import Columns, Rows
from .spec import Sweep
from .tolerance import ERRORS, OUTPUTS, Quantity, recorded, rounded, samples, study

JSON_NAME = "tolerance.json"
FILES = (JSON_NAME,) + tuple(f"tolerance_{q.name}.png" for q in OUTPUTS + ERRORS)
"""Every file a tolerance study may write (a summary removes those it did not write)."""
MAX_BINS = 60
"""Most bins of one histogram (a panel is a few hundred pixels wide)."""
ROUND_OFF = 1e-6
"""Spread (largest - smallest value) relative to the largest |value| below which a quantity
is drawn as one value rather than a histogram: the solvers' own noise. Under a pure moment
the open chain's end rotation error is the same at every draw, and spreads 3e-8 of its value
over the draws of ``open_chain_tolerance`` (dcmm:1); a tolerance study's outputs spread by
its tolerance, percents."""
PANEL = (3.6, 2.4)
"""Width and height of one histogram panel, inches."""


def is_tolerance(sweep: Sweep) -> bool:
    """Whether ``sweep`` is a tolerance study: it has axes, and every one is random."""
    return bool(sweep.axes) and all(a.random for a in sweep.axes)


def _quantities(sweep: Sweep, kinds: tuple[Quantity, ...]) -> tuple[Quantity, ...]:
    """The quantities of ``kinds`` that the sweep's outputs give (peak stress, limit load
    only when asked for)."""
    from .fields import OPTIONAL_OUTPUTS

    return tuple(
        q
        for q in kinds
        if not any(n in OPTIONAL_OUTPUTS and n not in sweep.outputs for n in q.needs)
    )


def sweep_study(sweep: Sweep, rows: Rows) -> dict[str, Any]:
    """The tolerance study of ``sweep``'s rows (unrounded), with the sweep's name, reference,
    load cases and random axes."""
    data = study(
        rows,
        sweep.reference.id,
        [s.id for s in sweep.models],
        sweep.load_cases,
        _quantities(sweep, OUTPUTS),
        _quantities(sweep, ERRORS),
    )
    axes = [
        {"path": a.path, "count": len(a.values)}
        | {k: v for k, v in zip(("mean", "std"), _moments(a.values))}
        for a in sweep.axes
    ]
    return {
        "sweep": sweep.name,
        "reference": sweep.reference.id,
        "reference_sample": sweep.reference_sample,
        "load_cases": list(sweep.load_cases),
        "axes": axes,
    } | data


def _moments(values: tuple[float, ...]) -> tuple[float, float | None]:
    a = np.asarray(values, dtype=float)
    return float(a.mean()), (float(a.std(ddof=1)) if a.size > 1 else None)


def bins(values: np.ndarray) -> int | np.ndarray:
    """numpy's ``auto`` bin edges of ``values``, or :data:`MAX_BINS` equal bins where ``auto``
    would give more (a few far outliers beside a narrow bulk)."""
    edges = np.histogram_bin_edges(values, bins="auto")
    return edges if len(edges) <= MAX_BINS + 1 else MAX_BINS


def histogram(
    rows: Rows,
    quantity: Quantity,
    entry: dict[str, Any],
    cases: tuple[str, ...],
    path: Path,
) -> Path:
    """Draw the histograms of ``quantity`` (its study ``entry`` gives the models, counts and
    statistics) into ``path``; the models without a value are left out."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    from ..report.figures import style

    models = [m for m, per in entry["models"].items() if any(d["n"] for d in per.values())]
    per_model = samples(rows, models, cases, quantity)
    units = entry.get("units") or {}
    fig, axs = plt.subplots(
        len(models),
        len(cases),
        figsize=(PANEL[0] * len(cases), PANEL[1] * len(models)),
        squeeze=False,
    )
    for i, m in enumerate(models):
        for j, c in enumerate(cases):
            ax, d = axs[i][j], entry["models"][m][c]
            values = per_model[m][c][0]
            if values.size and np.ptp(values) <= ROUND_OFF * np.max(np.abs(values)):
                ax.text(
                    0.5,
                    0.5,
                    f"all {values.size} values {d['mean']:.4g}\n(spread below the solvers' noise)",
                    ha="center",
                    va="center",
                    transform=ax.transAxes,
                    fontsize=8,
                )
            elif values.size:
                ax.hist(
                    values, bins=bins(values), color=style(m).get("color", "tab:brown"), alpha=0.75
                )
                ax.axvline(d["mean"], color="k", lw=1.0, label="mean")
                ax.axvline(d["p50"], color="k", lw=0.8, ls=":", label="median")
                for p in ("p1", "p99"):
                    ax.axvline(d[p], color="k", lw=0.8, ls="--", label="1 %, 99 %")
                ax.xaxis.set_major_locator(MaxNLocator(4))  # an offset for a narrow spread
            else:
                ax.text(0.5, 0.5, "no values", ha="center", va="center", transform=ax.transAxes)
            ax.set_title(f"{m}, {c}: n = {d['n']} / {d['rows']}", fontsize=8)
            unit = units.get(c) or quantity.unit
            ax.set_xlabel(f"{quantity.label} ({unit})", fontsize=8)
            ax.set_ylabel("points", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
    handles, labels = axs[0][0].get_legend_handles_labels()
    if handles:
        keep = dict(zip(labels, handles))
        axs[0][0].legend(keep.values(), keep.keys(), fontsize=6)
    return write_figure(fig, path, dpi=90)


def write_tolerance(sweep: Sweep, rows: Rows, out: Path) -> list[Path]:
    """Write ``tolerance.json`` and the histograms of the quantities some row carries into
    ``out``; the written paths."""
    table = Columns.of(rows)  # the study and the histograms read the same columns
    data = sweep_study(sweep, table)
    written = [write_json(out / JSON_NAME, rounded(data))]
    kinds = {q.name: q for q in OUTPUTS + ERRORS}
    for section in ("outputs", "errors"):
        for name, entry in recorded(data[section]).items():
            path = out / f"tolerance_{name}.png"
            written.append(histogram(table, kinds[name], entry, sweep.load_cases, path))
    return written


def summary_lines(sweep: Sweep, rows: Rows) -> list[str]:
    """The summary's Markdown section of the tolerance study (empty if ``sweep`` is not one)."""
    if not is_tolerance(sweep):
        return []
    from .tolerance import markdown

    return markdown(sweep_study(sweep, rows), sweep.load_cases, sweep.reference.id)
