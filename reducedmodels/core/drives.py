"""Displacement control: a body point's prescribed motion as an exact, load-scaled constraint.

A :class:`flexval.geometry.Displacement` prescribes, at load factor lambda,
the motion lambda d_u along the frame direction e_u, lambda d_v along
e_v (e_u turned by +90 degrees) of the material point P of body b, and
the body's rotation lambda d_theta; any of them may be free. It is a
connector between the ground (a) and b with one scaled Lagrange
multiplier mu_i per prescribed component and the saddle function of a
pin (:mod:`flexval.reducedmodels.core.joints`) restricted to those components,

    E = s sum_i mu_i c_i,   c_u = e_u . (x_a(P) - x_b(P)),   c_v likewise,
                           c_theta = l (theta_a - theta_b),

with l the mechanism's size (so that every mu_i is a length and every
residual a force). The motion enters as a load on the multipliers: the
potential -lambda m . mu with m_i = -s d_i (-s l d_theta) makes
stationarity in mu_i read c_i = -lambda d_i, which is the prescribed
motion, while the poses see the constraint forces. So the load factor
drives the motion through the core's one load machinery: load control,
arc length (through snap-through and snap-back), stability and batches
are unchanged. The force the drive applies to b at P is s sum mu_i e_i
(N) and its moment s l mu_theta (N mm): the reaction a designer asks for.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math

import numpy as np

from flexval.geometry import Displacement, LoadCase, Mechanism, SceneError
from flexval.geometry.kinematics import rigid_points

from .connector import Connector
from .joints import characteristic_stiffness, pin_connectors


class DriveConnector(Connector):
    """The exact constraint of a :class:`~flexval.geometry.Displacement` (a connector).

    Parameters
    ----------
    drive : Displacement
        The prescribed motion (its body is b; the ground is a).
    mechanism : Mechanism
        Supplies the ground, the bodies' reference points, the size l (mm) and
        the default scale.
    stiffness : float, optional
        The multiplier scale s, N/mm (default
        :func:`~flexval.reducedmodels.core.joints.characteristic_stiffness`).

    Notes
    -----
    Local coordinates are [pose_ground, pose_b, mu] with one mu (mm) per
    prescribed component, in the order dx, dy, rotation.
    """

    name = "drive"

    def __init__(self, drive: Displacement, mechanism: Mechanism, stiffness: float | None = None):
        if drive.body == mechanism.ground:
            raise ValueError(f"drive: the driven body {drive.body!r} is the ground")
        self.drive = drive
        self.bodies = (mechanism.ground, drive.body)
        point = np.asarray(drive.point, dtype=float)
        self._rel = [(point - mechanism.bodies[b].reference)[None] for b in self.bodies]
        self.components = [k for k, _ in drive.prescribed]
        self.n_internal = self.n_multipliers = len(self.components)
        self.length = float(mechanism.size())
        self.stiffness = float(
            stiffness if stiffness is not None else characteristic_stiffness(mechanism)
        )
        if not (math.isfinite(self.stiffness) and self.stiffness > 0.0):
            raise ValueError(f"drive: scale must be positive and finite, got {self.stiffness!r}")
        c, s = math.cos(drive.angle), math.sin(drive.angle)
        self._axes = np.array([[c, s], [-s, c]])  # e_u, e_v as rows

    def multiplier_loads(self) -> np.ndarray:
        """m (N) per multiplier: the load on mu whose factor lambda prescribes the motion."""
        scale = np.array([self.stiffness, self.stiffness, self.stiffness * self.length])
        values = np.array([v for _, v in self.drive.prescribed])
        return -scale[self.components] * values

    def evaluate(
        self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Saddle 'energy' s mu . c (N mm), its gradient (6 + k) and exact Hessian."""
        s, k = self.stiffness, self.n_internal
        mu = np.asarray(internal, dtype=float)
        xa, ja, d2a = rigid_points(np.asarray(pose_a, float), self._rel[0])
        xb, jb, d2b = rigid_points(np.asarray(pose_b, float), self._rel[1])
        # the constraints' gradients in (pose_a, pose_b): rows c_i
        rows = np.zeros((k, 6))
        values = np.zeros(k)
        for i, component in enumerate(self.components):
            if component < 2:
                e = self._axes[component]
                rows[i, 0:3] = e @ ja[0]
                rows[i, 3:6] = -(e @ jb[0])
                values[i] = e @ (xa[0] - xb[0])
            else:
                rows[i, 2], rows[i, 5] = self.length, -self.length
                values[i] = self.length * (pose_a[2] - pose_b[2])
        grad = np.empty(6 + k)
        grad[:6] = s * mu @ rows
        grad[6:] = s * values
        hess = np.zeros((6 + k, 6 + k))
        hess[:6, 6:] = s * rows.T
        hess[6:, :6] = s * rows
        force = self._force_direction(mu)  # sum over translations of mu_i e_i
        hess[2, 2] = s * force @ d2a[0]
        hess[5, 5] = -s * force @ d2b[0]
        return float(s * mu @ values), grad, hess

    def _force_direction(self, mu: np.ndarray) -> np.ndarray:
        """sum_i mu_i e_i over the prescribed translations (mm)."""
        total = np.zeros(2)
        for m, component in zip(mu.tolist(), self.components):
            if component < 2:
                total += m * self._axes[component]
        return total

    def reaction(self, internal: np.ndarray) -> np.ndarray:
        """[Fx, Fy, M]: the force (N) and moment (N mm, about the driven point) the drive
        applies to the driven body."""
        mu = np.asarray(internal, dtype=float)
        force = self.stiffness * self._force_direction(mu)
        moment = sum(
            self.stiffness * self.length * m
            for m, component in zip(mu.tolist(), self.components)
            if component == 2
        )
        return np.array([force[0], force[1], float(moment)])

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """The driven point as carried by the driven body, (1, 2) mm."""
        xb, _, _ = rigid_points(np.asarray(pose_b, float), self._rel[1])
        return xb


def drive_connectors(mechanism: Mechanism) -> list[DriveConnector]:
    """The :class:`DriveConnector` of ``mechanism``'s drive, if it has one (with the pins'
    scale)."""
    if mechanism.drive is None:
        return []
    return [DriveConnector(mechanism.drive, mechanism)]


def constraint_connectors(mechanism: Mechanism) -> list[Connector]:
    """The exact constraints every model of ``mechanism`` joins: its pins, then its drive."""
    return [*pin_connectors(mechanism), *drive_connectors(mechanism)]


def refuse_prescribed_motion(case: LoadCase | None, source: str, field: str, what: str) -> None:
    """Raise SceneError where ``case`` prescribes a motion and ``what`` (a command that
    perturbs a state under dead loads: buckling factors, the stiffness or the modes about
    a preloaded state) cannot take one; ``source`` and ``field`` name where it was asked.

    Raises
    ------
    SceneError
        Naming the load case and what to use instead.
    """
    if case is not None and case.drive is not None:
        raise SceneError(
            source,
            field,
            case.name,
            f"load case {case.name!r} prescribes a motion (displacement control); {what} "
            "takes a case of forces and moments (trace the prescribed motion with "
            "'flexval run', --arclength through a snap-through)",
        )
