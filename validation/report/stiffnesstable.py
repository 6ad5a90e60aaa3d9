"""The stiffness at the target in the validation report: the data, then its Markdown.

A stage designer's first numbers are the target's stiffness along its motion and
across it. Every model the report runs, and its reference, gets the 3 x 3
compliance at the target at rest, exactly as ``flexval stiffness SCENE --model M``
gives it (:func:`flexval.validation.studies.stiffness.run_stiffness`). The table gives each
coordinate's stiffness with the other two free, 1 / C_ii (the force a probe pushing
only along that coordinate meets), which is what a one-axis measurement of the target
finds and is defined even where a model is rigid along another coordinate, and its
error against the reference's. A model rigid along a coordinate (C_ii = 0: the PRBM's
inextensible straight leaves) shows as rigid, never as a large finite number.

Units: N/mm (dx, dy), N mm/rad (rotation); errors in percent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexval.geometry import Scene, SceneError
from flexval.reducedmodels import SolverError
from flexval.reducedmodels.catalogue import parse_model

from ..failures import Failure
from ..studies.stiffness import MOTIONS, run_stiffness

AXIS_UNITS = ("N/mm", "N/mm", "N mm/rad")
"""The unit of each coordinate's stiffness, in the order of
:data:`~flexval.validation.studies.stiffness.MOTIONS`."""
RIGID_FRACTION = 1e-12
"""A diagonal compliance below this fraction of the reference's is the model's rigid
direction (its compliance is zero to round-off): the relative size of a double's
round-off after a few solves with the tangent."""


@dataclass
class StiffnessTable:
    """The target's stiffness at rest of one scene's models.

    Attributes
    ----------
    models : list of str
        Every model analysed, in the report's order (the reference first if the report
        does not run it).
    reference : str
        Model id the errors are computed against.
    body : str
        The target body.
    point : tuple of float
        The target point at rest, mm.
    axial : dict of str -> list of (float or None)
        Model id -> the stiffness along dx, dy and rotation with the other two free
        (N/mm, N/mm, N mm/rad); None where the model is rigid along it.
    errors : dict of str -> list of (float or None)
        Model id -> (k - k_ref) / k_ref in percent, coordinate by coordinate (None where
        either is rigid or the reference failed).
    failures : list of Failure
        Models whose stiffness could not be found (a singular tangent at rest).
    """

    models: list[str]
    reference: str
    body: str
    point: tuple[float, float]
    axial: dict[str, list[float | None]]
    errors: dict[str, list[float | None]]
    failures: list[Failure]


def axial_stiffness(compliance: np.ndarray, scale: np.ndarray) -> list[float | None]:
    """1 / C_ii for each coordinate (None where C_ii is below :data:`RIGID_FRACTION` of
    ``scale``, that coordinate's reference compliance)."""
    diagonal = np.diag(compliance)
    return [None if c <= RIGID_FRACTION * s else float(1.0 / c) for c, s in zip(diagonal, scale)]


def stiffness_errors(values: list[float | None], reference: list[float | None] | None):
    """(k - k_ref) / k_ref in percent, coordinate by coordinate (None where either is rigid
    or there is no reference)."""
    if reference is None:
        return [None] * len(values)
    return [
        None if k is None or r is None else 100.0 * (k - r) / r for k, r in zip(values, reference)
    ]


def stiffness_data(scene: Scene, models: list[str], reference: str) -> StiffnessTable:
    """The target-stiffness table of ``scene`` for ``models`` and ``reference``.

    The reference is analysed too if it is not among ``models`` (listed first then).
    Solver and scene failures are recorded, never raised.
    """
    order = ([] if reference in models else [reference]) + list(models)
    compliances: dict[str, np.ndarray] = {}
    failures: list[Failure] = []
    point = scene.mechanism.target_point
    for model in order:
        try:
            _, found, _ = run_stiffness(scene, parse_model(model), None, 0.0)
        except (SolverError, SceneError, np.linalg.LinAlgError) as exc:
            reason = exc.reason if isinstance(exc, SceneError) else str(exc)
            failures.append(Failure(model, "rest", 0.0, 0.0, "N", reason, str(exc)))
            continue
        compliances[model] = found.compliance
    scale = np.abs(
        np.diag(compliances.get(reference, next(iter(compliances.values()), np.ones((3, 3)))))
    )
    axial = {m: axial_stiffness(c, scale) for m, c in compliances.items()}
    ref = axial.get(reference)
    return StiffnessTable(
        order,
        reference,
        scene.mechanism.target_body,
        (float(point[0]), float(point[1])),
        axial,
        {m: stiffness_errors(k, ref) for m, k in axial.items()},
        failures,
    )


def stiffness_table(table: StiffnessTable) -> list[str]:
    """Markdown: model x coordinate, the stiffness and its error against the reference."""
    heads = [f"k {axis} ({unit})" for axis, unit in zip(MOTIONS, AXIS_UNITS)]
    lines = ["| model | " + " | ".join(heads) + " |", "|---|" + "---:|" * len(heads)]
    failed = {f.model for f in table.failures}
    for m in table.models:
        if m in failed:
            cells = ["fails (below)"] + ["—"] * (len(heads) - 1)
        else:
            cells = [
                "rigid"
                if k is None
                else f"{k:.5g}"
                if e is None or m == table.reference
                else f"{k:.5g} ({e:+.2f} %)"
                for k, e in zip(table.axial[m], table.errors[m])
            ]
        lines.append(f"| `{m}` | " + " | ".join(cells) + " |")
    return lines


def section(table: StiffnessTable) -> list[str]:
    """The report's Markdown on the stiffness at the target of one scene."""
    x, y = table.point
    lines = [
        f"### Stiffness at the target against `{table.reference}`",
        "",
        f"The stiffness of `{table.body}` at ({x:.4g}, {y:.4g}) mm at rest, as `flexval "
        "stiffness` gives it: along each coordinate with the other two free (1 / C_ii, what "
        "a probe pushing only along it meets); in parentheses its error against the "
        "reference's. `rigid`: the model allows no motion along that coordinate.",
        "",
    ]
    lines += stiffness_table(table) + [""]
    for f in table.failures:
        lines += [f"- `{f.model}`: no stiffness at rest ({f.reason})", ""]
    return lines
