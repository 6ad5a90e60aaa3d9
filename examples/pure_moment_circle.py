"""A straight flexure under an end moment bends into a circle: beam:N against the closed form.

What it shows
-------------
* building a mechanism in Python (no scene file): one straight flexure
  clamped to the ground, its free end a rigid body ``"tip"``;
* asking the model catalogue for a model by id (``beam:N``);
* the one path tracer as a generator: :func:`reducedmodels.trace` yields
  every converged state and the caller records what it needs (here the
  tip's pose at each requested load level);
* the closed form it must meet: a moment M on a straight cantilever of
  length L and bending stiffness EI gives the constant curvature
  kappa = M / EI, so the tip turns by phi = M L / EI and sits at
  (sin(phi) / kappa, (1 - cos(phi)) / kappa) from the clamp.

The beam elements are exact for constant curvature except for their chord
approximation of the arc, so the error falls as 1/N^2 (the run prints it).

Units: mm, N, N mm, rad.

Run: ``python examples/pure_moment_circle.py``
"""

from __future__ import annotations

import numpy as np

from flexval.geometry import LoadCase, Material, Moment, Section, Segment
from flexval.geometry.mechanism import FlexureSpec, assemble
from flexval.reducedmodels import LoadControl, build_system, parse_model, trace

LENGTH = 20.0  # mm
SECTION = Section(1.0, 0.2)  # depth b, thickness h (mm)
MATERIAL = Material(2100.0, 0.35)
TURN = np.pi / 2  # tip rotation asked for at full load, rad


def cantilever():
    """A straight flexure along x from the ground (at the origin) to the body 'tip'."""
    spec = FlexureSpec(
        "f", Segment((0.0, 0.0), (LENGTH, 0.0)), ("ground", "tip"), SECTION, start_body="ground"
    )
    return assemble(
        [spec], "ground", np.array([[0.0, 0.0]]), MATERIAL, "tip", np.array([LENGTH, 0.0])
    )


def tip_path(model: str, levels: int = 5) -> list[tuple[float, np.ndarray]]:
    """(moment in N mm, tip pose (x, y, theta)) at each load level, traced by ``model``."""
    mech = cantilever()
    ei = MATERIAL.youngs_modulus * SECTION.inertia
    moment = ei * TURN / LENGTH
    case = LoadCase("M", (Moment("tip", moment),), levels)
    system = build_system(mech, parse_model(model))
    loads = system.loads(case)
    return [
        (point.factor * moment, system.pose(point.state, "tip").copy())
        for point in trace(system, loads, LoadControl(case.factors()))
    ]


def closed_form(moment: float) -> np.ndarray:
    """Tip pose (x, y, theta) of the pure-moment circle, mm and rad."""
    ei = MATERIAL.youngs_modulus * SECTION.inertia
    phi = moment * LENGTH / ei
    if phi == 0.0:
        return np.array([LENGTH, 0.0, 0.0])
    kappa = phi / LENGTH
    return np.array([np.sin(phi) / kappa, (1.0 - np.cos(phi)) / kappa, phi])


def tip_error(model: str) -> float:
    """Largest tip position error along the path, relative to the length (dimensionless)."""
    return max(
        float(np.hypot(*(pose - closed_form(m))[:2])) / LENGTH for m, pose in tip_path(model)
    )


def main() -> dict[int, float]:
    """Print and return the tip error of beam:N for N = 5, 10, 20, 40."""
    errors = {n: tip_error(f"beam:{n}") for n in (5, 10, 20, 40)}
    print(f"{'model':<9} {'tip error / L':>14} {'order':>6}")
    previous = None
    for n, err in errors.items():
        order = "" if previous is None else f"{np.log2(previous / err):6.2f}"
        print(f"beam:{n:<4} {err:14.3e} {order:>6}")
        previous = err
    return errors


if __name__ == "__main__":
    main()
