"""Error metrics between a model's LoadPath and a reference LoadPath.

Metrics (percent), all computed at matched load levels (the model's path is
interpolated linearly in the load onto the reference's levels when they
differ):

``end_disp``
    relative difference of the end-of-ramp displacement *magnitudes*,
    | |d_model| - |d_ref| | / |d_ref|  (the paper's "disp" column);
``end_disp_vec``
    relative error of the end-of-ramp displacement *vector*,
    |d_model - d_ref| / |d_ref|  (direction errors count too);
``end_rot``
    | rot_model - rot_ref | / | rot_ref | at the end of the ramp (the paper's "rot");
``path_disp``, ``path_rot``
    the largest error along the whole path normalised by the largest
    reference value, max_k |d_model,k - d_ref,k| / max_k |d_ref,k| (vector
    error), and likewise for the rotation. These catch a model that gets the
    end right but the soft stretch of a path wrong.

A reference value near zero would turn round-off into hundreds of percent, so each
quantity has a scale taken from the other one along the reference path (for the rotation
max_k |d_ref,k| / L, for the displacement max_k |rot_ref,k| L); below :data:`NEAR_ZERO`
times its scale, the error is reported in percent of the scale instead (:func:`scale_of`,
:func:`denominator`; why, with examples, in ARCHITECTURE.md, "Validation and outputs").
The size L is a required argument of :func:`errors`, so that every caller applies the one rule.

Displacements in mm, rotations in rad, lengths in mm, results in percent.
"""

from __future__ import annotations

import tomllib
from importlib import resources

import numpy as np

from flexval.reducedmodels import LoadPath

METRICS = ("end_disp", "end_disp_vec", "end_rot", "path_disp", "path_rot")

#: paper model names -> flexval model ids
PAPER_MODELS = {
    "FEM100": "beam:100",
    "FEM20": "beam:20",
    "PRBM": "prbm",
    "DCMM1": "dcmm:1",
    "DCMM2": "dcmm:2",
    "DCMM3": "dcmm:3",
}


def on_reference_levels(model: LoadPath, ref: LoadPath) -> tuple[np.ndarray, ...]:
    """``model``'s dx, dy (mm) and rotation (rad) at ``ref``'s loads (interpolated in load
    where the two paths' levels differ)."""
    lm, lr = np.asarray(model.load), np.asarray(ref.load)
    # np.allclose's test (rtol 1e-12, no atol) written out: a fifth of its cost per point
    if lm.shape == lr.shape and bool(np.all(np.abs(lm - lr) <= 1e-12 * np.abs(lr))):
        return np.asarray(model.dx), np.asarray(model.dy), np.asarray(model.rotation)
    order = np.argsort(lm)
    return tuple(
        np.interp(lr, lm[order], np.asarray(v)[order]) for v in (model.dx, model.dy, model.rotation)
    )


#: a reference value below this fraction of its scale is near zero (see the module
#: docstring): fifty times below the smallest of the paper's scenes (0.5)
NEAR_ZERO = 0.01


def scale_of(ref: LoadPath, length: float) -> dict[str, float]:
    """The scales of a reference path's displacement (mm) and rotation (rad).

    ``{"disp": max_k |rot_k| * length, "rot": max_k |d_k| / length}``, with
    ``length`` the mechanism's size (mm, :meth:`geometry.Mechanism.size`).
    """
    d = np.hypot(np.asarray(ref.dx), np.asarray(ref.dy))
    r = np.abs(np.asarray(ref.rotation))
    return {"disp": float(r.max()) * length, "rot": float(d.max()) / length}


def denominator(value: float, scale: float) -> float:
    """What an error in ``value`` is measured against: |value|, or ``scale`` when
    |value| is below :data:`NEAR_ZERO` times it (never zero).

    ``value`` and ``scale`` in the same unit (mm for a displacement, rad for a
    rotation); for quantities known only at the end of a ramp (e.g. a dynamic
    run's end state) with the scale of the matching static path.
    """
    v = abs(value)
    if v < NEAR_ZERO * scale:
        return scale
    return max(v, np.finfo(float).tiny)


