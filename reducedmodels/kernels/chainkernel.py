"""Compiled kernels of chains of nodes joined by chords: a flexure's discretisation seen as a
polyline between its two bodies (numba, cached on disk).

A beam's nodes (:mod:`flexval.reducedmodels.beam.elements`) and a DCMM chain's cut bodies
(:mod:`flexval.reducedmodels.dcmm.connector`) are such chains: nearly inextensible chords that
turn. Extrapolating or correcting their nodes coordinate by coordinate would stretch
every turning chord by (turn)^2 / 2, and the axial stiffness would turn that into forces
many times the load; these kernels predict the nodes of the next load step
(:func:`chain_memory`, :func:`predicted_chains`) and apply a Newton correction
(:func:`updated_chains`) in chord lengths and turns instead, closing each chain between
its end bodies by the flexure's own least-energy bending (:func:`close_chains`).

Compiled with :data:`flexval.reducedmodels.kernels.jit.kernel`. Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import kernel

TWO_PI = 2.0 * math.pi


@kernel
def wrapped(angle: float) -> float:
    """An angle (rad) brought into (-pi, pi], so that full turns carry no strain.

    pi - (pi - angle) mod 2 pi; the remainder (a library call) only when
    pi - angle is outside [0, 2 pi), where it changes it: the same number.
    """
    turned = math.pi - angle
    if 0.0 <= turned < TWO_PI:
        return math.pi - turned
    return math.pi - turned % TWO_PI


@kernel
def place_nodes(
    coordinates: np.ndarray, node_dof: np.ndarray, node_rel: np.ndarray, attached: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node positions (nodes, 2) mm, rotations (nodes,) rad and dx/dtheta (nodes, 2) mm.

    A free node reads its (x, y, theta) at ``coordinates[node_dof]``; an
    attached one is its body's material point x = p + R(theta) rel at the
    pose read there, turns with it and moves by dx/dtheta = J R(theta) rel
    (zero for a free node). ``node_dof`` gives where each node's (x, y, theta), or its
    body's pose, is read; ``node_rel`` an attached node's offset on its body (mm).
    """
    n_nodes = node_dof.size
    x = np.empty((n_nodes, 2))
    theta = np.empty(n_nodes)
    t = np.zeros((n_nodes, 2))
    for k in range(n_nodes):
        d = node_dof[k]
        if attached[k]:
            angle = coordinates[d + 2]
            c, s = math.cos(angle), math.sin(angle)
            rx = c * node_rel[k, 0] - s * node_rel[k, 1]
            ry = s * node_rel[k, 0] + c * node_rel[k, 1]
            x[k, 0], x[k, 1], theta[k] = coordinates[d] + rx, coordinates[d + 1] + ry, angle
            t[k, 0], t[k, 1] = -ry, rx
        else:
            x[k, 0], x[k, 1], theta[k] = coordinates[d], coordinates[d + 1], coordinates[d + 2]
    return x, theta, t


CLOSURE_ITERATIONS = 6
"""Most Newton iterations of a chain's closure (:func:`close_chains`); quadratic from a gap
of ~1e-3 of the arc length, it reaches the tolerance in two or three."""

CLOSURE_TOL = 1e-14
"""Gap (relative to the chain's arc length) left to a uniform stretch instead of bending
(:func:`close_chains`), a hundred times the round-off of a chain's sum. A Newton update's
gap is ~(correction)^2 of the arc, so corrections below ~1e-7 (scaled) skip the
closure's solve. 1e-13 and 1e-12 leave axial forces that keep the closed chain's beam:20
residual above ``force_tol`` for one more iteration (f- 26 -> 28 and 29 iterations);
1e-15 and 1e-14 give the same iterations on all 12 paper beam paths."""


SMALL_TURN = 1e-2
"""Turn (rad) below which :func:`rotated` uses the Taylor series of cos and sin (to the
terms in turn^6 and turn^7: truncation below turn^8 / 8! = 2.5e-21) instead of the library's."""


@kernel
def rotated(x: float, y: float, turn: float) -> tuple[float, float]:
    """The vector (x, y) turned by ``turn`` (rad).

    A chord's turn in a Newton update or a chain's closure is small, and
    the series is several times cheaper than the library's cos and sin.
    """
    if abs(turn) < SMALL_TURN:
        t2 = turn * turn
        c = 1.0 - t2 * (0.5 - t2 * (1.0 / 24.0 - t2 / 720.0))
        s = turn * (1.0 - t2 * (1.0 / 6.0 - t2 * (1.0 / 120.0 - t2 / 5040.0)))
    else:
        c, s = math.cos(turn), math.sin(turn)
    return c * x - s * y, s * x + c * y


