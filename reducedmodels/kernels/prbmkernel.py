"""Compiled kernel of the 3R pseudo-rigid-body chain (numba, cached on disk).

The one implementation of the PRBM connector's Lagrangian of
:mod:`flexval.reducedmodels.prbm.connector`: :func:`chain` gives one chain's Lagrangian,
gradient and Hessian values; :func:`assemble_chains` evaluates every chain
of a run of PRBM connectors and adds the results where the index maps say
(into the System's gradient and tangent storage, or into a connector's
local gradient and Hessian values); :func:`chain_wrenches`,
:func:`chain_polylines` and :func:`chain_statics` give the end-of-path
pass's wrenches, displaced polylines and section forces. One call per
Newton iteration replaces one Python call per flexure and the scatter of
their float lists.

Compiled with :data:`flexval.reducedmodels.kernels.jit.kernel` (numba, cached on disk; the
first run of an installation pays the compilation, see benchmarks/README.md,
"Compiled kernels"), whose
docstring gives the floating-point policy.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import kernel

COORDINATES = 10
"""A chain's local coordinates: x_a, y_a, theta_a, x_b, y_b, theta_b, phi_h, phi_l, mu_x, mu_y."""

PARAMETERS = 12
"""A chain's parameters: the joint offsets r_a, r_b from the end bodies' reference points and the
link vectors v_h, v_l (2 each, mm, initial), the joint stiffnesses k1, k2, k3 (N mm) and the
closure scale c (N/mm)."""

HESSIAN_VALUES = 34
"""Hessian values of one chain, in the order of
:func:`flexval.reducedmodels.prbm.connector._hessian_pattern`."""


@kernel
def chain(
    local: np.ndarray, p: np.ndarray, grad: np.ndarray, values: np.ndarray, with_hessian: bool
) -> float:
    """Lagrangian (N mm) of one chain; its gradient (10) and Hessian values (34) in place.

    ``local`` holds the chain's coordinates (:data:`COORDINATES`), ``p`` its
    parameters (:data:`PARAMETERS`); ``values`` is written only if
    ``with_hessian``. With the gap g and its Jacobian G (identity on x_a,
    minus identity on x_b, J R(.) v on the four angles), the springs t = B q
    and the scale c: gradient B^T K t + c G^T mu (and c g on mu), Hessian
    B^T K B plus the curvature of the gap, c mu . d2(R v)/dangle2 = -c mu . R v,
    on the four angle diagonals, plus c G and c G^T in the mu rows and columns.
    """
    xa, ya, ta, xb, yb, tb = local[0], local[1], local[2], local[3], local[4], local[5]
    ph, pl, mx, my = local[6], local[7], local[8], local[9]
    k1, k2, k3, c = p[8], p[9], p[10], p[11]
    ca, sa = math.cos(ta), math.sin(ta)
    rax, ray = ca * p[0] - sa * p[1], sa * p[0] + ca * p[1]  # R(theta_a) r_a
    cb, sb = math.cos(tb), math.sin(tb)
    rbx, rby = cb * p[2] - sb * p[3], sb * p[2] + cb * p[3]  # R(theta_b) r_b
    ch, sh = math.cos(ph), math.sin(ph)
    vhx, vhy = ch * p[4] - sh * p[5], sh * p[4] + ch * p[5]  # R(phi_h) v_h
    cl, sl = math.cos(pl), math.sin(pl)
    vlx, vly = cl * p[6] - sl * p[7], sl * p[6] + cl * p[7]  # R(phi_l) v_l
    gx = xa + rax + vhx + vlx - xb - rbx
    gy = ya + ray + vhy + vly - yb - rby
    # gap Jacobian columns on the angles: J R v = (-y, x)
    ga0, ga1, gb0, gb1 = -ray, rax, rby, -rbx
    gh0, gh1, gl0, gl1 = -vhy, vhx, -vly, vlx
    t1, t2, t3 = ph - ta, pl - ph, tb - pl
    f1, f2, f3 = k1 * t1, k2 * t2, k3 * t3
    cmx, cmy = c * mx, c * my
    energy = 0.5 * (f1 * t1 + f2 * t2 + f3 * t3) + cmx * gx + cmy * gy
    grad[0], grad[1], grad[2] = cmx, cmy, -f1 + cmx * ga0 + cmy * ga1
    grad[3], grad[4], grad[5] = -cmx, -cmy, f3 + cmx * gb0 + cmy * gb1
    grad[6], grad[7] = f1 - f2 + cmx * gh0 + cmy * gh1, f2 - f3 + cmx * gl0 + cmy * gl1
    grad[8], grad[9] = c * gx, c * gy
    if not with_hessian:
        return energy
    values[0], values[1], values[2] = k1 - cmx * rax - cmy * ray, -k1, -k1
    values[3], values[4], values[5] = k1 + k2 - cmx * vhx - cmy * vhy, -k2, -k2
    values[6], values[7], values[8] = k2 + k3 - cmx * vlx - cmy * vly, -k3, -k3
    values[9] = k3 + cmx * rbx + cmy * rby
    mixed = (c * ga0, c * gb0, c * gh0, c * gl0, c * ga1, c * gb1, c * gh1, c * gl1)
    for start in (10, 22):  # c G in the mu rows, then c G^T in the mu columns
        values[start], values[start + 1], values[start + 2], values[start + 3] = c, -c, c, -c
        for j in range(8):
            values[start + 4 + j] = mixed[j]
    return energy


