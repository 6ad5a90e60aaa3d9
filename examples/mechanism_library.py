"""The canonical mechanisms built in: each driven by its prescribed motion, drawn and checked.

What it shows
-------------
* the built-in scenes a designer starts from (:data:`flexval.geometry.MECHANISM_SCENES`):
  a parallel leaf guide, a folded guide, three rotary hinges (a cross-axis pivot, a
  cartwheel hinge, a trapezoidal pivot turning about a remote centre), a bistable
  truss, a fully compliant bistable arch (drawn from its arc-length trace through the
  snap) and a notch-hinge bridge amplifier;
* displacement control: each scene's first load case prescribes the motion of its
  shuttle (or top body, or apex), and the force or moment that holds it is the
  output (``LoadPath.drive_reactions``);
* each answer next to its textbook anchor: the guide's 24 EI / L^3 (its shuttle free
  to tilt on the leaves' axial compliance here: 0.1 % softer), the folded guide's
  12 EI / L^3, the hinges' stiffness by Wittrick's formula (2 EI / L, 8 EI / L and
  26 EI / L), the truss's snap-through force, the amplifier's cot(alpha) / 2 of ideal
  pivots (its notches' axial compliance takes 1.6 % off);
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


def wittrick(scene) -> float:
    """The rotational stiffness (N mm/rad) of a pivot's leaves turning about its target
    point: each leaf's moving end turns about a point c L from it along the leaf (c from
    the geometry), k = (EI / L) (12 c^2 - 12 c + 4) (Wittrick 1948), summed. A cartwheel's
    half-leaves meet at its hub, which turns half as far: a quarter of their sum."""
    mech = scene.mechanism
    total = 0.0
    for f in mech.flexures:
        start, end = (np.asarray(p, float) for p in f.shape.end_points)
        fixed, moving = (start, end) if f.bodies[0] == mech.ground else (end, start)
        length = math.dist(fixed, moving)
        if "hub" in f.bodies:  # the cartwheel's half-leaf: its ends turn theta / 2 apart,
            # the hub staying on the axis: (4 EI / L) (1/2)^2
            total += mech.material.youngs_modulus * f.section.inertia / length
            continue
        centre = np.asarray(mech.target_point, float)
        c = float((centre - moving) @ (fixed - moving)) / length**2
        ei = mech.material.youngs_modulus * f.section.inertia
        total += ei / length * (12 * c**2 - 12 * c + 4)
    return total


def anchor(name: str) -> tuple[str, float, float]:
    """(what, flexval's value, the closed form) of one mechanism, in the units named."""
    scene = load_scene(name)
    E = scene.mechanism.material.youngs_modulus
    section = scene.mechanism.flexures[0].section
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
    if name == "bridge_amplifier":  # the top block's motion across per unit stroke
        h1, h2 = (np.add(*f.shape.end_points) / 2 for f in scene.mechanism.flexures[:2])
        alpha = math.atan2(h2[1] - h1[1], h2[0] - h1[0])
        return "amplification (ideal pivots)", -path.dy[1] / path.load[1], 0.5 / math.tan(alpha)
    if name in ("cross_pivot", "cartwheel_hinge", "trapezoid_pivot"):
        return "turning stiffness, N mm/rad", first[2] / path.load[1], wittrick(scene)
    length = scene.mechanism.flexures[0].shape.length
    stiffness = first[0] / path.dx[1]
    guides = 1 if name == "parallel_guide" else 2  # guides in series
    return "primary stiffness, N/mm", stiffness, 24 * E * section.inertia / length**3 / guides


TRACED_PAST_A_BIFURCATION = ("bistable_arch",)
"""Scenes whose first case bifurcates: displacement control stops there, so they are drawn
from an arc-length trace switched onto the crossing branch (their anchor, shallow-arch
theory, is checked in ``tests/test_mechanism_library.py``)."""


def branch_trace(scene) -> flexval.LoadPath:
    """The arc-length trace of the first case, switched at the first bifurcation onto the
    crossing branch, to where the branch's motion turns back (mm, N)."""
    from flexval.reducedmodels import SolverError
    from flexval.validation.studies.limits import trace_arclength

    spec, case = flexval.parse_model(MODEL), scene.load_cases[0]
    try:
        return trace_arclength(
            scene, spec, case, record_poses=True, record_shapes=True, branch_switch=True
        )
    except SolverError as exc:  # it may wander off on its way back: the path so far
        return exc.path


def main() -> dict[str, float]:
    """Print each mechanism's anchor and draw them deformed; the relative errors."""
    use_file_backend()
    import matplotlib.pyplot as plt

    errors = {}
    print(f"{'mechanism':<16} {'what':<28} {MODEL:>10} {'closed form':>12} {'error':>8}")
    for name in MECHANISM_SCENES:
        if name in TRACED_PAST_A_BIFURCATION:
            continue
        what, value, exact = anchor(name)
        errors[name] = value / exact - 1.0
        print(f"{name:<16} {what:<28} {value:10.5g} {exact:12.5g} {errors[name]:8.2%}")
    fig, axes = plt.subplots(2, 4, figsize=(20, 10))
    for ax in axes.ravel()[len(MECHANISM_SCENES) :]:
        ax.set_axis_off()
    for ax, name in zip(axes.ravel(), MECHANISM_SCENES):
        scene = load_scene(name)
        case = scene.load_cases[0]
        if name in TRACED_PAST_A_BIFURCATION:
            path = branch_trace(scene)
        else:
            path = flexval.run_model(scene, MODEL, case, record_poses=True, record_shapes=True)
        flexval.plot.deformed(scene, path, ax=ax)
        ax.title.set_fontsize(9)
    fig.tight_layout()
    fig.savefig("mechanisms.png", dpi=90)
    return errors


if __name__ == "__main__":
    main()
