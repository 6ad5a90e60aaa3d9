"""Where a taper's slope makes beam theory's section integrals fall short of 2D elasticity.

The reduced models take a varying section's compliance from beam theory's integrals
∫ ds/EI(s), ∫ ds/EA(s) (and ∫ ds/(k G A(s)) with ``[shear]``). On a notch hinge that is
1-50 % too stiff (``benchmarks/calibrate_notch.py``): the contour turns steeply over a short,
deep section. A linear taper's contour has one slope, (h0 - h1) / (2 L) on each side; this
script measures what that slope costs against the continuum reference. A straight cantilever
of length L tapers from h0 at the clamp to h1 at its tip (mean thickness h = (h0 + h1) / 2),
loaded at the tip by a moment and, apart, a force across it, small enough (rotation about
1e-4 rad) for the response to be linear. ``beam:100`` and ``beam:100[shear]`` against
``continuum:2`` (plane stress), in tip rotation and deflection; the uniform leaf of the same
mean thickness (h0 / h1 = 1) gives the share that is not the slope's (shear, the clamp's
2D field). Then the tapered S-shaped spline of ``tests/scenes/spline_flexure.toml``.

Run from the repository root::

    python benchmarks/taper_slope.py      # about a minute

The table it prints is the one in ``docs/pages/models.md`` (tapers and splines).

Units: mm, N, N mm, MPa; slopes in rad.
"""

from __future__ import annotations

import sys
import time

LENGTH = 20.0  # mm
DEPTH = 5.0  # mm
YOUNG = 70000.0  # MPa; the ratios do not depend on it
POISSON = 0.33
ROTATION = 1e-4  # rad: the linear range
MEAN_OVER_LENGTH = (0.01, 0.025, 0.05, 0.1, 0.2)
TAPER_RATIOS = (1.0, 2.0, 4.0, 8.0)
MODELS = ("beam:100", "beam:100[shear]")
REFERENCE = "continuum:2"


def taper_scene(h0: float, h1: float, case: dict):
    """A straight cantilever from (0, 0) to (L, 0), thickness h0 at the clamp and h1 at the
    tip, with the one load case ``case``."""
    from flexval.geometry.scene import parse_scene

    data = {
        "name": "taper",
        "material": {"youngs_modulus": YOUNG, "poisson_ratio": POISSON},
        "section": {"depth": DEPTH, "thickness": h0},
        "ground": {"name": "ground", "points": [[0.0, 0.0]]},
        "target": {"body": "tip", "point": [LENGTH, 0.0]},
        "flexures": [
            {
                "name": "leaf",
                "bodies": ["ground", "tip"],
                "shape": "segment",
                "start": [0.0, 0.0],
                "end": [LENGTH, 0.0],
                "thickness": [h0, h1],
            }
        ],
        "load_cases": [case],
    }
    return parse_scene(data, f"<taper {h0:g} to {h1:g} mm>")


def tip_loads(mean: float) -> tuple[dict, dict]:
    """A tip moment and a tip force across the axis that turn a uniform leaf of thickness
    ``mean`` by about :data:`ROTATION`."""
    inertia = DEPTH * mean**3 / 12.0
    moment = ROTATION * YOUNG * inertia / LENGTH
    return (
        {"name": "moment", "kind": "moment", "body": "tip", "value": moment},
        {
            "name": "force",
            "kind": "force",
            "body": "tip",
            "point": [LENGTH, 0.0],
            "angle_deg": 90.0,
            "value": 2.0 * moment / LENGTH,
        },
    )


def taper_errors(mean_over_length: float, ratio: float) -> dict[str, float]:
    """Each model's relative error against the continuum on one taper: ``{model}
    moment rotation``, ``{model} force rotation``, ``{model} force deflection``."""
    import flexval

    mean = mean_over_length * LENGTH
    h1 = 2.0 * mean / (1.0 + ratio)
    out = {}
    for case in tip_loads(mean):
        scene = taper_scene(ratio * h1, h1, case)
        ref = flexval.run_model(scene, REFERENCE, case["name"], levels=2)
        for model in MODELS:
            lp = flexval.run_model(scene, model, case["name"], levels=2)
            out[f"{model} {case['name']} rotation"] = lp.rotation[-1] / ref.rotation[-1] - 1.0
            if case["name"] == "force":
                out[f"{model} force deflection"] = lp.dy[-1] / ref.dy[-1] - 1.0
    return out


def slope(mean_over_length: float, ratio: float) -> float:
    """A taper's contour slope (h0 - h1) / (2 L), rad."""
    mean = mean_over_length * LENGTH
    h1 = 2.0 * mean / (1.0 + ratio)
    return (ratio - 1.0) * h1 / (2.0 * LENGTH)


def spline_errors() -> dict[str, float]:
    """beam:100 and dcmm:4 against continuum:2 on the tapered spline flexure (its push)."""
    from pathlib import Path

    import flexval

    path = Path(__file__).resolve().parent.parent / "tests" / "scenes" / "spline_flexure.toml"
    scene = flexval.load_scene(str(path))
    ref = flexval.run_model(scene, REFERENCE, "push", levels=2)
    out = {}
    for model in ("beam:100", "dcmm:4"):
        lp = flexval.run_model(scene, model, "push", levels=2)
        out[f"{model} deflection"] = lp.dy[-1] / ref.dy[-1] - 1.0
        out[f"{model} rotation"] = lp.rotation[-1] / ref.rotation[-1] - 1.0
    return out


def main() -> int:
    start = time.perf_counter()
    print(f"Straight tapers, L = {LENGTH:g} mm, against {REFERENCE} (relative error, %)\n")
    print(
        "| h/L | h0/h1 | slope (rad) | moment: beam | force: beam rot. | force: beam defl. "
        "| force: [shear] defl. |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for mean in MEAN_OVER_LENGTH:
        for ratio in TAPER_RATIOS:
            e = taper_errors(mean, ratio)
            cells = [
                e["beam:100 moment rotation"],
                e["beam:100 force rotation"],
                e["beam:100 force deflection"],
                e["beam:100[shear] force deflection"],
            ]
            print(
                f"| {mean:g} | {ratio:g} | {slope(mean, ratio):.4f} | "
                + " | ".join(f"{100 * c:+.3f}" for c in cells)
                + " |",
                flush=True,
            )
    print("\nTapered spline flexure (push), against continuum:2 (relative error, %)\n")
    for name, value in spline_errors().items():
        print(f"- {name}: {100 * value:+.3f}")
    print(f"\n{time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
