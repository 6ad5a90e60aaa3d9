"""Natural frequencies in the validation report: the data, then its Markdown.

Every model the report runs, and its reference, gets the first
:data:`MODE_COUNT` natural frequencies about the rest state (the undeformed
state, or the equilibrium under gravity if the scene has gravity), exactly as
``flexval modes SCENE --model M --count 4`` gives them
(:func:`flexval.validation.studies.modes.run_modes`), and each mode's error against the
reference's mode of the same rank. The scene's mass data are used as given;
the flexure density is chosen by :func:`flexval.validation.studies.modes.choose_density`,
the function behind ``flexval modes`` and ``flexval run --dynamic``: a scene without
one gets :data:`DEFAULT_DENSITY` (PLA), as ``flexval modes --density`` would, and the
section says which density it assumed and why; bodies without mass data stay
massless (they then carry only the flexure pieces each model lumps on
them: see the models' ``mass_points``). A model whose modal
analysis fails (a massless moving body, no equilibrium, a singular mass
matrix) is a :class:`~flexval.validation.failures.Failure` in the table.

Units: Hz; density in t/mm^3; errors in percent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.linalg import ArpackError

from flexval.geometry import LoadCase, Moment, Scene, SceneError
from flexval.geometry.inertia import PLA_DENSITY
from flexval.reducedmodels import SolverError
from flexval.reducedmodels.catalogue import ModelSpec, parse_model

from ..failures import Failure
from ..studies.modes import DensityChoice, choose_density, run_modes

#: flexure density (t/mm^3) of a scene that gives none: PLA, as in the documentation's
#: frequency table
DEFAULT_DENSITY = PLA_DENSITY
#: how many of the lowest natural frequencies the report tabulates
MODE_COUNT = 4


@dataclass
class FrequencyTable:
    """The natural frequencies of one scene's models at rest.

    Attributes
    ----------
    models : list of str
        Every model analysed, in the report's order (the reference first if
        the report does not run it).
    reference : str
        Model id the errors are computed against.
    density : DensityChoice
        Flexure density used (t/mm^3) and where it comes from (the scene's, or
        :data:`DEFAULT_DENSITY`).
    massless_bodies : list of str
        Moving bodies without mass data.
    gravity : bool
        Whether the rest state is the equilibrium under the scene's gravity.
    frequencies : dict of str -> list of float
        Model id -> its lowest natural frequencies (Hz, ascending; negative:
        unstable), at most :data:`MODE_COUNT` (fewer if the model has fewer
        massive coordinates).
    errors : dict of str -> list of (float or None)
        Model id -> (f - f_ref) / f_ref in percent, mode by mode (None where
        the reference has no such mode or failed).
    failures : list of Failure
        Models whose modal analysis failed, on the load case ``"rest"``.
    """

    models: list[str]
    reference: str
    density: DensityChoice
    massless_bodies: list[str]
    gravity: bool
    frequencies: dict[str, list[float]]
    errors: dict[str, list[float | None]]
    failures: list[Failure]


def _rest_case(scene: Scene) -> LoadCase:
    """The rest state's load case as
    :func:`flexval.reducedmodels.analyses.modes.scaled_case` builds it."""
    return LoadCase("rest", (Moment(scene.mechanism.target_body, 0.0),), 2)


def mode_errors(values: list[float], reference: list[float] | None) -> list[float | None]:
    """(f - f_ref) / f_ref in percent, mode by mode against the reference's mode of the same
    rank (None where the reference has no such mode, or none at all)."""
    if reference is None:
        return [None] * len(values)
    return [
        100.0 * (f - reference[k]) / reference[k] if k < len(reference) else None
        for k, f in enumerate(values)
    ]


MODAL_ERRORS = (SolverError, SceneError, np.linalg.LinAlgError, ArpackError)
"""The failures of a modal analysis that the report records as a model's result."""


