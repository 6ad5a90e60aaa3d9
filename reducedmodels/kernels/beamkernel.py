"""Compiled kernels of the corotational beam elements (numba, cached on disk).

The one implementation of the element physics of :mod:`flexval.reducedmodels.beam.elements`:
:func:`assemble_elements` evaluates every element of a run of beam
connectors, transports the end nodes to their bodies' poses and adds the
gradients and tangent entries straight into the global gradient and the
tangent's storage (the index maps come from :class:`flexval.reducedmodels.core.system.System`);
the section forces and the validity measures are here too (the chord-wise
predictor and Newton update of its chains of nodes are
:mod:`flexval.reducedmodels.kernels.chainkernel`'s). One call per Newton iteration
replaces some forty numpy calls and
the scatter of the concatenated local Hessians, whose cost on a few hundred
elements was interpreter overhead, not arithmetic.

Compiled with :data:`flexval.reducedmodels.kernels.jit.kernel` (numba, cached on disk; the
first run of an installation pays the compilation, see benchmarks/README.md,
"Compiled kernels"), whose
docstring gives the floating-point policy.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math

import numpy as np

from .chainkernel import place_nodes, wrapped
from .jit import kernel


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

    ``Family.load`` of the beams calls this, so that a sweep's workers are
    forked with the machine code loaded (:mod:`flexval.validation.sweep.preload`);
    a run alone loads each kernel where it first calls it. Two elements
    between two bodies (one attached node each, one free node), the arrays
    typed as :class:`flexval.reducedmodels.beam.elements.BeamGroup` and the core pass them.
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