@kernel
def assemble_chains(
    coordinates: np.ndarray,
    gather: np.ndarray,
    parameters: np.ndarray,
    grad_slot: np.ndarray,
    hess_slot: np.ndarray,
    grad: np.ndarray,
    storage: np.ndarray,
) -> float:
    """Every chain's gradient and Hessian values added into ``grad`` and ``storage``; the energy.

    Chain k reads its local coordinate j at ``coordinates[gather[k, j]]``;
    ``parameters`` (c, PARAMETERS) are its :func:`chain` parameters. Its
    gradient entry j goes to ``grad[grad_slot[k, j]]``, its Hessian value j
    to ``storage[hess_slot[k, j]]`` (-1: dropped), chain after chain; the
    energy is in N mm.
    """
    energy = 0.0
    local = np.empty(COORDINATES)
    g = np.empty(COORDINATES)
    h = np.empty(HESSIAN_VALUES)
    for k in range(parameters.shape[0]):
        for j in range(COORDINATES):
            local[j] = coordinates[gather[k, j]]
        energy += chain(local, parameters[k], g, h, True)
        for j in range(COORDINATES):
            slot = grad_slot[k, j]
            if slot >= 0:
                grad[slot] += g[j]
        for j in range(HESSIAN_VALUES):
            slot = hess_slot[k, j]
            if slot >= 0:
                storage[slot] += h[j]
    return energy


@kernel
def chain_wrenches(local: np.ndarray, parameters: np.ndarray) -> np.ndarray:
    """Each chain's gradient on body b's pose at k states, (k, c, 3) (N, N, N mm).

    ``local`` (k, c, COORDINATES) holds every chain's coordinates at each state.
    """
    out = np.empty((local.shape[0], local.shape[1], 3))
    g = np.empty(COORDINATES)
    h = np.empty(0)
    for s in range(local.shape[0]):
        for k in range(local.shape[1]):
            chain(local[s, k], parameters[k], g, h, False)
            out[s, k, 0], out[s, k, 1], out[s, k, 2] = g[3], g[4], g[5]
    return out


