"""Is a mechanism a structure? Mobility and redundant pins from the linear kinematics.

Each moving body has three degrees of freedom (u, v, theta). Linearised, a
flexure forbids all three relative ones between its bodies (it is elastic in
each, so it removes them from any motion that costs no energy), a pin the
two relative translations at its point. The models can solve only if

* no motion of the bodies is left free: the constraint Jacobian of flexures
  and pins together has full column rank (otherwise some bodies can move at
  zero stiffness and every model's tangent is singular), and
* the pins alone are independent: their Jacobian has full row rank
  (otherwise their reactions are not unique and the saddle-point system of
  the multipliers is singular).

Flexures weld their bodies into rigid clusters for the first test, so only
the pins between clusters enter its (small) matrix and the check scales with
the number of pins, not of flexures. Rotations are scaled by the mechanism's
size so every column is in mm; ranks use a relative singular-value threshold
``RANK_TOL``. Units: mm, rad.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from .errors import SceneError
from .graph import connected_roots

if TYPE_CHECKING:
    from .mechanism import Mechanism, Pin

RANK_TOL = 1e-9
"""Singular values below this fraction of the largest count as zero (the matrices are O(1))."""


def _pin_rows(
    pins: list[Pin], column: dict[str, int], origin: dict[str, np.ndarray], scale: float
) -> np.ndarray:
    """Rows of [v_b(P) - v_a(P)] for each pin, over 3 columns per entry of ``column``.

    A body (or cluster) with pose rates (u, v, omega) about its origin R moves
    the point P at (u - omega (P_y - R_y), v + omega (P_x - R_x)); the
    rotation column holds omega * scale (mm). Entries missing from ``column``
    (the ground) do not move.
    """
    J = np.zeros((2 * len(pins), 3 * len(column)))
    for k, pin in enumerate(pins):
        for sign, key in ((-1.0, pin.bodies[0]), (1.0, pin.bodies[1])):
            if key not in column:
                continue
            c = 3 * column[key]
            r = (pin.point - origin[key]) / scale
            J[2 * k : 2 * k + 2, c : c + 3] += sign * np.array(
                [[1.0, 0.0, -r[1]], [0.0, 1.0, r[0]]]
            )
    return J


def _null_space(J: np.ndarray) -> np.ndarray:
    """Orthonormal basis (columns) of the null space of J."""
    if J.shape[0] == 0:
        return np.eye(J.shape[1])
    _, s, vt = np.linalg.svd(J)
    rank = int((s > RANK_TOL * max(s[0], 1.0)).sum())
    return vt[rank:].T


def check_structure(mech: Mechanism) -> None:
    """Raise SceneError if some bodies can move freely or some pins are redundant.

    The message names the bodies that can move (field ``pins``) or the pins
    that constrain the same motion twice (field ``pins.NAME``).
    """
    if not mech.pins:
        return  # flexures alone: reachability already makes a structure
    for pin in mech.pins:
        for body in pin.bodies:
            if body != mech.ground and not any(
                body in link.bodies for link in (*mech.flexures, *mech.pins) if link is not pin
            ):
                raise SceneError(
                    mech.source,
                    f"pins.{pin.name}.bodies",
                    list(pin.bodies),
                    f"body {body!r} is held by this pin only and would turn freely about it",
                )
    scale = mech.size() or 1.0
    cluster = connected_roots(mech.bodies, (f.bodies for f in mech.flexures))
    ground_cluster = cluster[mech.ground]
    moving_clusters = [c for c in dict.fromkeys(cluster.values()) if c != ground_cluster]
    column = {c: k for k, c in enumerate(moving_clusters)}
    origin = {c: mech.bodies[c].reference for c in moving_clusters}
    between = [p for p in mech.pins if cluster[p.bodies[0]] != cluster[p.bodies[1]]]
    lifted = [replace(p, bodies=(cluster[p.bodies[0]], cluster[p.bodies[1]])) for p in between]
    free = _null_space(_pin_rows(lifted, column, origin, scale))
    if free.shape[1]:
        moving = np.abs(free).reshape(len(moving_clusters), 3, -1).max(axis=(1, 2)) > 1e-6
        names = [
            b
            for b in mech.bodies
            if cluster[b] in {c for c, m in zip(moving_clusters, moving) if m}
        ]
        raise SceneError(
            mech.source,
            "pins",
            names,
            f"the mechanism is not a structure: bodies {names} can move with no "
            f"flexure deforming ({free.shape[1]} free motion(s)); add a flexure or "
            "remove a pin",
        )

    pinned = [b for b in dict.fromkeys(b for p in mech.pins for b in p.bodies) if b != mech.ground]
    column = {b: k for k, b in enumerate(pinned)}
    origin = {b: mech.bodies[b].reference for b in pinned}
    J = _pin_rows(list(mech.pins), column, origin, scale)
    dependent = _null_space(J.T)  # combinations of pin rows that vanish
    if dependent.shape[1]:
        weight = np.abs(dependent).reshape(len(mech.pins), 2, -1).max(axis=(1, 2))
        names = [p.name for p, w in zip(mech.pins, weight) if w > 1e-6]
        raise SceneError(
            mech.source,
            f"pins.{names[-1]}",
            names,
            f"redundant pins: {names} constrain the same relative motion more than "
            "once (e.g. a body pinned twice to the ground), so their reactions are "
            "not determined; remove one",
        )
