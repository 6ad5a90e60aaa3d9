"""Which model to trust on the paper's open chain: errors of every reduced model against beam:100.

What it shows
-------------
* loading a built-in scene and one of its load cases;
* running models by id through the catalogue (``flexval.validation.run.run_model``,
  the dispatcher behind ``flexval run``): any registered family, the
  continuum included, returns the same :class:`reducedmodels.LoadPath`;
* the paper's comparison in a few lines: the end displacement of the target
  point of each model relative to the converged beam model, next to its
  wall time.

On this load case (f+, 3 mN at 30 deg) the linear ellipse of elasticity
overshoots by tens of percent, DCMM improves as its arcs are split, and the
nonlinear beam converges to the reference; the run prints the table.

Units: mm, N, s.

Run: ``python examples/compare_models.py``
"""

from __future__ import annotations

import numpy as np

from flexval.geometry import load_scene
from flexval.reducedmodels import parse_model
from flexval.validation.run import run_model

MODELS = ("ee", "dcmm:1", "dcmm:2", "prbm", "beam:20")
REFERENCE = "beam:100"


def end_displacement(path) -> np.ndarray:
    """Target displacement (dx, dy) at full load, mm."""
    return np.array([path.dx[-1], path.dy[-1]])


def main(scene_name: str = "open_chain", case_name: str = "f+") -> dict[str, float]:
    """Print and return each model's relative end-displacement error against beam:100."""
    scene = load_scene(scene_name)
    case = scene.load_case(case_name)
    reference = end_displacement(run_model(scene, parse_model(REFERENCE), case))
    errors = {}
    print(f"{scene_name} {case_name}: |d| of {REFERENCE} = {np.linalg.norm(reference):.4f} mm")
    print(f"{'model':<9} {'|d| mm':>9} {'error %':>8} {'seconds':>8}")
    for model in MODELS:
        path = run_model(scene, parse_model(model), case)
        d = end_displacement(path)
        errors[model] = float(np.linalg.norm(d - reference) / np.linalg.norm(reference))
        print(f"{model:<9} {np.linalg.norm(d):9.4f} {100 * errors[model]:8.2f} {path.seconds:8.4f}")
    return errors


if __name__ == "__main__":
    main()