@kernel
def solve3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x with a x = b for a symmetric positive definite 3x3 ``a`` (Cholesky, written out)."""
    l00 = math.sqrt(a[0, 0])
    l10, l20 = a[1, 0] / l00, a[2, 0] / l00
    l11 = math.sqrt(a[1, 1] - l10 * l10)
    l21 = (a[2, 1] - l20 * l10) / l11
    l22 = math.sqrt(a[2, 2] - l20 * l20 - l21 * l21)
    y0 = b[0] / l00
    y1 = (b[1] - l10 * y0) / l11
    y2 = (b[2] - l20 * y0 - l21 * y1) / l22
    x = np.empty(3)
    x[2] = y2 / l22
    x[1] = (y1 - l21 * x[2]) / l11
    x[0] = (y0 - l10 * x[1] - l20 * x[2]) / l00
    return x


@kernel
def close_chains(
    chords: np.ndarray,
    x: np.ndarray,
    theta: np.ndarray,
    chain_nodes: np.ndarray,
    bending_flexibility: np.ndarray,
    axial_flexibility: np.ndarray,
) -> np.ndarray:
    """Interior nodes (x, y, theta) of chains of chords (elements, 2) mm, concatenated.

    Chain k holds the nodes ``chain_nodes[k]`` to ``chain_nodes[k + 1] - 1``
    and the elements between them; it is built chord after chord from its
    first node's position in ``x`` and closed at its last node's. The gap
    is closed the way the flexure itself would take up an end displacement
    with both ends clamped: by the least-energy deformation, a bending
    moment linear in position, M = M0 + (r - r_end) x F (and, for a nearly
    straight chain, the axial force F . e), found by Newton on the three
    unknowns (M0, F) with the flexibilities l0 / EI and l0 / EA of the
    elements (``bending_flexibility`` 1/(N mm), ``axial_flexibility`` mm/N;
    the integrals of ds / EI and ds / EA over an element of varying section).
    The chords turn by the rotations this bending gives, and the interior
    nodes (rotations from ``theta``) turn with them; the chords keep their
    lengths to within F l0 / EA. Spreading the gap as a uniform stretch
    instead leaves an axial force EA gap / L: on a slender flexure it is
    many times the load, and larger than its buckling load, so that Newton's
    tangent there is wrong in the soft (bending) directions and the next
    correction hardly reduces the bending error. A gap below ``CLOSURE_TOL``
    of the arc (or what is left after ``CLOSURE_ITERATIONS``) is spread
    along the chain in proportion to arc length.
    """
    n_chains = chain_nodes.size - 1
    out = np.empty(3 * (chain_nodes[-1] - 2 * n_chains))
    a, rhs = np.empty((3, 3)), np.zeros(3)
    o = 0
    for k in range(n_chains):
        n0, n1 = chain_nodes[k], chain_nodes[k + 1]
        e0, m = n0 - k, n1 - n0 - 1
        cx, cy = chords[e0 : e0 + m, 0].copy(), chords[e0 : e0 + m, 1].copy()
        ell = np.empty(m)
        px, py = np.empty(m + 1), np.empty(m + 1)
        psi = np.zeros(m + 1)
        px[0] = py[0] = 0.0
        arc = 0.0
        for i in range(m):
            ell[i] = math.hypot(cx[i], cy[i])
            arc += ell[i]
        target_x, target_y = x[n1 - 1, 0] - x[n0, 0], x[n1 - 1, 1] - x[n0, 1]
        for iteration in range(CLOSURE_ITERATIONS + 1):
            for i in range(m):
                px[i + 1], py[i + 1] = px[i] + cx[i], py[i] + cy[i]
            gap_x, gap_y = target_x - px[m], target_y - py[m]
            if (
                m < 2
                or iteration == CLOSURE_ITERATIONS
                or math.hypot(gap_x, gap_y) <= CLOSURE_TOL * arc
            ):
                break
            a[:, :] = 0.0
            for i in range(m):
                fb, fa = bending_flexibility[e0 + i], axial_flexibility[e0 + i]
                rx = -(py[m] - py[i] - 0.5 * cy[i])  # J (end - midpoint of chord i)
                ry = px[m] - px[i] - 0.5 * cx[i]
                ex, ey = cx[i] / ell[i], cy[i] / ell[i]
                a[0, 0] += fb
                a[1, 0] += fb * rx
                a[2, 0] += fb * ry
                a[1, 1] += fb * rx * rx + fa * ex * ex
                a[2, 1] += fb * rx * ry + fa * ex * ey
                a[2, 2] += fb * ry * ry + fa * ey * ey
            rhs[1], rhs[2] = gap_x, gap_y
            mu = solve3(a, rhs)
            turned = 0.0
            for i in range(m):
                rx = -(py[m] - py[i] - 0.5 * cy[i])
                ry = px[m] - px[i] - 0.5 * cx[i]
                bend = bending_flexibility[e0 + i] * (mu[0] + mu[1] * rx + mu[2] * ry)
                stretch = axial_flexibility[e0 + i] * (mu[1] * cx[i] + mu[2] * cy[i]) / ell[i]
                scale = (ell[i] + stretch) / ell[i]
                cx[i], cy[i] = rotated(scale * cx[i], scale * cy[i], turned + 0.5 * bend)
                ell[i] += stretch
                turned += bend
                psi[i + 1] += turned
        arc = 0.0
        for i in range(m):
            arc += ell[i]
        share = 0.0
        for i in range(1, m):
            share += ell[i - 1]
            f = share / arc
            out[o] = px[i] + x[n0, 0] + f * gap_x
            out[o + 1] = py[i] + x[n0, 1] + f * gap_y
            out[o + 2] = theta[n0 + i] + psi[i]
            o += 3
    return out


@kernel
def updated_chains(
    old: np.ndarray,
    new: np.ndarray,
    node_dof: np.ndarray,
    node_rel: np.ndarray,
    attached: np.ndarray,
    chain_nodes: np.ndarray,
    bending_flexibility: np.ndarray,
    axial_flexibility: np.ndarray,
) -> np.ndarray:
    """Interior nodes after a Newton correction from ``old`` to ``new`` (linear), chords turned.

    Each chord's change is split into its stretch (along the old chord) and
    its turn (across it, over its length); the chains of chords with those
    lengths and directions are closed between the end nodes of ``new``
    (:func:`close_chains`). The chord changes take an end node's motion as
    Newton's linearisation sees it, dp + (dx/dtheta) dtheta: the node itself
    moves on a circle about its body's reference point, and the O(dtheta^2)
    between the two, taken as the end element's stretch, would carry EA times
    it (on the open chain, 1.9e-5 strain after a 3e-3 rad turn, forty times
    the load); the closure takes it up by bending instead. Tables as in
    :func:`place_nodes`, chains as in :func:`close_chains`; returns
    the interior nodes' (x, y, theta).
    """
    x_old, _, t_old = place_nodes(old, node_dof, node_rel, attached)
    x_new, theta, _ = place_nodes(new, node_dof, node_rel, attached)
    x_lin = x_new.copy()
    for k in range(node_dof.size):
        if attached[k]:
            d = node_dof[k]
            turn = new[d + 2] - old[d + 2]
            x_lin[k, 0] = x_old[k, 0] + (new[d] - old[d]) + t_old[k, 0] * turn
            x_lin[k, 1] = x_old[k, 1] + (new[d + 1] - old[d + 1]) + t_old[k, 1] * turn
    n_chains = chain_nodes.size - 1
    chords = np.empty((chain_nodes[-1] - n_chains, 2))
    for k in range(n_chains):
        for i in range(chain_nodes[k], chain_nodes[k + 1] - 1):
            dx, dy = x_old[i + 1, 0] - x_old[i, 0], x_old[i + 1, 1] - x_old[i, 1]
            cx, cy = x_lin[i + 1, 0] - x_lin[i, 0] - dx, x_lin[i + 1, 1] - x_lin[i, 1] - dy
            chord = math.hypot(dx, dy)
            tx, ty = dx / chord, dy / chord
            length = chord + (tx * cx + ty * cy)
            chords[i - k, 0], chords[i - k, 1] = rotated(
                length * tx, length * ty, (tx * cy - ty * cx) / chord
            )
    return close_chains(chords, x_new, theta, chain_nodes, bending_flexibility, axial_flexibility)


@kernel
def chain_memory(
    coordinates: np.ndarray,
    node_dof: np.ndarray,
    node_rel: np.ndarray,
    attached: np.ndarray,
    chain_nodes: np.ndarray,
) -> np.ndarray:
    """What :func:`predicted_chains` reads of a converged state, computed once per state.

    Laid end to end (4 elements + 3 nodes,): each chord's length (mm),
    direction angle (rad) and unit vector (x, then y), each node's rotation
    (rad) and dx/dtheta (mm, x then y; zero for a free node). Tables as in
    :func:`place_nodes`, chains as in :func:`close_chains`.
    """
    n_chains = chain_nodes.size - 1
    n_nodes = chain_nodes[-1]
    n = n_nodes - n_chains
    x, theta, t = place_nodes(coordinates, node_dof, node_rel, attached)
    memory = np.empty(4 * n + 3 * n_nodes)
    for k in range(n_chains):
        for i in range(chain_nodes[k], chain_nodes[k + 1] - 1):
            e = i - k
            dx, dy = x[i + 1, 0] - x[i, 0], x[i + 1, 1] - x[i, 1]
            chord = math.hypot(dx, dy)
            memory[e], memory[n + e] = chord, math.atan2(dy, dx)
            memory[2 * n + e], memory[3 * n + e] = dx / chord, dy / chord
    for i in range(n_nodes):
        memory[4 * n + i] = theta[i]
        memory[4 * n + n_nodes + i], memory[4 * n + 2 * n_nodes + i] = t[i, 0], t[i, 1]
    return memory


@kernel
def predicted_chains(
    memories: np.ndarray,
    weights: np.ndarray,
    poses: np.ndarray,
    node_dof: np.ndarray,
    node_rel: np.ndarray,
    attached: np.ndarray,
    chain_nodes: np.ndarray,
    bending_flexibility: np.ndarray,
    axial_flexibility: np.ndarray,
    slope: np.ndarray,
    slope_weight: float,
) -> np.ndarray:
    """Interior nodes extrapolated in chord lengths and angles from converged states.

    ``memories`` (states, m) holds :func:`chain_memory` of each converged
    state, oldest first, ``weights`` their extrapolation weights, ``poses``
    coordinates whose body poses are the predicted ones. Each chord's
    length and its turn from the last state's direction, and each node's
    rotation, are extrapolated; the chains are closed between the end nodes
    at the predicted poses (:func:`close_chains`). With a nonzero
    ``slope_weight``, ``slope`` holds the coordinates' derivative along the
    path at the last state (per unit load factor, read like the
    coordinates): the chords' and rotations' derivatives it gives (an end
    node moving as dp + (dx/dtheta) dtheta) join the extrapolation with that
    weight (Hermite weights, see :func:`flexval.reducedmodels.core.extrapolation.hermite_weights`).
    """
    n_chains = chain_nodes.size - 1
    n_nodes = chain_nodes[-1]
    n = n_nodes - n_chains
    newest = memories.shape[0] - 1
    last = memories[newest]
    length, turn, theta = np.empty(n), np.zeros(n), np.empty(n_nodes)
    w = weights[newest]  # the last state's own turn is 0
    for e in range(n):
        length[e] = w * last[e]
    for i in range(n_nodes):
        theta[i] = w * last[4 * n + i]
    for h in range(newest):
        w = weights[h]
        memory = memories[h]
        for e in range(n):
            length[e] += w * memory[e]
            turn[e] += w * wrapped(memory[n + e] - last[n + e])
        for i in range(n_nodes):
            theta[i] += w * memory[4 * n + i]
    if slope_weight != 0.0:
        velocity = np.empty((n_nodes, 2))
        for i in range(n_nodes):
            d = node_dof[i]
            spin = slope[d + 2]
            velocity[i, 0] = slope[d] + last[4 * n + n_nodes + i] * spin
            velocity[i, 1] = slope[d + 1] + last[4 * n + 2 * n_nodes + i] * spin
            theta[i] += slope_weight * spin
        for k in range(n_chains):
            for i in range(chain_nodes[k], chain_nodes[k + 1] - 1):
                e = i - k
                vx, vy = velocity[i + 1, 0] - velocity[i, 0], velocity[i + 1, 1] - velocity[i, 1]
                ux, uy = last[2 * n + e], last[3 * n + e]
                length[e] += slope_weight * (ux * vx + uy * vy)
                turn[e] += slope_weight * (ux * vy - uy * vx) / last[e]
    chords = np.empty((n, 2))
    for e in range(n):
        chords[e, 0], chords[e, 1] = rotated(
            length[e] * last[2 * n + e], length[e] * last[3 * n + e], turn[e]
        )
    ends = place_nodes(poses, node_dof, node_rel, attached)[0]
    return close_chains(chords, ends, theta, chain_nodes, bending_flexibility, axial_flexibility)


def warm_up() -> None:
    """Compile, or load from the on-disk cache, every kernel for the argument types the
    beam and DCMM groups pass: one chain of three nodes between two bodies (one attached
    end node each, one free node)."""
    node_dof = np.array([0, 3, 6], np.int64)
    rel = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 0.5]])
    attached = np.array([True, False, True])
    coordinates, ones = np.zeros(9), np.ones(2)
    chain_nodes = np.array([0, 3], np.int64)
    updated_chains(coordinates, coordinates, node_dof, rel, attached, chain_nodes, ones, ones)
    memory = chain_memory(coordinates, node_dof, rel, attached, chain_nodes)
    predicted_chains(
        np.array([memory, memory]),
        ones,
        coordinates,
        node_dof,
        rel,
        attached,
        chain_nodes,
        ones,
        ones,
        coordinates,
        0.0,
    )
