"""Models against a measurement, rendered: the table (terminal and Markdown), the figure
and the report's *Against measurements* section.

The numbers come from :mod:`flexval.validation.studies.measuredcompare`; here they are only
formatted. Scores in percent of the measured range, shares in percent, loads in N or
N mm, displacements in mm, rotations in degrees.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..studies.measuredcompare import MeasuredComparison
from .tables import Column, markdown_table, sig, text_table

COLUMNS = (
    Column("model", "<"),
    Column("points"),
    Column("disp rms %"),
    Column("disp max %"),
    Column("rot rms %"),
    Column("rot max %"),
    Column("disp in 2u %"),
    Column("rot in 2u %"),
)
"""The columns of the comparison table (``2u``: twice the standard uncertainty)."""
_LABELS = {"dx": "dx (mm)", "dy": "dy (mm)", "rotation": "rotation (deg)"}


def _share(value: float | None) -> str:
    return "-" if value is None else f"{100.0 * value:.0f}"


def rows(comparison: MeasuredComparison) -> list[list[str]]:
    """One row per model: scored points (of the file's), the four scores, the shares
    within twice the standard uncertainty."""
    n = len(comparison.measurement.load)
    return [
        [
            s.model,
            f"{s.scored}/{n}",
            *(sig(s.errors[k], 3) for k in ("disp_rms", "disp_max", "rot_rms", "rot_max")),
            _share(s.within_2u["disp"]),
            _share(s.within_2u["rot"]),
        ]
        for s in comparison.scores
    ]


def headline(comparison: MeasuredComparison) -> str:
    """One line: the file, its load case, rows and measured ranges."""
    m, ranges = comparison.measurement, comparison.ranges()
    parts = []
    if ranges["disp"] is not None:
        parts.append(f"displacement {sig(ranges['disp'])} mm")
    if ranges["rot"] is not None:
        parts.append(f"rotation {sig(ranges['rot'])} deg")
    return (
        f"{comparison.scene.name} {m.load_case}: {len(m.load)} measured points from "
        f"{Path(m.source).name} (loads {sig(min(m.load, key=abs))} to "
        f"{sig(max(m.load, key=abs))} {m.unit}); measured range: {', '.join(parts)}"
    )


def notes(comparison: MeasuredComparison) -> list[str]:
    """One line per model whose path stops before the largest measured load, and per
    score left undefined by a measured range of zero."""
    out = [f"{s.model}: {comparison.beyond_text(s)}" for s in comparison.stopped()]
    ranges = comparison.ranges()
    for quantity, word in (("disp", "displacement"), ("rot", "rotation")):
        if ranges[quantity] == 0.0:
            out.append(f"the measured {word} does not vary: no {word} score (range 0)")
    return out


def text_lines(comparison: MeasuredComparison) -> list[str]:
    """The comparison as the terminal shows it: headline, table, notes."""
    return (
        [headline(comparison)]
        + text_table(COLUMNS, rows(comparison))
        + [f"  ! {line}" for line in notes(comparison)]
    )


def plot(comparison: MeasuredComparison, path: Path) -> str:
    """Each measured column against the load: the measurement (error bars: twice the
    standard uncertainty, where given) and every model's path through the measured loads
    (a path that stops early ends where it stopped). Matplotlib, Agg."""
    from ..outputs import write_figure
    from . import figures

    plt = figures.plt
    m = comparison.measurement
    cols = list(m.columns)
    fig, axes = plt.subplots(1, len(cols), figsize=(4.4 * len(cols), 4.2), squeeze=False)
    load = np.asarray(m.load)
    for ax, col in zip(axes[0], cols):
        to_shown = math.degrees(1.0) if col == "rotation" else 1.0
        for s in comparison.scores:
            if s.path is None or not s.path.load:
                continue
            label = s.model + (
                f" (stops at {sig(comparison.reached_load(s), 3)} {m.unit})" if s.failure else ""
            )
            ax.plot(
                s.path.load,
                np.asarray(getattr(s.path, col)) * to_shown,
                label=label,
                **figures.style(s.model),
            )
        std = m.std(col)
        ax.errorbar(
            load,
            np.asarray(getattr(m, col)) * to_shown,
            yerr=None if std is None else 2.0 * np.asarray(std) * to_shown,
            fmt="o",
            color="black",
            mfc="white",
            ms=4,
            capsize=2,
            lw=1,
            zorder=5,
            label="measured" + (" (± 2 u)" if std is not None else ""),
        )
        ax.set_xlabel(f"load ({m.unit})")
        ax.set_ylabel(_LABELS[col])
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.suptitle(f"{comparison.scene.name}, load case {m.load_case}: models against measurement")
    return write_figure(fig, path).name


def section(comparisons: list[MeasuredComparison], out: Path, draw: Callable) -> list[str]:
    """Markdown of the report's *Against measurements* section of one scene (empty when
    the scene has no measurement); draws each figure into ``out`` with ``draw``."""
    from ..outputs import output_path

    if not comparisons:
        return []
    L = [
        "### Against measurements",
        "",
        "Each model traced through the measured loads of the scene's `[[measurements]]` "
        "files and scored at every measured point: RMS and largest difference in percent "
        "of the measured range (the largest distance between two measured values; the "
        "displacement is the vector (dx, dy) where both are measured); *in 2u*: the share "
        "of points within twice the measurement's standard uncertainty. Loads beyond a "
        "model's path are not scored.",
        "",
    ]
    for k, c in enumerate(comparisons):
        png = output_path(out, f"{c.scene.name}_{c.measurement.load_case}_measured_{k}", ".png")
        draw(plot, c, png)
        L += [headline(c) + ".", ""]
        L += markdown_table(COLUMNS, rows(c)) + [""]
        stops = notes(c)
        L += [f"- {line}." for line in stops] + ([""] if stops else [])
        L += [f"![{c.scene.name} {c.measurement.load_case}: measured]({png.name})", ""]
    return L
