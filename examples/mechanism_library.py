"""The canonical mechanisms built in: each driven by its prescribed motion, drawn and checked.

What it shows
-------------
* the built-in scenes a designer starts from (:data:`flexval.geometry.MECHANISM_SCENES`):
  a parallel leaf guide, a folded guide, three rotary hinges (a cross-axis pivot, a
  cartwheel hinge, a trapezoidal pivot turning about a remote centre) and a bistable
  truss;
* displacement control: each scene's first load case prescribes the motion of its
  shuttle (or top body, or apex), and the force or moment that holds it is the
  output (``LoadPath.drive_reactions``);
* each answer next to its textbook anchor: the guide's 24 EI / L^3 (its shuttle free
  to tilt on the leaves' axial compliance here: 0.1 % softer), the folded guide's
  12 EI / L^3, the hinges' 2 EI / L, 8 EI / L and 26 EI / L, the truss's snap-through
  force;
* :func:`flexval.plot.deformed` drawing each mechanism deformed over its outline,
  into one figure ``mechanisms.png``.

Units: mm, N, N mm, rad.

Run: ``python examples/mechanism_library.py``
"""

from __future__ import annotations

import math

import numpy as np

import flexval
from flexval.geometry import MECHANISM_SCENES, load_scene
from flexval.validation.outputs import use_file_backend

MODEL = "beam:100"
"""The model every mechanism is traced with (any family would do)."""


def anchor(name: str) -> tuple[str, float, float]:
    """(what, flexval's value, the closed form) of one mechanism, in the units named."""
    scene = load_scene(name)
    E = scene.mechanism.material.youngs_modulus
    section = scene.mechanism.flexures[0].section
    ei = E * section.inertia
    case = scene.load_cases[0]
    if name == "bistable_truss":
        path = flexval.run_model(scene, MODEL, case.name, levels=121)
        push = -np.asarray(path.drive_reactions)[:, 1]
        a, h0 = 50.0, 6.0
        push = push[-np.asarray(path.dy) < h0]  # before both bars are level: the snap
        w = np.linspace(0.0, 2 * h0, 120001)
        h = h0 - w
        exact = 2 * E * section.area * h * (1 / np.hypot(a, h) - 1 / math.hypot(a, h0))
        return "snap-through force, N", float(push.max()), float(exact.max())
    path = flexval.run_model(scene, MODEL, case.name, levels=41)
    first = np.asarray(path.drive_reactions[1])
    length = scene.mechanism.flexures[0].shape.length
    hinges = {"cross_pivot": 2.0, "cartwheel_hinge": 8.0, "trapezoid_pivot": 26.0}
    if name in hinges:  # K = factor EI / L, L the whole leaf
        whole = 2 * length if name == "cartwheel_hinge" else length  # its half-leaves
        return "turning stiffness, N mm/rad", first[2] / path.load[1], hinges[name] * ei / whole
    stiffness = first[0] / path.dx[1]
    guides = 1 if name == "parallel_guide" else 2  # guides in series
    return "primary stiffness, N/mm", stiffness, 24 * ei / length**3 / guides


def main() -> dict[str, float]:
    """Print each mechanism's anchor and draw them deformed; the relative errors."""
    use_file_backend()
    import matplotlib.pyplot as plt

    errors = {}
    print(f"{'mechanism':<16} {'what':<28} {MODEL:>10} {'closed form':>12} {'error':>8}")
    for name in MECHANISM_SCENES:
        what, value, exact = anchor(name)
        errors[name] = value / exact - 1.0
        print(f"{name:<16} {what:<28} {value:10.5g} {exact:12.5g} {errors[name]:8.2%}")
    fig, axes = plt.subplots(2, 3, figsize=(15, 10))
    for ax, name in zip(axes.ravel(), MECHANISM_SCENES):
        scene = load_scene(name)
        case = scene.load_cases[0].name
        path = flexval.run_model(scene, MODEL, case, record_poses=True, record_shapes=True)
        flexval.plot.deformed(scene, path, ax=ax)
        ax.title.set_fontsize(9)
    fig.tight_layout()
    fig.savefig("mechanisms.png", dpi=90)
    return errors


if __name__ == "__main__":
    main()