@kernel
def chain_polylines(local: np.ndarray, parameters: np.ndarray, end_rel: np.ndarray) -> np.ndarray:
    """Each chain's polyline end_a, R_a, R_2, R_b, end_b at k states, (k, c, 5, 2) mm.

    ``local`` (k, c, COORDINATES) holds every chain's coordinates at each
    state; ``end_rel`` (c, 4) the flexure ends' offsets from bodies a and b (mm).
    """
    states, chains = local.shape[0], local.shape[1]
    out = np.empty((states, chains, 5, 2))
    for s in range(states):
        for k in range(chains):
            q, p, e = local[s, k], parameters[k], end_rel[k]
            ca, sa = math.cos(q[2]), math.sin(q[2])
            cb, sb = math.cos(q[5]), math.sin(q[5])
            ch, sh = math.cos(q[6]), math.sin(q[6])
            out[s, k, 0, 0] = q[0] + (ca * e[0] - sa * e[1])
            out[s, k, 0, 1] = q[1] + (sa * e[0] + ca * e[1])
            jx, jy = q[0] + (ca * p[0] - sa * p[1]), q[1] + (sa * p[0] + ca * p[1])
            out[s, k, 1, 0], out[s, k, 1, 1] = jx, jy
            out[s, k, 2, 0] = jx + (ch * p[4] - sh * p[5])
            out[s, k, 2, 1] = jy + (sh * p[4] + ch * p[5])
            out[s, k, 3, 0] = q[3] + (cb * p[2] - sb * p[3])
            out[s, k, 3, 1] = q[4] + (sb * p[2] + cb * p[3])
            out[s, k, 4, 0] = q[3] + (cb * e[2] - sb * e[3])
            out[s, k, 4, 1] = q[4] + (sb * e[2] + cb * e[3])
    return out


@kernel
def chain_statics(
    local: np.ndarray, parameters: np.ndarray, end_rel: np.ndarray, wrenches: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Normal force (N) and bending moment (N mm) at both ends of each polyline segment.

    Each chain's wrench ``wrenches[state, chain]`` (force N, moment N mm
    about body b's reference point) carried by statics along its polyline
    (:func:`chain_polylines`): at the start of segment q (station q) and at
    its end (station 4 + q), with the segment's axis, M = -(M_ref + r x F)
    and N = t . F. Returns (k, c, 8) each; a segment of zero length (a
    joint on the flexure's end) has no axis and gives nan.
    """
    return line_statics(local, chain_polylines(local, parameters, end_rel), wrenches)


@kernel
def line_statics(
    local: np.ndarray, lines: np.ndarray, wrenches: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`chain_statics` along polylines computed already (``lines``: :func:`chain_polylines`'s,
    (k, c, 5, 2) mm), so that the validity screen and the statics share them."""
    states, chains = local.shape[0], local.shape[1]
    axial = np.empty((states, chains, 8))
    moment = np.empty((states, chains, 8))
    for s in range(states):
        for k in range(chains):
            fx, fy, m = wrenches[s, k, 0], wrenches[s, k, 1], wrenches[s, k, 2]
            xb, yb = local[s, k, 3], local[s, k, 4]
            for q in range(4):
                dx = lines[s, k, q + 1, 0] - lines[s, k, q, 0]
                dy = lines[s, k, q + 1, 1] - lines[s, k, q, 1]
                length = math.hypot(dx, dy)
                normal = (dx / length) * fx + (dy / length) * fy
                for end in range(2):
                    rx = xb - lines[s, k, q + end, 0]
                    ry = yb - lines[s, k, q + end, 1]
                    moment[s, k, 4 * end + q] = -(m + (rx * fy - ry * fx))
                    axial[s, k, 4 * end + q] = normal
    return axial, moment


def warm_up() -> None:
    """Compile, or load from the on-disk cache, the kernels for the argument types flexval uses.

    ``Family.load`` of the PRBM calls this, so that a sweep's workers are forked
    with the machine code loaded (:mod:`flexval.validation.sweep.preload`); a run
    alone loads each kernel where it first calls it.
    """
    parameters = np.zeros((1, PARAMETERS))
    slots = np.full((1, COORDINATES), -1, np.int64)
    assemble_chains(
        np.zeros(COORDINATES),
        slots + 1,
        parameters,
        slots,
        np.full((1, HESSIAN_VALUES), -1, np.int64),
        np.zeros(COORDINATES),
        np.zeros(HESSIAN_VALUES),
    )
    local = np.zeros((1, 1, COORDINATES))
    chain_wrenches(local, parameters)
    chain_statics(local, parameters, np.zeros((1, 4)), np.zeros((1, 1, 3)))
    line_statics(local, np.zeros((1, 1, 5, 2)), np.zeros((1, 1, 3)))
