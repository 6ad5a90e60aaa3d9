"""Compiled kernels of the corotational beam elements (numba, cached on disk).

The one implementation of the element physics of :mod:`flexval.reducedmodels.beam`:
:func:`assemble_elements` evaluates every element of a run of beam
connectors, transports the end nodes to their bodies' poses and adds the
gradients and tangent entries straight into the global gradient and the
tangent's storage (the index maps come from :class:`flexval.reducedmodels.core.System`);
the chord-wise predictor and Newton update, the section forces and the
validity measures are here too. One call per Newton iteration replaces some forty numpy calls and
the scatter of the concatenated local Hessians, whose cost on a few hundred
elements was interpreter overhead, not arithmetic.

Compiled with :data:`flexval.reducedmodels.jit.kernel` (numba, cached on disk; the
first run of an installation pays the compilation, see benchmarks/README.md,
"Compiled kernels"), whose
docstring gives the floating-point policy.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import kernel

TWO_PI = 2.0 * math.pi


def tangent_layout() -> tuple[np.ndarray, np.ndarray]:
    """Where each entry of a row-major 6x6 element tangent comes from: (source, sign), (36,) each.

    In element coordinates [x1, y1, theta1, x2, y2, theta2] the tangent is,
    by node and dof kind, [[A, w1, -A, w2], [w1^T, k11, -w1^T, k12],
    [-A, -w1, A, -w2], [w2^T, k12, -w2^T, k22]] with A symmetric 2x2, so every
    entry is +- one of the ten independent entries
    [Axx, Axy, Ayy, w1x, w1y, k11, k12, w2x, w2y, k22] (:func:`element`).
    """
    source = np.empty((6, 6), dtype=np.intp)
    sign = np.ones((6, 6))
    translations, rotations = ([0, 1], [3, 4]), (2, 5)
    for i, ti in enumerate(translations):
        for j, tj in enumerate(translations):
            source[np.ix_(ti, tj)] = [[0, 1], [1, 2]]
            sign[np.ix_(ti, tj)] = 1.0 if i == j else -1.0
        for r, w in zip(rotations, ([3, 4], [7, 8])):
            source[ti, r] = source[r, ti] = w
            sign[ti, r] = sign[r, ti] = 1.0 if i == 0 else -1.0
    source[2, 2], source[5, 5] = 5, 9
    source[2, 5] = source[5, 2] = 6
    return source.ravel(), sign.ravel()


SOURCE, SIGN = tangent_layout()
"""The layout of the element tangent, frozen into the kernels as constants."""

ENTRIES = 10
"""Independent entries of an element tangent (:func:`tangent_layout`)."""


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
def chord_frame(
    x1: float, y1: float, x2: float, y2: float, theta1: float, theta2: float, c0x: float, c0y: float
) -> tuple[float, float, float, float, float]:
    """An element's corotational frame: chord length l (mm), direction (c, s), local end rotations.

    The local rotations a1, a2 (rad) are the nodes' rotations from the
    chord's, wrap(theta_i - alpha), alpha the chord's turn from its initial
    unit direction (c0x, c0y) (see :func:`element`).
    """
    dx, dy = x2 - x1, y2 - y1
    length = math.hypot(dx, dy)
    alpha = math.atan2(c0x * dy - c0y * dx, c0x * dx + c0y * dy)
    return length, dx / length, dy / length, wrapped(theta1 - alpha), wrapped(theta2 - alpha)


@kernel
def element(
    x1: float,
    y1: float,
    x2: float,
    y2: float,
    theta1: float,
    theta2: float,
    c0x: float,
    c0y: float,
    l0: float,
    k_axial: float,
    k11: float,
    k12: float,
    k22: float,
    grad: np.ndarray,
    entries: np.ndarray,
) -> float:
    """Energy (N mm) of one corotational element; its gradient and tangent entries in place.

    The element joins node 1 (x1, y1, theta1) to node 2 (x2, y2, theta2)
    (mm, rad increments from the initial configuration); (c0x, c0y) is its
    initial unit chord, l0 its initial length (mm), k_axial its axial
    stiffness (EA/l0 for a uniform section, N/mm), k11, k12, k22 the entries
    of the local bending stiffness k_b = [[k11, k12], [k12, k22]] (N mm;
    k22 = k11 for a uniform section, not for a varying one).

    ``grad`` (6,) receives the internal forces [f, M1, -f, M2] with
    f = -N e + V n (e = (c, s) the current chord direction, n = (-s, c),
    V = (M1 + M2)/l); ``entries`` (10,) the independent entries
    [Axx, Axy, Ayy, w1x, w1y, k11, k12, w2x, w2y, k22] of the consistent
    tangent (see :func:`tangent_layout`): Crisfield's
    B^T D B + N z z^T / l + (M1 + M2)(r z^T + z r^T) / l^2 with
    A = k_axial e e^T + ((k11 + 2 k12 + k22)/l^2 + N/l) n n^T
    + (M1 + M2)/l^2 (e n^T + n e^T), w1 = (k11 + k12)/l n and
    w2 = (k12 + k22)/l n, written in double-angle form
    (cos 2b = c^2 - s^2, sin 2b = 2 c s).
    """
    length, c, s, a1, a2 = chord_frame(x1, y1, x2, y2, theta1, theta2, c0x, c0y)
    return element_in_frame(length, c, s, a1, a2, l0, k_axial, k11, k12, k22, grad, entries)


@kernel
def element_in_frame(
    length: float,
    c: float,
    s: float,
    a1: float,
    a2: float,
    l0: float,
    k_axial: float,
    k11: float,
    k12: float,
    k22: float,
    grad: np.ndarray,
    entries: np.ndarray,
) -> float:
    """:func:`element` from the element's :func:`chord_frame` (same arguments otherwise).

    With k22 = k11 the numbers are those of the symmetric element bit for
    bit: k11 + k12 and k12 + k22 are then the same sum, and their sum is
    twice it exactly.
    """
    u = length - l0
    axial = k_axial * u
    m1 = k11 * a1 + k12 * a2
    m2 = k12 * a1 + k22 * a2
    shear = (m1 + m2) / length
    fx, fy = -axial * c - shear * s, -axial * s + shear * c
    grad[0], grad[1], grad[2], grad[3], grad[4], grad[5] = fx, fy, m1, -fx, -fy, m2
    row1, row2 = k11 + k12, k12 + k22
    k_normal = (row1 + row2) / (length * length) + axial / length
    k_cross = shear / length
    k_rot, k_rot2 = row1 / length, row2 / length
    cos2, sin2 = c * c - s * s, 2.0 * c * s
    mean, half = 0.5 * (k_axial + k_normal), 0.5 * (k_axial - k_normal)
    diagonal = half * cos2 - k_cross * sin2
    entries[0] = mean + diagonal
    entries[1] = half * sin2 + k_cross * cos2
    entries[2] = mean - diagonal
    entries[3] = -k_rot * s
    entries[4] = k_rot * c
    entries[5] = k11
    entries[6] = k12
    entries[7] = -k_rot2 * s
    entries[8] = k_rot2 * c
    entries[9] = k22
    return 0.5 * (axial * u + m1 * a1 + m2 * a2)


@kernel
def attach(grad: np.ndarray, tangent: np.ndarray, slot: int, t0: float, t1: float) -> None:
    """Transport one element node's force and tangent to its rigid body's pose, in place.

    The node is the body's material point x = p + R(theta) rel and turns
    with it. With T = d node / d pose (identity except dx/dtheta = t, mm)
    the chain rule gives g <- T^T g and
    K <- T^T K T + (g_xy . d^2x/dtheta^2) e_theta e_theta^T, where
    d^2x/dtheta^2 = -R(theta) rel = J t. ``slot`` is the node's first entry
    in the element vector (0 or 3); ``tangent`` is the row-major 6x6.
    """
    x, y, th = slot, slot + 1, slot + 2
    gx, gy = grad[x], grad[y]
    geometric = -(gx * t1 - gy * t0)
    grad[th] += t0 * gx + t1 * gy
    for j in range(6):
        tangent[6 * th + j] += t0 * tangent[6 * x + j] + t1 * tangent[6 * y + j]
    for i in range(6):
        tangent[6 * i + th] += t0 * tangent[6 * i + x] + t1 * tangent[6 * i + y]
    tangent[6 * th + th] += geometric


@kernel
def place_nodes(
    coordinates: np.ndarray, node_dof: np.ndarray, node_rel: np.ndarray, attached: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node positions (nodes, 2) mm, rotations (nodes,) rad and dx/dtheta (nodes, 2) mm.

    A free node reads its (x, y, theta) at ``coordinates[node_dof]``; an
    attached one is its body's material point x = p + R(theta) rel at the
    pose read there, turns with it and moves by dx/dtheta = J R(theta) rel
    (zero for a free node). See :func:`assemble_elements` for the tables.
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


@kernel
def assemble_elements(
    coordinates: np.ndarray,
    node_dof: np.ndarray,
    node_rel: np.ndarray,
    attached: np.ndarray,
    first: np.ndarray,
    terms: np.ndarray,
    grad_slot: np.ndarray,
    tangent_slot: np.ndarray,
    tangent_pick: np.ndarray,
    grad_out: np.ndarray,
    tangent_out: np.ndarray,
) -> float:
    """Add every element's gradient and tangent into ``grad_out`` and ``tangent_out``; the energy.

    Parameters
    ----------
    coordinates : array
        The coordinates the nodes are read from (mm, rad).
    node_dof : int array (nodes,)
        Position in ``coordinates`` of each node's (x, y, theta), or of the
        pose (x, y, theta) of the body an attached node belongs to.
    node_rel : array (nodes, 2)
        An attached node's initial offset from its body's reference point, mm.
    attached : bool array (nodes,)
        Whether the node is a material point of a rigid body (an end node).
    first : int array (elements,)
        Each element's first node; its second is the next one.
    terms : array (elements, 7)
        Each element's initial unit chord (2), length (mm), axial stiffness
        (N/mm) and k_b entries k11, k12, k22 (N mm).
    grad_slot : int array (elements, 6)
        Where each element coordinate's force is added in ``grad_out`` (-1: nowhere).
    tangent_slot, tangent_pick : int arrays (elements, w)
        The tangent entries each element adds, in row-major order of its
        6x6 tangent, padded with slot -1: where each is added in
        ``tangent_out``, and which value it is (:func:`scatter_tables`):
        for an end element (transported to its bodies) its index in the
        row-major 6x6 tangent, for an interior one its index in the ten
        independent entries followed by their negatives (every entry is
        +- one of them, :func:`tangent_layout`).
    """
    x, theta, t = place_nodes(coordinates, node_dof, node_rel, attached)
    energy = 0.0
    grad = np.empty(6)
    entries = np.empty(ENTRIES)
    signed = np.empty(2 * ENTRIES)
    tangent = np.empty(36)
    width = tangent_slot.shape[1]
    for e in range(first.size):
        i = first[e]
        j = i + 1
        energy += element(
            x[i, 0],
            x[i, 1],
            x[j, 0],
            x[j, 1],
            theta[i],
            theta[j],
            terms[e, 0],
            terms[e, 1],
            terms[e, 2],
            terms[e, 3],
            terms[e, 4],
            terms[e, 5],
            terms[e, 6],
            grad,
            entries,
        )
        if attached[i] or attached[j]:  # an end element: transported to its bodies
            for k in range(36):
                tangent[k] = SIGN[k] * entries[SOURCE[k]]
            if attached[i]:
                attach(grad, tangent, 0, t[i, 0], t[i, 1])
            if attached[j]:
                attach(grad, tangent, 3, t[j, 0], t[j, 1])
            for m in range(width):
                slot = tangent_slot[e, m]
                if slot < 0:
                    break
                tangent_out[slot] += tangent[tangent_pick[e, m]]
        else:  # an interior one: added from its ten entries
            for k in range(ENTRIES):
                signed[k], signed[ENTRIES + k] = entries[k], -entries[k]
            for m in range(width):
                slot = tangent_slot[e, m]
                if slot < 0:
                    break
                tangent_out[slot] += signed[tangent_pick[e, m]]
        for k in range(6):
            slot = grad_slot[e, k]
            if slot >= 0:
                grad_out[slot] += grad[k]
    return energy


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
def scatter_tables(tangent_slot: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tangent entries each element adds, as :func:`assemble_elements` reads them.

    ``tangent_slot`` (elements, 36) says where each entry of an element's
    row-major 6x6 tangent is added in the storage (-1: nowhere, e.g. a
    ground row or the lower triangle of a symmetric band); ``ends``
    (elements,) whether the element has an end node on a body (its tangent
    is transported to the body's pose before it is added). Returns (slots,
    picks), (elements, w) each, w the most entries any element keeps: the
    kept entries in row-major order, padded with slot -1, and their values'
    index, for an end element in its 6x6 tangent, for an interior one in
    its ten independent entries followed by their negatives
    (:func:`tangent_layout`). The kernel then adds the same numbers in the
    same order as over all 36 entries with their signs, without the ones
    it would skip.
    """
    n = tangent_slot.shape[0]
    width = 0
    for e in range(n):
        kept = 0
        for k in range(36):
            if tangent_slot[e, k] >= 0:
                kept += 1
        width = max(width, kept)
    slots = np.full((n, width), -1, np.int64)
    picks = np.zeros((n, width), np.int64)
    for e in range(n):
        m = 0
        for k in range(36):
            if tangent_slot[e, k] >= 0:
                slots[e, m] = tangent_slot[e, k]
                picks[e, m] = k if ends[e] else SOURCE[k] + (ENTRIES if SIGN[k] < 0.0 else 0)
                m += 1
    return slots, picks


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
    :func:`assemble_elements`, chains as in :func:`close_chains`; returns
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
    :func:`assemble_elements`, chains as in :func:`close_chains`.
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
    weight (Hermite weights, see :func:`flexval.reducedmodels.core.hermite_weights`).
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


