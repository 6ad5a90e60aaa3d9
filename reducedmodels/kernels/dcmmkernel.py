"""Compiled kernel of the DCMM displaced compliance element (numba, cached on disk).

The one implementation of the sub-arc element of :mod:`flexval.reducedmodels.dcmm.connector`:
:func:`sub_arc` gives one element's energy, gradient and Hessian;
:func:`assemble_sub_arcs` evaluates every sub-arc of a run of DCMM
connectors and adds the results where the index maps say (into the
System's gradient and tangent storage, or into a connector's local
gradient and Hessian values); :func:`sub_arc_wrenches`,
:func:`sample_statics` and :func:`chain_measures` give the end-of-path
pass's wrenches, section forces and validity measures. One call per Newton
iteration replaces one Python call per sub-arc and the scatter of their
float lists, whose cost on a few sub-arcs was interpreter overhead, not
arithmetic; one call per path replaces some forty small array operations.

Compiled with :data:`flexval.reducedmodels.kernels.jit.kernel` (numba, cached on disk; the
first run of an installation pays the compilation, see benchmarks/README.md,
"Compiled kernels"), whose
docstring gives the floating-point policy.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.bending import TERMS as BENDING_TERMS
from .jit import kernel

PARAMETERS = 13 + 2 * BENDING_TERMS
"""A sub-arc's parameters: r_L (2), r_F (2) in mm, the rows of Q (q11, q12, q21, q22), the
inverse compliances k1, k2 (N/mm), k3 (N mm), its axis t at rest (2; zero: no bending
kinematics) and the coefficients a_1..a_K, b_1..b_K (mm) of its bending kinematics."""


@kernel
def sub_arc(
    xl: float,
    yl: float,
    tl: float,
    xf: float,
    yf: float,
    tf: float,
    p: np.ndarray,
    grad: np.ndarray,
    hessian: np.ndarray,
    with_hessian: bool,
) -> float:
    """Energy (N mm) of one displaced compliance element; gradient (6) and Hessian (36) in place.

    Parameters
    ----------
    xl, yl, tl, xf, yf, tf : float
        Poses of the leading and following bodies (mm, mm, rad).
    p : array (PARAMETERS,)
        r_L, r_F: initial offsets of the centre of elasticity from each
        body's reference point (mm); q11, q12, q21, q22: the ellipse axes
        e1, e2 as the columns of Q; k1, k2, k3: the inverse of the diagonal
        compliance (N/mm, N/mm, N mm); t (2): the straight sub-arc's axis at
        rest, from its leading to its following body (zero: none); a_k, b_k:
        its bending kinematics' coefficients (mm).
    grad : array (6,)
        Receives the gradient over (x_L, y_L, theta_L, x_F, y_F, theta_F).
    hessian : array (36,)
        Receives the row-major Hessian if ``with_hessian`` (else untouched).

    Notes
    -----
    With A = R(-theta_L), phi = theta_F - theta_L and d = x_F - x_L, the
    relative displacement in the leader frame is v = A d + R(phi) r_F - r_L
    and u = (Q^T v, phi); E = 1/2 u^T diag(k1, k2, k3) u. A sub-arc with an axis t
    (a calibrated notch hinge's) takes v - g(phi) instead of v: the separation of its
    two centre points when it bends freely by phi, g = g_x t + g_y J t with
    g_x = sum a_k phi^2k and g_y = sum b_k phi^(2k+1), k = 1..K
    (:func:`flexval.reducedmodels.core.bending.centre_separation`), which adds
    g'(phi) to dv/dtheta_L, -g'(phi) to dv/dtheta_F and the second derivatives' terms
    to the geometric part. Each derivative
    du_i/d(coordinates) is (a, b, c, -a, -b, d) -- the followers'
    translations enter with the opposite sign of the leader's -- so the
    gradient and the Hessian are expansions of a 4-vector and of the
    symmetric 4x4 M = sum_i k_i w_i w_i^T + (geometric part),
    w_i = (a, b, c, d), over (x, y, theta_L, theta_F).
    """
    rlx, rly, rfx, rfy = p[0], p[1], p[2], p[3]
    q11, q12, q21, q22 = p[4], p[5], p[6], p[7]
    k1, k2, k3 = p[8], p[9], p[10]
    ca, sa = math.cos(tl), math.sin(tl)  # A = R(-tl) = [[ca, sa], [-sa, ca]]
    phi = tf - tl
    dx, dy = xf - xl, yf - yl
    adx, ady = ca * dx + sa * dy, -sa * dx + ca * dy  # A d
    cp, sp = math.cos(phi), math.sin(phi)
    rrx, rry = cp * rfx - sp * rfy, sp * rfx + cp * rfy  # R(phi) r_F
    vx, vy = adx + rrx - rlx, ady + rry - rly
    tx, ty = p[11], p[12]
    bent = tx != 0.0 or ty != 0.0
    g1x = g1y = g2x = g2y = 0.0  # g'(phi), g''(phi)
    if bent:  # Horner in phi^2, highest term first
        x = phi * phi
        sx = sx1 = sx2 = sy = sy1 = sy2 = 0.0
        for k in range(BENDING_TERMS, 0, -1):
            a, b = p[12 + k], p[12 + BENDING_TERMS + k]
            sx = sx * x + a  # g_x / phi^2
            sx1 = sx1 * x + 2 * k * a  # g_x' / phi
            sx2 = sx2 * x + 2 * k * (2 * k - 1) * a  # g_x''
            sy = sy * x + b  # g_y / phi^3
            sy1 = sy1 * x + (2 * k + 1) * b  # g_y' / phi^2
            sy2 = sy2 * x + (2 * k + 1) * 2 * k * b  # g_y'' / phi
        gx, gy = sx * x, sy * x * phi
        d1x, d1y = sx1 * phi, sy1 * x
        d2x, d2y = sx2, sy2 * phi
        vx -= gx * tx - gy * ty
        vy -= gx * ty + gy * tx
        g1x, g1y = d1x * tx - d1y * ty, d1x * ty + d1y * tx
        g2x, g2y = d2x * tx - d2y * ty, d2x * ty + d2y * tx
    u1, u2 = q11 * vx + q21 * vy, q12 * vx + q22 * vy  # Q^T v
    f1, f2, m = k1 * u1, k2 * u2, k3 * phi
    energy = 0.5 * (f1 * u1 + f2 * u2 + m * phi)
    # dv/d(x_L, y_L, theta_L, theta_F); dv/d(x_F, y_F) = -dv/d(x_L, y_L)
    # dv_x = (-ca, -sa, ady + rry, -rry), dv_y = (sa, -ca, -adx - rrx, rrx)
    ex, ey, et, ef = -ca, -sa, ady + rry + g1x, -rry - g1x
    nx, ny, nt, nf = sa, -ca, -adx - rrx + g1y, rrx - g1y
    a1, b1, c1, d1 = (
        q11 * ex + q21 * nx,
        q11 * ey + q21 * ny,
        q11 * et + q21 * nt,
        q11 * ef + q21 * nf,
    )
    a2, b2, c2, d2 = (
        q12 * ex + q22 * nx,
        q12 * ey + q22 * ny,
        q12 * et + q22 * nt,
        q12 * ef + q22 * nf,
    )
    gx, gy = f1 * a1 + f2 * a2, f1 * b1 + f2 * b2
    grad[0], grad[1], grad[2] = gx, gy, f1 * c1 + f2 * c2 - m
    grad[3], grad[4], grad[5] = -gx, -gy, f1 * d1 + f2 * d2 + m
    if not with_hessian:
        return energy
    # geometric part: lambda = Q K u (translation force in the leader frame)
    lx, ly = q11 * f1 + q12 * f2, q21 * f1 + q22 * f2
    lam_rr = lx * rrx + ly * rry
    lam_x, lam_y = lx * sa + ly * ca, -lx * ca + ly * sa
    ka1, kb1, kc1, kd1 = k1 * a1, k1 * b1, k1 * c1, k1 * d1
    ka2, kb2, kc2, kd2 = k2 * a2, k2 * b2, k2 * c2, k2 * d2
    m00, m01 = ka1 * a1 + ka2 * a2, ka1 * b1 + ka2 * b2
    m02, m03 = ka1 * c1 + ka2 * c2 + lam_x, ka1 * d1 + ka2 * d2
    m11, m12, m13 = kb1 * b1 + kb2 * b2, kb1 * c1 + kb2 * c2 + lam_y, kb1 * d1 + kb2 * d2
    lam_g = lx * g2x + ly * g2y  # lambda . g''(phi): -g'' in d2v/dtheta_L2 and dtheta_F2
    m22 = kc1 * c1 + kc2 * c2 + k3 - (lx * adx + ly * ady) - lam_rr - lam_g
    m23 = kc1 * d1 + kc2 * d2 - k3 + lam_rr + lam_g
    m33 = kd1 * d1 + kd2 * d2 + k3 - lam_rr - lam_g
    # rows x_L, y_L, theta_L, x_F, y_F, theta_F; the 4x4 M expanded with the followers'
    # translations' signs
    rows = ((m00, m01, m02, m03), (m01, m11, m12, m13), (m02, m12, m22, m23))
    for i in range(3):
        r0, r1, r2, r3 = rows[i]
        hessian[6 * i], hessian[6 * i + 1], hessian[6 * i + 2] = r0, r1, r2
        hessian[6 * i + 3], hessian[6 * i + 4], hessian[6 * i + 5] = -r0, -r1, r3
    hessian[18], hessian[19], hessian[20] = -m00, -m01, -m02
    hessian[21], hessian[22], hessian[23] = m00, m01, -m03
    hessian[24], hessian[25], hessian[26] = -m01, -m11, -m12
    hessian[27], hessian[28], hessian[29] = m01, m11, -m13
    hessian[30], hessian[31], hessian[32] = m03, m13, m23
    hessian[33], hessian[34], hessian[35] = -m03, -m13, m33
    return energy


@kernel
def assemble_sub_arcs(
    coordinates: np.ndarray,
    lead_dof: np.ndarray,
    follow_dof: np.ndarray,
    parameters: np.ndarray,
    grad_slot: np.ndarray,
    hess_slot: np.ndarray,
    grad: np.ndarray,
    storage: np.ndarray,
) -> float:
    """Every sub-arc's gradient and Hessian added into ``grad`` and ``storage``; the energy (N mm).

    Sub-arc k reads its leading body's pose at ``coordinates[lead_dof[k]:+3]``
    and its following body's at ``coordinates[follow_dof[k]:+3]``;
    ``parameters`` (e, PARAMETERS) are its :func:`sub_arc` parameters. Its
    gradient entry j goes to ``grad[grad_slot[k, j]]``, its row-major
    Hessian entry j to ``storage[hess_slot[k, j]]`` (-1: dropped), sub-arc
    after sub-arc.
    """
    energy = 0.0
    g = np.empty(6)
    h = np.empty(36)
    for k in range(parameters.shape[0]):
        i, j = lead_dof[k], follow_dof[k]
        energy += sub_arc(
            coordinates[i],
            coordinates[i + 1],
            coordinates[i + 2],
            coordinates[j],
            coordinates[j + 1],
            coordinates[j + 2],
            parameters[k],
            g,
            h,
            True,
        )
        for a in range(6):
            slot = grad_slot[k, a]
            if slot >= 0:
                grad[slot] += g[a]
        for a in range(36):
            slot = hess_slot[k, a]
            if slot >= 0:
                storage[slot] += h[a]
    return energy


@kernel
def sub_arc_wrenches(poses: np.ndarray, lead: np.ndarray, parameters: np.ndarray) -> np.ndarray:
    """Each sub-arc's gradient on its following body's pose at k states, (k, e, 3) (N, N mm).

    ``poses`` (k, bodies, 3) are the chain bodies' poses; sub-arc k joins
    body ``lead[k]`` to the next one.
    """
    out = np.empty((poses.shape[0], parameters.shape[0], 3))
    g = np.empty(6)
    h = np.empty(0)
    for s in range(poses.shape[0]):
        for k in range(parameters.shape[0]):
            b = lead[k]
            sub_arc(
                poses[s, b, 0],
                poses[s, b, 1],
                poses[s, b, 2],
                poses[s, b + 1, 0],
                poses[s, b + 1, 1],
                poses[s, b + 1, 2],
                parameters[k],
                g,
                h,
                False,
            )
            out[s, k, 0], out[s, k, 1], out[s, k, 2] = g[3], g[4], g[5]
    return out


@kernel
def sample_statics(
    poses: np.ndarray,
    wrenches: np.ndarray,
    wrench_of: np.ndarray,
    end: np.ndarray,
    lead: np.ndarray,
    w: np.ndarray,
    rel: np.ndarray,
    tangent: np.ndarray,
    order: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Normal force (N) and bending moment (N mm) at every sample of a chain stack, k states.

    Sample i lies on the sub-arc from body ``lead[i]`` to the next one, at
    the blend (1 - w) x_leading + w x_following of the points the two
    bodies carry (``rel[i]``: its offsets from them, mm);
    its section turns from ``tangent[i]`` (rad) with the same blend of the
    bodies' rotations. The wrench ``wrenches[state, wrench_of[i]]`` (force
    N, moment N mm about body ``end[i]``'s reference point) is carried to it
    by statics: M = -(M_ref + r x F), N = t . F. ``poses`` (k, bodies, 3);
    the results (k, samples) are in the order ``order``.
    """
    states, samples = poses.shape[0], order.size
    axial = np.empty((states, samples))
    moment = np.empty((states, samples))
    # each body's rotation, cosine and sine at each state, once (a body carries many samples)
    turns = np.empty((poses.shape[1], 3))
    for s in range(states):
        for body in range(poses.shape[1]):
            t = poses[s, body, 2]
            turns[body, 0], turns[body, 1], turns[body, 2] = t, math.cos(t), math.sin(t)
        for j in range(samples):
            i = order[j]
            a, b, wi = lead[i], lead[i] + 1, w[i]
            ta, ca, sa = turns[a, 0], turns[a, 1], turns[a, 2]
            tb, cb, sb = turns[b, 0], turns[b, 1], turns[b, 2]
            px = (1.0 - wi) * (poses[s, a, 0] + (ca * rel[i, 0] - sa * rel[i, 1])) + wi * (
                poses[s, b, 0] + (cb * rel[i, 2] - sb * rel[i, 3])
            )
            py = (1.0 - wi) * (poses[s, a, 1] + (sa * rel[i, 0] + ca * rel[i, 1])) + wi * (
                poses[s, b, 1] + (sb * rel[i, 2] + cb * rel[i, 3])
            )
            angle = tangent[i] + (1.0 - wi) * ta + wi * tb
            e, k = end[i], wrench_of[i]
            fx, fy = wrenches[s, k, 0], wrenches[s, k, 1]
            rx, ry = poses[s, e, 0] - px, poses[s, e, 1] - py
            moment[s, j] = -(wrenches[s, k, 2] + (rx * fy - ry * fx))
            axial[s, j] = math.cos(angle) * fx + math.sin(angle) * fy
    return axial, moment


@kernel
def _chord_point(
    poses: np.ndarray, state: int, body: int, a: int, b: int, end_rel: np.ndarray, chain: int
) -> tuple[float, float]:
    """A chord's end on ``body`` (mm): the flexure's end on the end bodies a and b, else the cut."""
    x, y = poses[state, body, 0], poses[state, body, 1]
    if body != a and body != b:
        return x, y
    o = 0 if body == a else 2
    c, s = math.cos(poses[state, body, 2]), math.sin(poses[state, body, 2])
    return (
        x + (c * end_rel[chain, o] - s * end_rel[chain, o + 1]),
        y + (s * end_rel[chain, o] + c * end_rel[chain, o + 1]),
    )


@kernel
def chain_measures(
    poses: np.ndarray,
    first: np.ndarray,
    end_rel: np.ndarray,
    sub_arc_body: np.ndarray,
    lengths: np.ndarray,
    sub_arc_start: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Each chain's largest sub-arc chord strain and relative rotation (rad) at k states.

    Chain j runs from body ``first[j]`` (body a, its flexure end at the
    offset ``end_rel[j, 0:2]``, mm) over its sub-arcs
    ``sub_arc_start[j]:sub_arc_start[j + 1]`` to body b (flexure end at
    ``end_rel[j, 2:4]``); sub-arc e joins ``sub_arc_body[e]`` to the next
    body and has the arc length ``lengths[e]`` (mm). A chord runs between
    the cut points (the cut bodies' reference points) and the flexure ends.
    ``poses`` (k, bodies, 3); returns (k, chains) each.
    """
    states, chains = poses.shape[0], first.size
    strain = np.empty((states, chains))
    turn = np.empty((states, chains))
    for s in range(states):
        for j in range(chains):
            a = first[j]
            b = a + sub_arc_start[j + 1] - sub_arc_start[j]
            worst_strain, worst_turn = -math.inf, 0.0
            for e in range(sub_arc_start[j], sub_arc_start[j + 1]):
                lead = sub_arc_body[e]
                x0, y0 = _chord_point(poses, s, lead, a, b, end_rel, j)
                x1, y1 = _chord_point(poses, s, lead + 1, a, b, end_rel, j)
                worst_strain = max(worst_strain, math.hypot(x1 - x0, y1 - y0) / lengths[e] - 1.0)
                worst_turn = max(worst_turn, abs(poses[s, lead + 1, 2] - poses[s, lead, 2]))
            strain[s, j], turn[s, j] = worst_strain, worst_turn
    return strain, turn


def warm_up() -> None:
    """Compile, or load from the on-disk cache, the kernels for the argument types flexval uses.

    ``Family.load`` of DCMM and EE calls this, so that a sweep's workers are forked
    with the machine code loaded (:mod:`flexval.validation.sweep.preload`); a run
    alone loads each kernel where it first calls it.
    """
    parameters = np.zeros((1, PARAMETERS))
    dofs = np.zeros(1, np.int64)
    assemble_sub_arcs(
        np.zeros(6),
        dofs,
        dofs + 3,
        parameters,
        np.full((1, 6), -1, np.int64),
        np.full((1, 36), -1, np.int64),
        np.zeros(6),
        np.zeros(36),
    )
    poses = np.zeros((1, 2, 3))
    sub_arc_wrenches(poses, dofs, parameters)
    sample_statics(
        poses,
        np.zeros((1, 1, 3)),
        dofs,
        dofs,
        dofs,
        np.zeros(1),
        np.zeros((1, 4)),
        np.zeros(1),
        dofs,
    )
    chain_measures(poses, dofs, np.zeros((1, 4)), dofs, np.ones(1), np.array([0, 1], np.int64))
