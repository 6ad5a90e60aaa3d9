"""Planar rigid-body kinematics of points: the one home of the rotation R(theta).

A body's pose is q = (x, y, theta): the current position (mm) of its
reference point and its rotation (rad, counterclockwise) from the initial
configuration. A material point whose initial offset from the reference
point is ``rel`` (mm) is at ``x = (x, y) + R(theta) rel``. Connectors use
these maps to move their end nodes with the bodies and to transport forces
and tangents back to the poses (chain rule, including the second
derivative in theta); loads use them for forces at material points; plots
for drawing bodies. Every other layer imports them from here.

Two forms of the same map: numpy versions for arrays of points, and
:func:`rotate_xy` on two floats for the innermost loops of the models, where
small numpy arrays cost more than the algebra.

Units: mm, rad.
"""

from __future__ import annotations

import math

import numpy as np


def rotation(angle: float) -> np.ndarray:
    """Planar rotation matrix R(angle) (2, 2), angle in rad (counterclockwise)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def rotate(angle: float, v: np.ndarray) -> np.ndarray:
    """R(angle) v for one vector (2,) or many (m, 2), mm; angle in rad."""
    return np.asarray(v, float) @ rotation(angle).T


def rotate_xy(angle: float, x: float, y: float) -> tuple[float, float]:
    """R(angle) (x, y) on plain floats (mm, rad), for scalar inner loops."""
    c, s = math.cos(angle), math.sin(angle)
    return c * x - s * y, s * x + c * y


def place_points(pose: np.ndarray, rel: np.ndarray) -> np.ndarray:
    """Current positions p + R(theta) rel of material points (m, 2) of a body at ``pose``, mm."""
    return np.asarray(pose[:2], float) + rotate(pose[2], rel)


def rigid_points(pose: np.ndarray, rel: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions of material points of a body and their derivatives.

    Parameters
    ----------
    pose : array (3,)
        (x, y, theta) in mm, mm, rad.
    rel : array (m, 2)
        Initial offsets of the points from the reference point, mm.

    Returns
    -------
    x : array (m, 2)
        Current positions, mm.
    jac : array (m, 2, 3)
        dx/dpose.
    d2 : array (m, 2)
        d^2 x / dtheta^2 (= -R(theta) rel); all other second derivatives vanish.
    """
    c, s = np.cos(pose[2]), np.sin(pose[2])
    rr = np.column_stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]])
    m = rel.shape[0]
    jac = np.zeros((m, 2, 3))
    jac[:, 0, 0] = 1.0
    jac[:, 1, 1] = 1.0
    jac[:, 0, 2] = -rr[:, 1]
    jac[:, 1, 2] = rr[:, 0]
    return pose[:2] + rr, jac, -rr


def body_point(pose: np.ndarray, rel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position x = p + R(theta) rel of one material point and dx/dtheta, both (2,) mm.

    ``rel`` (2,) is the point's initial offset from the body's reference
    point; d^2x/dtheta^2 = -R(theta) rel follows as minus the rotated offset.
    """
    rx, ry = rotate_xy(float(pose[2]), float(rel[0]), float(rel[1]))
    return pose[:2] + np.array([rx, ry]), np.array([-ry, rx])
