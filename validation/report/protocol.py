"""The report's section on the paper's dynamic protocol, read from ``protocol.json``.

``benchmarks/paper_protocol.py`` runs the paper's protocol (Eq. 15 ramp,
Rayleigh damping, errors read at the end of the ramp) on the open chain's f-
case over a grid of ramp times and damping ratios; it takes minutes, too long
for ``flexval report``. It writes its results as ``protocol.json`` (format
:data:`PROTOCOL_FORMAT`, no timings) next to its full table ``protocol.md``;
:func:`protocol_section` renders the report's summary from that file: the
paper's figures, each model's grid cell closest to its paper figure, the
verdict, a link to the full table, and a note when the file is missing,
unreadable or was computed by another code version. It never fails the
report: a bad file becomes a sentence saying how to produce a good one.

File contents (errors in percent; ramp times in first natural periods T1 of
the reference at rest, and in s)::

    {"format": "flexval-protocol/1", "code_version": "<hash>",
     "scene": "open_chain", "case": "f-", "reference": "beam:100",
     "match_points": 2.0, "table": "protocol.md",
     "paper": {"beam:20": {"disp": 10.7, "rot": 8.5}, ...},
     "static": {"beam:20": {"disp": 0.5, "rot": 0.5}, ...},
     "cells": [{"model": "beam:20", "ramp_periods": 2.0, "ramp_s": 0.09,
                "damping_ratio": 0.05, "disp": 118.5, "rot": 230.0,
                "integration": {"disp": 0.4, "rot": 0.5},
                "failure": null}, ...], "check_factor": 10.0, ...}

``disp`` / ``rot`` of a cell are the end-of-ramp errors against the
reference run under the same protocol (null for a failed run);
``integration`` (optional, points) their change when every run's local
error bound is ``check_factor`` times looser, an estimate of the
integration error the cell carries.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..studies.studyfile import read_study, stale_lines

PROTOCOL_FORMAT = "flexval-protocol/1"
"""Format tag of ``protocol.json``."""
PROTOCOL_SCENE = "open_chain"
"""The scene whose f- case the protocol study runs (the section appears only with it)."""
REQUIRED = ("code_version", "case", "reference", "match_points", "paper", "static", "cells")
"""Fields the section reads."""
PRODUCE = (
    "`python benchmarks/paper_protocol.py` (writes `reports/dynamics/protocol.json`; "
    "minutes), then `flexval report --protocol reports/dynamics/protocol.json`"
)
"""How to produce the file the section is rendered from."""


@dataclass(frozen=True)
class Cell:
    """One model on one grid cell: ramp (T1 and s), damping ratio, errors (percent) or failure."""

    model: str
    ramp_periods: float
    ramp_s: float
    damping_ratio: float
    disp: float | None
    rot: float | None
    failure: str | None
    integration: float | None = None


def read_protocol(path: Path) -> tuple[dict | None, str | None]:
    """The protocol document at ``path``, or None and the reason it cannot be used."""
    doc, why = read_study(path, PROTOCOL_FORMAT, REQUIRED)
    if doc is None:
        return None, why
    try:
        _cells(doc)
        _by_model(doc, "paper")
        _by_model(doc, "static")
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        return None, f"`{path.as_posix()}` has a malformed entry ({type(exc).__name__}: {exc})"
    return doc, None


def _cells(doc: dict) -> list[Cell]:
    return [
        Cell(
            str(c["model"]),
            float(c["ramp_periods"]),
            float(c["ramp_s"]),
            float(c["damping_ratio"]),
            _num(c["disp"]),
            _num(c["rot"]),
            c.get("failure"),
            _largest(c.get("integration")),
        )
        for c in doc["cells"]
    ]


def _largest(change: dict | None) -> float | None:
    """The larger of a cell's integration error estimates (points), None if absent or failed."""
    if not change or change.get("disp") is None or change.get("rot") is None:
        return None
    return max(float(change["disp"]), float(change["rot"]))


def _by_model(doc: dict, key: str) -> dict[str, tuple[float, float]]:
    """(disp, rot) errors (percent) by model of ``doc[key]`` ("paper" or "static")."""
    return {str(m): (float(f["disp"]), float(f["rot"])) for m, f in doc[key].items()}


def _num(v) -> float | None:
    return None if v is None else float(v)


def closest_cell(cells: list[Cell], model: str, paper_disp: float) -> Cell | None:
    """The successful cell of ``model`` whose disp error is closest to ``paper_disp`` (percent);
    ties go to the first in grid order. None when the model has no successful cell."""
    mine = [c for c in cells if c.model == model and c.disp is not None]
    return min(mine, key=lambda c: abs(c.disp - paper_disp)) if mine else None