def errors(model: LoadPath, ref: LoadPath, length: float) -> dict[str, float]:
    """All :data:`METRICS` of ``model`` against ``ref``, in percent.

    ``length`` (mm) is the mechanism's size (:meth:`geometry.Mechanism.size`):
    a reference value near zero is measured against its scale
    (:func:`scale_of`, :data:`NEAR_ZERO`), every other one against itself.

    Raises
    ------
    ValueError
        If ``length`` is not a positive finite number, the two paths are for
        different load cases, or the reference did not reach full load.
    """
    if not (isinstance(length, (int, float, np.floating)) and 0 < length < np.inf):
        raise ValueError(
            f"length must be the mechanism's size, a positive number of mm: {length!r}"
        )
    if model.load_case != ref.load_case:
        raise ValueError(f"load cases differ: {model.load_case!r} vs {ref.load_case!r}")
    if not ref.converged:
        raise ValueError(f"reference {ref.model} did not reach full load on {ref.load_case}")
    dx, dy, rot = on_reference_levels(model, ref)
    rx, ry, rr = (np.asarray(v) for v in (ref.dx, ref.dy, ref.rotation))
    d_ref = np.hypot(rx, ry)
    vec_err = np.hypot(dx - rx, dy - ry)
    scale = scale_of(ref, length)
    end_d, path_d = (denominator(v, scale["disp"]) for v in (d_ref[-1], d_ref.max()))
    end_r, path_r = (denominator(v, scale["rot"]) for v in (rr[-1], np.abs(rr).max()))
    return {
        "end_disp": 100 * abs(np.hypot(dx[-1], dy[-1]) - d_ref[-1]) / end_d,
        "end_disp_vec": 100 * vec_err[-1] / end_d,
        "end_rot": 100 * abs(rot[-1] - rr[-1]) / end_r,
        "path_disp": 100 * vec_err.max() / path_d,
        "path_rot": 100 * np.abs(rot - rr).max() / path_r,
    }


def paper_results() -> dict:
    """The paper's Tables 2, 3, 5, 6 (percent differences from FEM100, seconds)."""
    text = resources.files("flexval.validation").joinpath("data", "paper_results.toml").read_text()
    return tomllib.loads(text)["paper_results"]


def paper_scene(scene: str) -> dict | None:
    """The paper's data for the scene named ``scene`` (None if the paper has none).

    Keys: ``load_cases`` (the columns), ``percent_table``, ``seconds_table``
    and optionally ``relative_rotations_figure`` (labels in the paper),
    ``percent_difference`` and ``seconds`` (the rows, see the data file).
    """
    return paper_results().get(scene)


def paper_percent(
    scene: str, load_cases: list[str] | None = None
) -> dict[str, dict[str, dict[str, float]]]:
    """The paper's percentages as {model id: {load case: {"disp": %, "rot": %}}} ("-" skipped).

    ``load_cases`` name the columns (default: the data file's own).
    """
    data = paper_results()[scene]
    cases = load_cases or data["load_cases"]
    out: dict[str, dict[str, dict[str, float]]] = {}
    for name, row in data["percent_difference"].items():
        model = PAPER_MODELS[name]
        for k, case in enumerate(cases):
            disp, rot = row[2 * k], row[2 * k + 1]
            if disp == "-":
                continue
            out.setdefault(model, {})[case] = {"disp": float(disp), "rot": float(rot)}
    return out


def paper_seconds(scene: str, load_cases: list[str] | None = None) -> dict[str, dict[str, float]]:
    """The paper's run times as {model id: {load case: seconds}} ("-" skipped)."""
    data = paper_results()[scene]
    cases = load_cases or data["load_cases"]
    return {
        PAPER_MODELS[name]: {c: float(v) for c, v in zip(cases, row) if v != "-"}
        for name, row in data["seconds"].items()
    }
