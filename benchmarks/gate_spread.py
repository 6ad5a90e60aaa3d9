"""How far a legitimate change of the solver's path moves the gated error figures.

Run: ``python benchmarks/gate_spread.py``. Every reduced model of the gates
(``tests/test_accuracy_gates.py``) is traced again with other load sub-steps
and Newton tolerances, and the continuum reference likewise; the script prints
the largest change of any gated error figure (percentage points) against the
committed ``reports/paper/gates.json``. This spread is what the gates' margin
``GATE_TOL`` is set from. Units: error figures in percent.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from flexval.geometry import load_scene
from flexval.reducedmodels import SolverSettings, build_system, parse_model, solve_path
from flexval.reducedmodels.catalogue import LINEAR
from flexval.reducedmodels.models import solve_linear
from flexval.validation.studies.compare import errors

GATES = Path(__file__).resolve().parents[1] / "reports" / "paper" / "gates.json"
GATED = ("end_disp_vec", "end_rot", "path_disp", "path_rot")
#: (max_rotation_step rad, max_translation_step, error_tol): finer and coarser than the default
VARIANTS = ((0.05, 0.01, 1e-12), (0.5, 0.1, 1e-9))


def trace(scene, model: str, case: str, settings: SolverSettings):
    """The load path of ``model`` on ``case`` with the given solver settings."""
    spec = parse_model(model)
    load_case = scene.load_case(case)
    system = build_system(scene.mechanism, spec, settings=settings)
    if spec.model_family.has(LINEAR):
        return solve_linear(system, load_case, model=model)
    return solve_path(system, load_case, model=model)


def spread(variant: tuple[float, float, float]) -> tuple[float, float, int]:
    """Largest absolute (points) and relative change of a gated figure, and their number."""
    rot, trans, tol = variant
    settings = dataclasses.replace(
        SolverSettings(), max_rotation_step=rot, max_translation_step=trans, error_tol=tol
    )
    base = json.loads(GATES.read_text())
    paths: dict = {}
    worst_abs = worst_rel = 0.0
    count = 0
    for scene_name, refs in base.items():
        scene = load_scene(scene_name)
        for ref, models in refs.items():
            for model, per_case in models.items():
                for case, was in per_case.items():
                    if "continuum" in ref + model and case != "f+":
                        continue
                    for m in (model, ref):
                        if (scene_name, m, case) not in paths:
                            paths[scene_name, m, case] = trace(scene, m, case, settings)
                    got = errors(
                        paths[scene_name, model, case],
                        paths[scene_name, ref, case],
                        scene.mechanism.size(),
                    )
                    for metric in GATED:
                        change = abs(got[metric] - was[metric])
                        worst_abs = max(worst_abs, change)
                        worst_rel = max(worst_rel, change / max(was[metric], 1e-300))
                        count += 1
    return worst_abs, worst_rel, count


def main() -> None:
    for variant in VARIANTS:
        worst_abs, worst_rel, count = spread(variant)
        print(
            f"sub-step bounds {variant[0]} rad / {variant[1]} of size, error_tol {variant[2]:g}: "
            f"{count} figures, largest change {worst_abs:.2e} points ({worst_rel:.1e} relative)"
        )


if __name__ == "__main__":
    main()
