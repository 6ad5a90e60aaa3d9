"""What holds a prescribed motion: each model's reaction against the reference's.

Under displacement control the motion is the input and the force (or moment) the
drive needs is the answer a designer reads: a guide's stiffness, a bistable
mechanism's snap-through force. The displacement metrics of
:mod:`flexval.validation.studies.compare` see only the free components there (reported
as parasitic motion, :mod:`flexval.validation.studies.parasitic`); this module scores the
reaction itself, component by component along the drive:

* at full load, against the reference's value of that component (percent);
* over the path, the largest difference against the reference's largest
  magnitude of it (percent): a bistable's force changes sign, so a value near a
  zero crossing is no scale;
* the reference's largest value and where it is zero (unloaded equilibria).

Units: N, N mm, mm, rad; errors in percent.
"""

from __future__ import annotations

import math

import numpy as np

from flexval.geometry import Displacement
from flexval.reducedmodels import LoadPath

COMPONENT_NAMES = ("Fu", "Fv", "M")
"""The reaction's components along the drive's frame: its dx axis, its dy axis, the
moment."""


def along_drive(path: LoadPath, drive: Displacement) -> np.ndarray:
    """The reaction in the drive's frame at every level, (levels, 3): force along its dx
    and dy axes (N) and the moment (N mm)."""
    forces = np.asarray(path.drive_reactions, float).reshape(-1, 3)
    c, s = math.cos(drive.angle), math.sin(drive.angle)
    return np.column_stack(
        [c * forces[:, 0] + s * forces[:, 1], -s * forces[:, 0] + c * forces[:, 1], forces[:, 2]]
    )


def reaction_errors(model: LoadPath, ref: LoadPath, drive: Displacement) -> list[dict]:
    """Per prescribed component of ``drive``: ``component``, ``unit``, the reference's and
    the model's value at full load, ``end`` (percent of the reference's) and ``path`` (the
    largest difference over the path, percent of the reference's largest magnitude), both
    paths on the same load factors."""
    ours, theirs = along_drive(model, drive), along_drive(ref, drive)
    if ours.shape != theirs.shape:
        raise ValueError(
            f"{model.model} and {ref.model} on {ref.load_case}: "
            f"{len(ours)} and {len(theirs)} levels"
        )
    rows = []
    for k, _ in drive.prescribed:
        mine, reference = ours[:, k], theirs[:, k]
        largest = float(np.abs(reference).max())
        rows.append(
            {
                "component": COMPONENT_NAMES[k],
                "unit": "N mm" if k == 2 else "N",
                "reference": float(reference[-1]),
                "model": float(mine[-1]),
                "end": _percent(mine[-1] - reference[-1], reference[-1]),
                "path": _percent(np.abs(mine - reference).max(), largest),
            }
        )
    return rows


def _percent(difference: float, of: float) -> float | None:
    """100 |difference| / |of|, None where ``of`` is zero."""
    return 100.0 * abs(float(difference)) / abs(of) if of else None


def zero_crossings(path: LoadPath, values: np.ndarray) -> list[float]:
    """The loads (the prescribed motion, mm or rad) where ``values`` along ``path`` change
    sign, interpolated linearly between levels (the rest state excluded)."""
    load = np.asarray(path.load, float)
    found = []
    for i in range(1, len(values) - 1):
        a, b = values[i], values[i + 1]
        if a * b < 0 or (b == 0 and a != 0):
            found.append(float(load[i] + (load[i + 1] - load[i]) * a / (a - b)))
    return found


def section(res, reference: str) -> list[str]:
    """Markdown: the reaction of every displacement-controlled load case of a scene's results
    ``res`` (:class:`flexval.validation.report.data.SceneResults`), each model against
    ``reference``; nothing where no case prescribes a motion."""
    lines: list[str] = []
    for c in res.cases:
        drive = res.scene.load_case(c).drive
        ref = res.converged(reference, c)
        if drive is None or ref is None or not ref.drive_reactions:
            continue
        rows = []
        for m in res.models:
            lp = res.converged(m, c)
            if m == reference or lp is None or not lp.drive_reactions:
                continue
            for e in reaction_errors(lp, ref, drive):
                rows.append(
                    f"| {m} | {e['component']} ({e['unit']}) | {e['model']:.5g} | "
                    f"{_cell(e['end'])} | {_cell(e['path'])} |"
                )
        if not rows:
            continue
        along = along_drive(ref, drive)
        told = []
        for k, _ in drive.prescribed:
            values = along[:, k]
            zeros = zero_crossings(ref, values)
            text = (
                f"{COMPONENT_NAMES[k]} from {values.min():.5g} to {values.max():.5g} "
                f"{'N mm' if k == 2 else 'N'}"
            )
            if zeros:
                text += f", zero at {', '.join(f'{z:.4g}' for z in zeros)} {ref.load_unit}"
            told.append(text)
        lines += [f"`{c}` — `{reference}`: {'; '.join(told)}.", ""]
        lines += [
            "| model | reaction | at full load | error (% of the reference's) | "
            "largest difference over the path (% of its largest) |",
            "|---|---|---:|---:|---:|",
            *rows,
            "",
        ]
    if not lines:
        return []
    return [
        "### Reaction to the prescribed motion",
        "",
        "Where a load case prescribes a motion, the force and moment that hold it are the "
        "answer: each model's reaction along the drive's axes (Fu, Fv along its dx and dy, M "
        "the moment) against the reference's, at full load and over the path.",
        "",
        *lines,
    ]


def _cell(value: float | None) -> str:
    return "–" if value is None else f"{value:.2f}"
