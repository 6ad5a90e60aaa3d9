"""Displaced Compliance Matrix Method, DCMM_n (paper Sects. 2.3 and 3).

Each flexure is cut into n equal sub-arcs joined by n - 1 intermediate rigid
bodies (the rigid cross-sections at the cuts). Each sub-arc is its diagonal
compliance diag(w b^2, w a^2, w) at its centre of elasticity C, along its
ellipse axes (Eqs. 1-5). It acts between the two bodies it joins in the
*displaced* configuration (Eqs. 9-14): the relative displacement of the
follower's material point at C, measured in the displaced frame of the
leading body (the one nearer to body i of flexure e_ij), and the relative
rotation, are the arguments of the quadratic energy

    E = 1/2 u^T diag(1/(w b^2), 1/(w a^2), 1/w) u,
    u = [Q^T R(theta_L)^T (p_F(C) - p_L(C)),  theta_F - theta_L].

Forces follow as its gradient, so the element is conservative and its
tangent is exact and symmetric. For a straight sub-arc (b = 0) the axial
compliance L/EA replaces the vanishing w b^2.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import numpy as np

from geometry import Flexure, Mechanism

_J = np.array([[0.0, -1.0], [1.0, 0.0]])


def _rot(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s], [s, c]])


def sub_arc_energy(pose_l: np.ndarray, pose_f: np.ndarray, r_l: np.ndarray, r_f: np.ndarray,
                   axes: np.ndarray, stiffness: np.ndarray
                   ) -> tuple[float, np.ndarray, np.ndarray]:
    """Energy, gradient (6) and Hessian (6, 6) of one displaced compliance element.

    Parameters
    ----------
    pose_l, pose_f : array (3,)
        Poses of the leading and following bodies (mm, mm, rad).
    r_l, r_f : array (2,)
        Initial offsets of the centre of elasticity from each body's reference point, mm.
    axes : array (2, 2)
        Ellipse axes e1, e2 as columns (initial configuration).
    stiffness : array (3,)
        Inverse of the diagonal compliance, (N/mm, N/mm, N mm).
    """
    A = _rot(-pose_l[2])
    Rphi = _rot(pose_f[2] - pose_l[2])
    d = pose_f[:2] - pose_l[:2]
    Rr = Rphi @ r_f
    v = A @ d + Rr - r_l                       # relative displacement, leader frame
    u = np.array([*(axes.T @ v), pose_f[2] - pose_l[2]])
    ku = stiffness * u
    energy = 0.5 * float(u @ ku)
    # dv/dq, q = [xL, yL, thL, xF, yF, thF]
    dv = np.zeros((2, 6))
    AJd = A @ _J @ d
    RJr = Rphi @ _J @ r_f
    dv[:, 0:2] = -A
    dv[:, 2] = -AJd - RJr
    dv[:, 3:5] = A
    dv[:, 5] = RJr
    du = np.zeros((3, 6))
    du[:2] = axes.T @ dv
    du[2, 2], du[2, 5] = -1.0, 1.0
    grad = du.T @ ku
    hess = du.T @ (stiffness[:, None] * du)
    lam = axes @ ku[:2]                        # force on the follower, leader frame
    AJ = A @ _J
    h = np.zeros((6, 6))
    h[2, 2] = lam @ (-(A @ d) - Rr)
    h[2, 5] = h[5, 2] = lam @ Rr
    h[5, 5] = -(lam @ Rr)
    h[2, 3:5] = h[3:5, 2] = -(lam @ AJ)
    h[2, 0:2] = h[0:2, 2] = lam @ AJ
    return energy, grad, hess + h


class DcmmConnector:
    """DCMM_n model of one flexure (a connector for :mod:`reducedmodels.core`).

    Internal coordinates are the poses of the n - 1 intermediate bodies,
    whose reference points are the cut points on the centre line.
    """

    def __init__(self, flexure: Flexure, mechanism: Mechanism, n: int):
        if n < 1:
            raise ValueError(f"dcmm: number of sub-arcs must be >= 1, got {n}")
        self.name = flexure.name
        self.bodies = tuple(flexure.bodies)
        self.n_internal = 3 * (n - 1)
        EI = flexure.bending_stiffness(mechanism.material)
        EA = flexure.axial_stiffness(mechanism.material)
        parts = flexure.shape.split(n)
        forward = flexure.start_body == self.bodies[0]   # chain runs start -> end
        if not forward:
            parts = parts[::-1]
        # chain of reference points: body a, cuts (in chain order), body b
        cuts = [p.end_points[1] if forward else p.end_points[0] for p in parts[:-1]]
        refs = [mechanism.bodies[self.bodies[0]].reference, *cuts,
                mechanism.bodies[self.bodies[1]].reference]
        self._cuts = np.array(cuts).reshape(-1, 2)
        self._elements = []
        for k, part in enumerate(parts):
            ell = part.ellipse(EI)
            c = ell.compliance().diagonal().copy()
            if ell.b == 0.0:
                c[0] = part.length / EA
            self._elements.append((ell.center - refs[k], ell.center - refs[k + 1], ell.axes,
                                   1.0 / c))
        self._ends = np.array([flexure.end_point_of(self.bodies[0]),
                               flexure.end_point_of(self.bodies[1])])
        self._ref_ends = np.array([refs[0], refs[-1]])

    def initial_internal(self) -> np.ndarray:
        """Cut-point bodies at rest: (x, y, 0) each."""
        return np.column_stack([self._cuts, np.zeros(len(self._cuts))]).ravel()

    def internal_is_rotation(self) -> np.ndarray:
        """Every third internal coordinate is an angle."""
        return np.tile([False, False, True], len(self._cuts))

    def _chain(self, pose_a, pose_b, internal) -> list[np.ndarray]:
        return [pose_a, *internal.reshape(-1, 3), pose_b]

    def evaluate(self, pose_a, pose_b, internal):
        """Energy (N mm), gradient and dense Hessian over [pose_a, pose_b, internal]."""
        chain = self._chain(pose_a, pose_b, internal)
        n = 6 + self.n_internal
        # local slot of each chain body: a -> 0..2, b -> 3..5, cut k -> 6 + 3k
        slots = [np.arange(0, 3)] + [np.arange(6 + 3 * k, 9 + 3 * k)
                                     for k in range(len(self._cuts))] + [np.arange(3, 6)]
        energy, grad, hess = 0.0, np.zeros(n), np.zeros((n, n))
        for k, (r_l, r_f, axes, kdiag) in enumerate(self._elements):
            e, g, h = sub_arc_energy(chain[k], chain[k + 1], r_l, r_f, axes, kdiag)
            idx = np.concatenate([slots[k], slots[k + 1]])
            energy += e
            grad[idx] += g
            hess[np.ix_(idx, idx)] += h
        return energy, grad, hess

    def shape(self, pose_a, pose_b, internal) -> np.ndarray:
        """Polyline through the flexure ends and the cut points, mm."""
        chain = self._chain(pose_a, pose_b, internal)
        pts = []
        for k, pose in enumerate(chain):
            if k == 0 or k == len(chain) - 1:
                end = self._ends[0 if k == 0 else 1]
                ref = self._ref_ends[0 if k == 0 else 1]
                pts.append(pose[:2] + _rot(pose[2]) @ (end - ref))
            else:
                pts.append(pose[:2])
        return np.array(pts)
