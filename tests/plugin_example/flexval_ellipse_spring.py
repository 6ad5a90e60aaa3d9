"""A flexval model family in its own package: a spring at each flexure's centre of elasticity.

Importing this module registers the family ``ellipse-spring`` in flexval's
model catalogue; the package's ``pyproject.toml`` names the module in the
entry-point group ``flexval.families``, so flexval imports it the first time
an id names a family it does not know (``flexval run SCENE --model
ellipse-spring``, ``flexval gate``) and when ``flexval models`` lists every
family.

The model is the one of ``examples/custom_family.py``: the flexure's ellipse
of elasticity (compliance diag(w b^2, w a^2, w) at the centre of elasticity,
along the ellipse axes) as a spring between the two bodies, rigid motions
linearised, so its energy is quadratic in the poses. A straight flexure
(b = 0) is refused. Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import numpy as np

from flexval.geometry import Flexure, Mechanism
from flexval.reducedmodels import Connector, Family, ModelSpec, SolverSettings, System, register
from flexval.reducedmodels.models import connector_system, trace_nonlinear


class EllipseSpring(Connector):
    """Linear spring between two bodies: the flexure's ellipse of elasticity, small rotations."""

    def __init__(self, flexure: Flexure, mechanism: Mechanism):
        self.name, self.bodies = flexure.name, tuple(flexure.bodies)
        ell = flexure.shape.ellipse(flexure.bending_stiffness(mechanism.material))
        if ell.b <= 0.0:
            raise ValueError("the ellipse-spring needs an arc (a straight flexure has b = 0)")
        refs = [mechanism.bodies[b].reference for b in self.bodies]
        jac = []
        for sign, ref in zip((-1.0, 1.0), refs):
            arm = ell.center - ref
            moves = np.array([[1.0, 0.0, -arm[1]], [0.0, 1.0, arm[0]]])  # dC/d(x, y, theta)
            jac.append(sign * np.vstack([ell.axes.T @ moves, [0.0, 0.0, 1.0]]))
        jacobian = np.hstack(jac)  # (3, 6): relative motion along the axes, per pose unit
        self.rest = np.concatenate([[*refs[0], 0.0], [*refs[1], 0.0]])
        self.hessian = jacobian.T @ np.diag(1.0 / np.diag(ell.compliance())) @ jacobian

    def evaluate(self, pose_a, pose_b, internal):
        """Energy (N mm), gradient and the constant Hessian over the two poses."""
        u = np.concatenate([pose_a, pose_b]) - self.rest
        g = self.hessian @ u
        return 0.5 * g @ u, g, self.hessian

    def shape(self, pose_a, pose_b, internal) -> np.ndarray:
        """The two body reference points, mm (a spring has no centre line)."""
        return np.array([pose_a[:2], pose_b[:2]])


def _system(
    mechanism: Mechanism, spec: ModelSpec, settings: SolverSettings | None = None, **options
) -> System:
    return connector_system(mechanism, spec, lambda f, m, s: EllipseSpring(f, m), settings, options)


register(
    Family(
        "ellipse-spring",
        "linear spring at each flexure's centre of elasticity",
        trace_nonlinear,
        system=_system,
    )
)