def _cell_text(c: Cell) -> str:
    return f"ramp {c.ramp_periods:g} T1 ({c.ramp_s:.3f} s), damping ratio {c.damping_ratio:g}"


def _model_lines(doc: dict, cells: list[Cell]) -> tuple[list[str], dict[str, set]]:
    """One bullet per model with a paper figure, and the grid cells matching its disp figure."""
    pts = float(doc["match_points"])
    lines, matching = [], {}
    statics = _by_model(doc, "static")
    for model, (p_disp, p_rot) in _by_model(doc, "paper").items():
        best = closest_cell(cells, model, p_disp)
        if best is None:
            lines.append(
                f"- **{model}** (paper {p_disp:g} % disp, {p_rot:g} % rot): every "
                "run failed; not reproduced."
            )
            matching[model] = set()
            continue
        hits = [
            c
            for c in cells
            if c.model == model and c.disp is not None and abs(c.disp - p_disp) <= pts
        ]
        matching[model] = {(c.ramp_periods, c.damping_ratio) for c in hits}
        rot_ok = abs(best.rot - p_rot) <= pts
        verdict = (
            f"**reproduced** (disp within {pts:g} points"
            f"{'; rot too' if rot_ok else f'; rot {best.rot:.1f} % is not'}), "
            f"by {len(hits)} of the grid's cells"
            if hits
            else f"**not reproduced** (no cell within {pts:g} points)"
        )
        static_text = (
            f"; static {statics[model][0]:.1f} % / {statics[model][1]:.1f} %"
            if model in statics
            else ""
        )
        lines.append(
            f"- **{model}** (paper {p_disp:g} % disp, {p_rot:g} % rot{static_text}): "
            f"closest "
            f"{_cell_text(best)}: {best.disp:.1f} % disp, {best.rot:.1f} % rot; "
            f"{verdict}."
        )
    return lines, matching


def protocol_section(path: Path | None, out: Path, code: str) -> list[str]:
    """Markdown lines of the section, from ``path`` (None: not given) for a report written to
    ``out`` by code version ``code``; the link to the full table is relative to ``out``."""
    lines = [
        "## Dynamics: the paper's protocol (open chain f−)",
        "",
        "The paper ran dynamic simulations (loads ramped by its Eq. 15, damping "
        '"adjusted to minimize dynamic effects", errors read at the end of the ramp). '
        "`benchmarks/paper_protocol.py` runs that protocol on a grid of ramp times and "
        "damping ratios; it takes minutes, so the report reads its result file.",
        "",
    ]
    if path is None:
        return lines + [
            f"Not included in this report (no `--protocol` file). Produce it with {PRODUCE}.",
            "",
        ]
    doc, why = read_protocol(path)
    if doc is None:
        return lines + [f"Not available: {why}. Produce it with {PRODUCE}.", ""]
    cells = _cells(doc)
    table = Path(os.path.relpath(path.parent / doc.get("table", "protocol.md"), out)).as_posix()
    lines += stale_lines(doc, code, "python benchmarks/paper_protocol.py")
    lines += [
        f"Errors (percent) at the end of the ramp against `{doc['reference']}` run "
        f"under the same protocol, on {doc['case']}; ramp times in T1, the first natural "
        f"period at rest of `{doc['reference']}`. A paper figure counts as reproduced by a "
        f"grid cell within {float(doc['match_points']):g} percentage points of it.",
        "",
    ]
    model_lines, matching = _model_lines(doc, cells)
    lines += model_lines
    if len(matching) > 1:
        common = sorted(set.intersection(*matching.values()))
        both = ", ".join(f"{t:g} T1 / ratio {z:g}" for t, z in common)
        lines.append(
            f"- One protocol for every model at once (as the paper ran it): "
            f"{both or 'no grid cell'}."
        )
    checked = [c.integration for c in cells if c.integration is not None]
    if checked:
        lines.append(
            f"- Integration error: at most {max(checked):.2f} points over the grid "
            f"(each cell's change when every run's error bound is "
            f"{float(doc.get('check_factor') or 0):g} times looser, an over-estimate)."
        )
    failed = sum(c.failure is not None for c in cells)
    if failed:
        lines.append(f"- {failed} of {len(cells)} runs failed (listed in the full table).")
    lines += ["", f"Full grid, frequencies, static errors and lags: [{table}]({table}).", ""]
    return lines
