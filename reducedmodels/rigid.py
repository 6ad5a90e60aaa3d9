"""Exact large-rotation kinematics of material points on planar rigid bodies.

A body's pose is q = (x, y, theta): the current position (mm) of its
reference point and its rotation (rad) from the initial configuration.
A material point whose initial offset from the reference point is ``rel``
(mm) is at ``x = (x, y) + R(theta) rel``. Connectors use these maps to move
their end nodes with the bodies and to transport forces and tangents back
to the poses (chain rule, including the second derivative in theta).
"""

from __future__ import annotations

import numpy as np


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
