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

import dataclasses
import math

import numpy as np

from geometry import Flexure, Mechanism

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

    Notes
    -----
    With A = R(-theta_L), phi = theta_F - theta_L and d = x_F - x_L, the
    relative displacement in the leader frame is v = A d + R(phi) r_F - r_L and
    u = (Q^T v, phi). Written with scalars: the 2x2 algebra is far cheaper in
    plain floats than in small numpy arrays, and this is the innermost loop.
    """
    xl, yl, tl = pose_l
    xf, yf, tf = pose_f
    ca, sa = math.cos(tl), math.sin(tl)          # A = R(-tl) = [[ca, sa], [-sa, ca]]
    phi = tf - tl
    cp, sp_ = math.cos(phi), math.sin(phi)
    dx, dy = xf - xl, yf - yl
    adx, ady = ca * dx + sa * dy, -sa * dx + ca * dy          # A d
    rfx, rfy = r_f
    rrx, rry = cp * rfx - sp_ * rfy, sp_ * rfx + cp * rfy      # R(phi) r_F
    vx, vy = adx + rrx - r_l[0], ady + rry - r_l[1]
    (q11, q12), (q21, q22) = axes                             # rows of Q
    u1, u2 = q11 * vx + q21 * vy, q12 * vx + q22 * vy          # Q^T v
    k1, k2, k3 = stiffness
    f1, f2, m = k1 * u1, k2 * u2, k3 * phi
    energy = 0.5 * (f1 * u1 + f2 * u2 + m * phi)
    # derivatives of v: A J d = (-ady, adx); R(phi) J r_F = (-rry, rrx)
    dv = np.array([
        [-ca, -sa, ady + rry, ca, sa, -rry],
        [sa, -ca, -adx - rrx, -sa, ca, rrx],
    ])
    du = np.empty((3, 6))
    du[:2] = axes.T @ dv
    du[2] = (0.0, 0.0, -1.0, 0.0, 0.0, 1.0)
    ku = np.array([f1, f2, m])
    grad = du.T @ ku
    hess = du.T @ (stiffness[:, None] * du)
    lx, ly = q11 * f1 + q12 * f2, q21 * f1 + q22 * f2         # Q K u (translation part)
    lam_rr = lx * rrx + ly * rry
    lam_aj_x, lam_aj_y = lx * sa + ly * ca, -lx * ca + ly * sa     # lam^T A J, A J = [[sa, -ca], [ca, sa]]
    hess[2, 2] += -(lx * adx + ly * ady) - lam_rr
    hess[2, 5] += lam_rr
    hess[5, 2] += lam_rr
    hess[5, 5] -= lam_rr
    hess[2, 3] -= lam_aj_x
    hess[3, 2] -= lam_aj_x
    hess[2, 4] -= lam_aj_y
    hess[4, 2] -= lam_aj_y
    hess[2, 0] += lam_aj_x
    hess[0, 2] += lam_aj_x
    hess[2, 1] += lam_aj_y
    hess[1, 2] += lam_aj_y
    return energy, grad, hess


class DcmmConnector:
    """DCMM_n model of one flexure (a connector for :mod:`reducedmodels.core`).

    Internal coordinates are the poses of the n - 1 intermediate bodies,
    whose reference points are the cut points on the centre line.

    ``frame`` chooses the body whose displaced frame measures each element's
    relative displacement: ``"leader"`` (body i of e_ij, as the paper's Sect. 3
    states; the default) or ``"follower"`` (body j). The two agree for small
    relative rotations and as n grows, but DCMM_1 on the closed chain
    depends strongly on the choice (see the report's sensitivity table); the
    paper's closed-chain DCMM_1 figures are closer to ``"follower"``.
    """

    def __init__(self, flexure: Flexure, mechanism: Mechanism, n: int, frame: str = "leader"):
        if n < 1:
            raise ValueError(f"dcmm: number of sub-arcs must be >= 1, got {n}")
        if frame not in ("leader", "follower"):
            raise ValueError(f"dcmm: frame must be 'leader' or 'follower', got {frame!r}")
        if frame == "follower":      # measure in the displaced frame of body j of e_ij
            flexure = dataclasses.replace(flexure, bodies=flexure.bodies[::-1])
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
        # local slots of the chain bodies: a -> 0..2, cut k -> 6 + 3k, b -> 3..5
        slots = ([np.arange(0, 3)] + [np.arange(6 + 3 * k, 9 + 3 * k) for k in range(n - 1)]
                 + [np.arange(3, 6)])
        self._element_dofs = [np.concatenate([slots[k], slots[k + 1]]) for k in range(n)]
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
        if len(self._elements) == 1:
            return sub_arc_energy(pose_a, pose_b, *self._elements[0])
        chain = self._chain(pose_a, pose_b, internal)
        n = 6 + self.n_internal
        energy, grad, hess = 0.0, np.zeros(n), np.zeros((n, n))
        for k, element in enumerate(self._elements):
            e, g, h = sub_arc_energy(chain[k], chain[k + 1], *element)
            idx = self._element_dofs[k]
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