@kernel
def path_element_ends(
    coordinates: np.ndarray,
    node_dof: np.ndarray,
    node_rel: np.ndarray,
    attached: np.ndarray,
    first: np.ndarray,
    tangent0: np.ndarray,
    chord0: np.ndarray,
    l0: np.ndarray,
    k_axial: np.ndarray,
    k11: np.ndarray,
    k12: np.ndarray,
    k22: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each element's chord and end forces at k states: what the end pass of a load path needs.

    ``coordinates`` (k, m) holds the coordinates at each state, read through
    the node tables of :func:`assemble_elements` (element e joins node
    ``first[e]`` to the next); ``tangent0`` is each node's initial tangent
    angle (rad), turned by the node's rotation into its section axis.
    Returns (length, turn, axial, moment):

    * (k, elements) each: the chord length (mm) and the larger turn of the
      end nodes from the chord, |a1| or |a2| of :func:`chord_frame` (rad):
      what a two-node element must carry as bending (the validity
      monitor's measures);
    * (k, 2 elements) each: the normal force (N) and bending moment (N mm)
      at every element's start node, then at every element's end node, on
      the part towards the chain's end from the part before: at an
      element's start node the force that holds the element there, at its
      end node minus that force (the section forces).

    Each element's frame is computed once for both.
    """
    k, n = coordinates.shape[0], first.size
    length, turn = np.empty((k, n)), np.empty((k, n))
    axial, moment = np.empty((k, 2 * n)), np.empty((k, 2 * n))
    grad = np.empty(6)
    entries = np.empty(ENTRIES)
    cos_axis, sin_axis = np.empty(node_dof.size), np.empty(node_dof.size)
    for state in range(k):
        x, theta, _ = place_nodes(coordinates[state], node_dof, node_rel, attached)
        for i in range(node_dof.size):
            axis = tangent0[i] + theta[i]
            cos_axis[i], sin_axis[i] = math.cos(axis), math.sin(axis)
        for e in range(n):
            i = first[e]
            j = i + 1
            chord, c, s, a1, a2 = chord_frame(
                x[i, 0], x[i, 1], x[j, 0], x[j, 1], theta[i], theta[j], chord0[e, 0], chord0[e, 1]
            )
            length[state, e] = chord
            turn[state, e] = max(abs(a1), abs(a2))
            element_in_frame(
                chord, c, s, a1, a2, l0[e], k_axial[e], k11[e], k12[e], k22[e], grad, entries
            )
            axial[state, e] = -(grad[0] * cos_axis[i] + grad[1] * sin_axis[i])
            axial[state, n + e] = grad[3] * cos_axis[j] + grad[4] * sin_axis[j]
            moment[state, e], moment[state, n + e] = grad[2], -grad[5]
    return length, turn, axial, moment


def warm_up() -> None:
    """Compile, or load from the on-disk cache, every kernel for the argument types flexval uses.

    Loading the machine code takes a noticeable fraction of a second per
    process (importing numba included); the beam family calls this before a
    path's clock starts, so that path times measure the paths. Two elements
    between two bodies (one attached node each, one free node), the arrays
    typed as :class:`flexval.reducedmodels.beam.BeamGroup` and the core pass them.
    """
    chain = np.array([0, 3, 6], np.int64)
    rel = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 0.5]])
    attached = np.array([True, False, True])
    first = np.array([0, 1], np.int64)
    chord0 = np.array([[1.0, 0.0], [0.0, 1.0]])
    ones = np.ones(2)
    grad_slot, tangent_slot = np.full((2, 6), -1, np.int64), np.full((2, 36), -1, np.int64)
    coordinates = np.zeros(9)
    slots, picks = scatter_tables(tangent_slot, np.array([True, True]))
    assemble_elements(
        coordinates,
        chain,
        rel,
        attached,
        first,
        np.ones((2, 7)),
        grad_slot,
        slots,
        picks,
        np.zeros(9),
        np.zeros(9),
    )
    chain_nodes = np.array([0, 3], np.int64)
    updated_chains(coordinates, coordinates, chain, rel, attached, chain_nodes, ones, ones)
    memory = chain_memory(coordinates, chain, rel, attached, chain_nodes)
    predicted_chains(
        np.array([memory, memory]),
        ones,
        coordinates,
        chain,
        rel,
        attached,
        chain_nodes,
        ones,
        ones,
        coordinates,
        0.0,
    )
    path_element_ends(
        np.zeros((1, 9)),
        chain,
        rel,
        attached,
        first,
        np.zeros(3),
        chord0,
        ones,
        ones,
        ones,
        ones,
        ones,
    )
