"""Revolute joints (pins) as exact constraints with Lagrange multipliers.

A pin keeps the material point P of body a and the material point P of
body b together; their relative rotation is free. It is a connector of
:mod:`flexval.reducedmodels.core.system` whose two internal coordinates are (scaled)
Lagrange multipliers mu, and whose "energy" is the saddle function

    E = s mu . (x_a(P) - x_b(P)),      x(P) = p + R(theta) (P - ref),

so that dE/dmu = s c (the constraint, c = 0 at equilibrium) and
dE/dpose = +-s J^T mu (the constraint forces). Stationarity of the total
potential is then exactly the Lagrange (KKT) system; no penalty, so the
pin is rigid whatever the loads. The Hessian is exact, including the
theta-theta terms s mu . d2x/dtheta2 that rigid rotation brings in. It is
indefinite (zero mu-mu block), which the core's LU solves (dense, banded
and sparse, all pivoting; see :mod:`flexval.reducedmodels.core.tangent`) handle.

Why the scale s (N/mm): the core measures every non-angle coordinate as a
length and its residual as a force. With ``lambda = s mu`` the multiplier
coordinate mu is a length (mm) and its residual s c a force (N), so the
core's convergence test, its step bounds and the arc-length norm treat the
pin like every other unknown: the pin gap is converged to ``force_tol``
times (load / s), a fraction of a typical deflection, and the KKT matrix is
balanced (its constraint blocks are of the order of the stiffness blocks).
The default s is a characteristic bending stiffness of the mechanism
(geometric mean of EI / L^3 over its flexures); any positive s gives the
same solution.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math

import numpy as np

from flexval.geometry import Mechanism
from flexval.geometry.kinematics import rigid_points

from .connector import Connector


def characteristic_stiffness(mechanism: Mechanism) -> float:
    """Geometric mean of EI / L^3 over the flexures, N/mm (a cantilever's bending stiffness / 3).

    A flexure whose section varies takes 1 / (w L^2), w = ∫ ds / EI (the same for a uniform one).
    """
    logs = [math.log(_bending_scale(f, mechanism.material)) for f in mechanism.flexures]
    return math.exp(sum(logs) / len(logs))


def _bending_scale(flexure, material) -> float:
    """EI / L^3 of a flexure (N/mm), or 1 / (w L^2) where its section varies."""
    if flexure.section.is_uniform:
        return flexure.bending_stiffness(material) / flexure.shape.length**3
    from flexval.geometry.compliance import curve_compliance

    weight = curve_compliance(flexure.shape, flexure.section, material).ellipse.weight
    return 1.0 / (weight * flexure.shape.length**2)


class PinConnector(Connector):
    """A pin between ``body_a`` and ``body_b`` at ``point``
    (a :class:`~flexval.reducedmodels.core.connector.Connector`).

    Parameters
    ----------
    name : str
    body_a, body_b : str
        The two bodies (either may be the ground).
    point : array (2,)
        The pin's position in the undeformed configuration, mm.
    mechanism : Mechanism
        Supplies the bodies' reference points (and the default scale).
    stiffness : float, optional
        The multiplier scale s, N/mm (default :func:`characteristic_stiffness`).

    Notes
    -----
    Local coordinates are [pose_a, pose_b, mu] with mu (2,) in mm; the
    constraint force the pin exerts on body b is s mu (N), on body a -s mu
    (see :meth:`force_on_b`).
    """

    n_internal = 2
    n_multipliers = 2

    def __init__(
        self,
        name: str,
        body_a: str,
        body_b: str,
        point: np.ndarray,
        mechanism: Mechanism,
        stiffness: float | None = None,
    ):
        if body_a == body_b:
            raise ValueError(f"pin {name!r}: a pin must join two different bodies, got {body_a!r}")
        self.name = name
        self.bodies = (body_a, body_b)
        point = np.asarray(point, dtype=float)
        self._rel = [(point - mechanism.bodies[b].reference)[None] for b in self.bodies]
        self.stiffness = float(
            stiffness if stiffness is not None else characteristic_stiffness(mechanism)
        )
        if not (math.isfinite(self.stiffness) and self.stiffness > 0.0):
            raise ValueError(
                f"pin {name!r}: scale must be positive and finite, got {self.stiffness!r} N/mm"
            )
        self._point = point

    def rigid_directions(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Both directions at the pin's point (mm): a pin holds every translation there."""
        return [(self._point, np.array([1.0, 0.0])), (self._point, np.array([0.0, 1.0]))]

    def evaluate(
        self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Saddle 'energy' s mu.(x_a - x_b) (N mm), its gradient (8) and exact Hessian (8, 8)."""
        s = self.stiffness
        mu = np.asarray(internal, dtype=float)
        xa, ja, d2a = rigid_points(np.asarray(pose_a, float), self._rel[0])
        xb, jb, d2b = rigid_points(np.asarray(pose_b, float), self._rel[1])
        gap = xa[0] - xb[0]
        grad = np.empty(8)
        grad[0:3] = s * ja[0].T @ mu
        grad[3:6] = -s * jb[0].T @ mu
        grad[6:8] = s * gap
        hess = np.zeros((8, 8))
        hess[0:3, 6:8] = s * ja[0].T
        hess[3:6, 6:8] = -s * jb[0].T
        hess[6:8, 0:6] = hess[0:6, 6:8].T
        hess[2, 2] = s * mu @ d2a[0]
        hess[5, 5] = -s * mu @ d2b[0]
        return float(s * mu @ gap), grad, hess

    def force_on_b(self, internal: np.ndarray) -> np.ndarray:
        """Force (N) the pin exerts on body b (body a gets the opposite)."""
        return self.stiffness * np.asarray(internal, dtype=float)

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """The pin point as carried by body a and by body b, (2, 2) mm (equal when converged)."""
        xa, _, _ = rigid_points(np.asarray(pose_a, float), self._rel[0])
        xb, _, _ = rigid_points(np.asarray(pose_b, float), self._rel[1])
        return np.vstack([xa, xb])


def pin_connectors(mechanism: Mechanism) -> list[PinConnector]:
    """One :class:`PinConnector` per pin of ``mechanism``, with one shared scale."""
    if not mechanism.pins:
        return []
    s = characteristic_stiffness(mechanism)
    return [
        PinConnector(p.name, p.bodies[0], p.bodies[1], p.point, mechanism, stiffness=s)
        for p in mechanism.pins
    ]