def lowest_frequencies(massive: Scene, spec: ModelSpec, count: int = MODE_COUNT) -> list[float]:
    """The ``count`` lowest natural frequencies (Hz, ascending) of ``spec`` at rest on
    ``massive`` (the scene with the density of
    :func:`~flexval.validation.studies.modes.choose_density`),
    as the report's table gives them (fewer if the model has fewer massive coordinates).

    Raises
    ------
    One of :data:`MODAL_ERRORS`
        If the modal analysis fails.
    """
    _, modes = run_modes(massive, spec, None, 0.0, count)
    return modes.frequencies_hz.tolist()


def modal_reason(exc: Exception) -> str:
    """The reason of a failed modal analysis, in words (one of :data:`MODAL_ERRORS`)."""
    if isinstance(exc, SceneError):
        return exc.reason
    if isinstance(exc, SolverError):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"


def frequency_data(scene: Scene, models: list[str], reference: str) -> FrequencyTable:
    """The natural-frequency table of ``scene`` for ``models`` and ``reference``.

    The reference is analysed too if it is not among ``models`` (listed
    first then). Solver, scene and eigensolver failures are recorded, never
    raised.
    """
    inertia = scene.mechanism.inertia
    massive, density = choose_density(scene, None, DEFAULT_DENSITY)
    rest = _rest_case(scene)
    order = ([] if reference in models else [reference]) + list(models)
    frequencies: dict[str, list[float]] = {}
    failures: list[Failure] = []
    for model in order:
        try:
            frequencies[model] = lowest_frequencies(massive, parse_model(model))
        except MODAL_ERRORS as exc:
            factor = exc.load_factor if isinstance(exc, SolverError) else 0.0
            failures.append(
                Failure(model, rest.name, factor, 0.0, rest.unit, modal_reason(exc), str(exc))
            )
    ref = frequencies.get(reference)
    return FrequencyTable(
        order,
        reference,
        density,
        inertia.massless_bodies(scene.mechanism.moving_bodies),
        inertia.gravity is not None,
        frequencies,
        {m: mode_errors(f, ref) for m, f in frequencies.items()},
        failures,
    )


def frequency_table(table: FrequencyTable) -> list[str]:
    """Markdown: model x mode, frequency (Hz) and its error against the reference."""
    lines = [
        "| model | " + " | ".join(f"f{k + 1} (Hz)" for k in range(MODE_COUNT)) + " |",
        "|---|" + "---:|" * MODE_COUNT,
    ]
    for m in table.models:
        fail = next((f for f in table.failures if f.model == m), None)
        if fail is not None:
            cells = ["fails (below)"] + ["—"] * (MODE_COUNT - 1)
        else:
            values, errs = table.frequencies[m], table.errors[m]
            cells = [
                (
                    "—"
                    if k >= len(values)
                    else f"{values[k]:.5g}"
                    if errs[k] is None
                    else f"{values[k]:.5g} ({errs[k]:+.2f} %)"
                )
                for k in range(MODE_COUNT)
            ]
        lines.append(f"| `{m}` | " + " | ".join(cells) + " |")
    return lines


def section(table: FrequencyTable) -> list[str]:
    """The report's Markdown on the natural frequencies of one scene."""
    density = table.density.describe("t/mm³")
    bodies = (
        f"; bodies without mass data ({', '.join(table.massless_bodies)}) are massless "
        "and carry only the flexure pieces each model lumps on them"
        if table.massless_bodies
        else ""
    )
    state = "the equilibrium under the scene's gravity" if table.gravity else "the undeformed state"
    lines = [
        f"### Natural frequencies against `{table.reference}`",
        "",
        f"The {MODE_COUNT} lowest natural frequencies (Hz) about {state}, as "
        f"`flexval modes --count {MODE_COUNT}` gives them, with {density}{bodies}; in "
        "parentheses each mode's error against the reference's mode of the same rank "
        "(— where a model has fewer modes).",
        "",
    ]
    lines += frequency_table(table) + [""]
    lines += [f"- `{f.model}`: modal analysis failed: {f.message}" for f in table.failures]
    return lines + ([""] if table.failures else [])
