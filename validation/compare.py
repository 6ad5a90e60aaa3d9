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

Displacements in mm, rotations in rad, results in percent.
"""

from __future__ import annotations

import tomllib
from importlib import resources

import numpy as np

from reducedmodels import LoadPath

METRICS = ("end_disp", "end_disp_vec", "end_rot", "path_disp", "path_rot")

#: paper model names -> flexval model ids
PAPER_MODELS = {"FEM100": "beam:100", "FEM20": "beam:20", "PRBM": "prbm", "DCMM1": "dcmm:1",
                "DCMM2": "dcmm:2", "DCMM3": "dcmm:3"}


def _on_reference_levels(model: LoadPath, ref: LoadPath) -> tuple[np.ndarray, ...]:
    lm, lr = np.asarray(model.load), np.asarray(ref.load)
    if lm.shape == lr.shape and np.allclose(lm, lr, rtol=1e-12, atol=0.0):
        return np.asarray(model.dx), np.asarray(model.dy), np.asarray(model.rotation)
    order = np.argsort(lm)
    return tuple(np.interp(lr, lm[order], np.asarray(v)[order])
                 for v in (model.dx, model.dy, model.rotation))


def errors(model: LoadPath, ref: LoadPath) -> dict[str, float]:
    """All :data:`METRICS` of ``model`` against ``ref``, in percent.

    Raises
    ------
    ValueError
        If the two paths are for different load cases, or the reference did not
        reach full load.
    """
    if model.load_case != ref.load_case:
        raise ValueError(f"load cases differ: {model.load_case!r} vs {ref.load_case!r}")
    if not ref.converged:
        raise ValueError(f"reference {ref.model} did not reach full load on {ref.load_case}")
    dx, dy, rot = _on_reference_levels(model, ref)
    rx, ry, rr = (np.asarray(v) for v in (ref.dx, ref.dy, ref.rotation))
    d_ref = np.hypot(rx, ry)
    vec_err = np.hypot(dx - rx, dy - ry)
    tiny = np.finfo(float).tiny
    return {
        "end_disp": 100 * abs(np.hypot(dx[-1], dy[-1]) - d_ref[-1]) / max(d_ref[-1], tiny),
        "end_disp_vec": 100 * vec_err[-1] / max(d_ref[-1], tiny),
        "end_rot": 100 * abs(rot[-1] - rr[-1]) / max(abs(rr[-1]), tiny),
        "path_disp": 100 * vec_err.max() / max(d_ref.max(), tiny),
        "path_rot": 100 * np.abs(rot - rr).max() / max(np.abs(rr).max(), tiny),
    }


def paper_results() -> dict:
    """The paper's Tables 2, 3, 5, 6 (percent differences from FEM100, seconds)."""
    text = resources.files("validation").joinpath("data", "paper_results.toml").read_text()
    return tomllib.loads(text)["paper_results"]


def paper_scene(scene: str) -> dict | None:
    """The paper's data for the scene named ``scene`` (None if the paper has none).

    Keys: ``load_cases`` (the columns), ``percent_table``, ``seconds_table``
    and optionally ``relative_rotations_figure`` (labels in the paper),
    ``percent_difference`` and ``seconds`` (the rows, see the data file).
    """
    return paper_results().get(scene)


def paper_percent(scene: str, load_cases: list[str] | None = None
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


def paper_seconds(scene: str, load_cases: list[str] | None = None
                  ) -> dict[str, dict[str, float]]:
    """The paper's run times as {model id: {load case: seconds}} ("-" skipped)."""
    data = paper_results()[scene]
    cases = load_cases or data["load_cases"]
    return {PAPER_MODELS[name]: {c: float(v) for c, v in zip(cases, row) if v != "-"}
            for name, row in data["seconds"].items()}
