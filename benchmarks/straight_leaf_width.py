"""The 3D stiffening of straight leaves clamped at both ends: the points ``[width]`` is fitted to.

A parallel leaf guide's stroke stiffness (the 3 x 3 compliance at its shuttle, the shuttle
free to tilt and shorten: 1 / C_xx) by the 3D solid ``continuum:1[3d]`` and by the
plane-stress beam ``beam:100``, over the leaf's depth-to-thickness ratio b / h (1 to 40)
and slenderness L / h (40 to 160); their ratio is the stiffening the clamps give a deep
leaf, which :data:`flexval.geometry.clampedleaf.CLAMP_DECAY` is fitted to. Two more
mechanisms check the fit beyond it: the folded guide (leaves bent as in the fit) and the
cross-axis pivot (leaves under a nearly uniform moment, where the fit is an estimate).
It writes ``reports/threed/straight_leaves.json`` (no timings) and prints the table::

    python benchmarks/straight_leaf_width.py          # about 8 minutes on 2 cores

Units: mm, N/mm, N mm/rad; ratios dimensionless.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from flexval.geometry import Scene, load_scene
from flexval.geometry.clampedleaf import CLAMP_DECAY, clamped_leaf_ratio
from flexval.geometry.scene import parse_scene, read_scene_data
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.cache import code_version
from flexval.validation.outputs import write_json
from flexval.validation.studies.stiffness import run_stiffness

SOLID = "continuum:1[3d]"
"""The 3D reference the fit is made against."""
PLANE = "beam:100"
"""Plane-stress beam theory (E I): within 0.03 % of ``continuum:1`` on these guides."""
LENGTH = 50.0
"""The leaves' length (mm); the parallel guide's 20 mm spacing is kept."""
GRID = [(40, r) for r in (1, 2, 5, 10, 20, 40)] + [(80, r) for r in (1, 2, 5, 10, 20, 40)]
GRID += [(160, r) for r in (2, 5, 10, 20)]
"""(L / h, b / h) of the fitted guides: the 3D mesh of a leaf of L / h = 160 and b / h = 40
does not fit the memory of a 2-core machine."""
CHECKS = (("folded_guide", 0), ("cross_pivot", 2))
"""Built-in mechanisms checked beyond the fit, with the target coordinate compared (0 dx, 2
rotation)."""


def guide(depth: float, thickness: float) -> Scene:
    """The built-in parallel guide with leaves of ``depth`` and ``thickness`` (mm)."""
    data = read_scene_data("parallel_guide")[1]
    data["section"]["depth"], data["section"]["thickness"] = depth, thickness
    for flexure in data["flexures"]:
        flexure["end"] = [flexure["end"][0], LENGTH]
    data["target"]["point"] = [10.0, LENGTH]
    return parse_scene(data, "<guide>")


def stiffness(scene: Scene, model: str, coordinate: int) -> float:
    """1 / C_ii at the target (N/mm or N mm/rad), the other coordinates free."""
    compliance = run_stiffness(scene, parse_model(model), None, 0.0)[1].compliance
    return float(1.0 / compliance[coordinate, coordinate])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("reports/threed"))
    args = ap.parse_args()
    code = code_version()
    rows = []
    print(f"{'L/h':>5} {'b/h':>5} {'3D / plane':>11} {'fit':>8} {'fit error':>10}")
    for slenderness, ratio in GRID:
        thickness = LENGTH / slenderness
        scene = guide(ratio * thickness, thickness)
        solid, plane = stiffness(scene, SOLID, 0), stiffness(scene, PLANE, 0)
        fit = clamped_leaf_ratio(ratio * thickness, LENGTH, scene.mechanism.material.poisson_ratio)
        rows.append({"L_h": slenderness, "b_h": ratio, "solid": solid, "plane": plane, "fit": fit})
        error = 100 * (fit / (solid / plane) - 1)
        print(f"{slenderness:5d} {ratio:5d} {solid / plane:11.4f} {fit:8.4f} {error:+9.2f} %")
    checks = []
    for name, coordinate in CHECKS:
        scene = load_scene(name)
        solid = stiffness(scene, SOLID, coordinate)
        width = stiffness(scene, f"{PLANE}[width]", coordinate)
        plane = stiffness(scene, PLANE, coordinate)
        checks.append(
            {
                "scene": name,
                "coordinate": coordinate,
                "solid": solid,
                "width": width,
                "plane": plane,
            }
        )
        print(
            f"{name}: {PLANE} {100 * (plane / solid - 1):+.2f} %, "
            f"{PLANE}[width] {100 * (width / solid - 1):+.2f} % against {SOLID}"
        )
    write_json(
        args.out / "straight_leaves.json",
        {
            "code_version": code,
            "solid": SOLID,
            "plane": PLANE,
            "length_mm": LENGTH,
            "clamp_decay": CLAMP_DECAY,
            "guides": rows,
            "checks": checks,
        },
    )


if __name__ == "__main__":
    main()
