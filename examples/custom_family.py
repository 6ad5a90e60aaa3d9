"""Adding a model family in one module: a linear spring at each flexure's centre of elasticity.

What it shows
-------------
* the connector contract (:class:`reducedmodels.Connector`): a model of a
  flexure implements ``evaluate`` (energy N mm, gradient, Hessian over the
  two bodies' poses) and ``shape``; every other hook has a default;
* one registration in the model catalogue makes the family usable by id
  everywhere (``parse_model``, ``run_model``, the CLI, the cache);
* an independent check: this connector is the ellipse of elasticity written
  as a spring (paper Eqs. 1-5: compliance diag(w b^2, w a^2, w) at the
  centre of elasticity, along the ellipse axes) with *linearised* rigid
  motions, so its energy is quadratic in the poses. Under a pure moment (a
  load whose potential is linear too) the traced rotation is then exactly
  linear in the load and must equal the linear ``ee`` model's to round-off,
  whatever the rotation; the target point's displacement differs from
  ``ee``'s, which linearises the rigid motion of that point too. The
  family's *linear* response (``flexval.reducedmodels.models.trace_linear``, the
  runner of ``ee``) must equal ``ee``'s under any load, displacements
  included: that checks that the DCMM connector's tangent at rest is the
  ellipse's stiffness.

A straight flexure has b = 0 (it does not stretch): this spring would be
infinitely stiff, so the connector refuses it with a ValueError, which the
catalogue turns into an input error naming the flexure.

Units: mm, N, N mm, rad.

Run: ``python examples/custom_family.py``
"""

from __future__ import annotations

import numpy as np

from flexval.geometry import Flexure, Mechanism, load_scene
from flexval.reducedmodels import (
    Connector,
    Family,
    ModelSpec,
    SolverSettings,
    System,
    parse_model,
    register,
)
from flexval.reducedmodels.catalogue import unregister
from flexval.reducedmodels.models import connector_system, trace_linear, trace_nonlinear
from flexval.validation.run import run_model


class EllipseSpring(Connector):
    """Linear spring between two bodies: the flexure's ellipse of elasticity, small rotations.

    The relative displacement of the centre of elasticity C (as a point of
    each body, rotations linearised) and the relative rotation, expressed
    along the ellipse axes, are resisted by the inverse of the compliance
    diag(w b^2, w a^2, w) (mm/N, mm/N, 1/(N mm)).
    """

    def __init__(self, flexure: Flexure, mechanism: Mechanism):
        self.name, self.bodies = flexure.name, tuple(flexure.bodies)
        ell = flexure.shape.ellipse(flexure.bending_stiffness(mechanism.material))
        if ell.b <= 0.0:
            raise ValueError("the ellipse-spring needs an arc (a straight flexure has b = 0)")
        refs = [mechanism.bodies[b].reference for b in self.bodies]
        # rows: (u . e1, u . e2, rotation) of body b relative to body a, per unit of each pose
        jac = []
        for sign, ref in zip((-1.0, 1.0), refs):
            arm = ell.center - ref
            moves = np.array([[1.0, 0.0, -arm[1]], [0.0, 1.0, arm[0]]])  # dC/d(x, y, theta)
            jac.append(sign * np.vstack([ell.axes.T @ moves, [0.0, 0.0, 1.0]]))
        self.jacobian = np.hstack(jac)  # (3, 6)
        self.rest = np.concatenate([[*refs[0], 0.0], [*refs[1], 0.0]])
        stiffness = np.diag(1.0 / np.diag(ell.compliance()))
        self.hessian = self.jacobian.T @ stiffness @ self.jacobian

    def evaluate(self, pose_a, pose_b, internal):
        """Energy (N mm), gradient and the constant Hessian over the two poses."""
        g = self.hessian @ (np.concatenate([pose_a, pose_b]) - self.rest)
        return 0.5 * g @ (np.concatenate([pose_a, pose_b]) - self.rest), g, self.hessian

    def shape(self, pose_a, pose_b, internal) -> np.ndarray:
        """The two body reference points, mm (a spring has no centre line)."""
        return np.array([pose_a[:2], pose_b[:2]])


def _system(
    mechanism: Mechanism, spec: ModelSpec, settings: SolverSettings | None = None, **options
) -> System:
    return connector_system(mechanism, spec, lambda f, m, s: EllipseSpring(f, m), settings, options)


ELLIPSE_SPRING = Family(
    "ellipse-spring",
    "linear spring at each flexure's centre of elasticity",
    trace_nonlinear,
    system=_system,
)


def main() -> dict[str, float]:
    """Register the family, run it on the open chain's m+ case, compare with ee and beam:100.

    Returns the relative difference of the end rotation of the spring
    against ``ee`` and against ``beam:100``, and of its linear end
    displacement under the f+ force against ``ee``'s (dimensionless).
    """
    register(ELLIPSE_SPRING)
    try:
        scene = load_scene("open_chain")
        case = scene.load_case("m+")
        paths = {
            m: run_model(scene, parse_model(m), case) for m in ("ellipse-spring", "ee", "beam:100")
        }
        force = scene.load_case("f+")
        linear = trace_linear(scene.mechanism, parse_model("ellipse-spring"), force)
        ee_force = run_model(scene, parse_model("ee"), force)
    finally:
        unregister(ELLIPSE_SPRING.name)

    def rotation(m: str) -> float:
        return paths[m].rotation[-1]

    spring = rotation("ellipse-spring")
    out = {
        "rotation vs ee": abs(spring - rotation("ee")) / abs(rotation("ee")),
        "rotation vs beam:100": abs(spring - rotation("beam:100")) / abs(rotation("beam:100")),
        "linear f+ vs ee": float(
            np.hypot(linear.dx[-1] - ee_force.dx[-1], linear.dy[-1] - ee_force.dy[-1])
            / np.hypot(ee_force.dx[-1], ee_force.dy[-1])
        ),
    }
    for model in ("ellipse-spring", "ee", "beam:100"):
        p = paths[model]
        print(
            f"{model:<15} dx {p.dx[-1]:9.4f} mm  dy {p.dy[-1]:9.4f} mm  "
            f"rot {p.rotation[-1]:8.5f} rad"
        )
    for k, v in out.items():
        print(f"ellipse-spring {k}: {v:.2e} (relative)")
    return out


if __name__ == "__main__":
    main()
