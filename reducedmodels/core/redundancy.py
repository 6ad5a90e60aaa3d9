"""Rigid directions that lock one motion more than once: a statically indeterminate model.

A connector may hold a relative motion of its two bodies rigid at rest
(:meth:`~flexval.reducedmodels.core.connector.Connector.rigid_directions`: the
PRBM's straight leaf its axis, a pin both directions at its point). Each such
direction is one row of a matrix on the bodies' small motions; where the rows
are dependent (three parallel leaves of a guide, two leaves on one line), a
set of forces along them is in equilibrium by itself, so how the connectors
share a load is not determined by the model: its Lagrange multipliers, and
with them the section forces and stresses, are not defined, and the saddle
point's tangent at rest is singular. A model that carries the leaves' axial
stiffness (beams, DCMM) has no such rows and is always determinate.

Units: mm, rad.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flexval.geometry import Mechanism

from .connector import Connector
from .joints import PinConnector

DEPENDENT_BELOW = 1e-6
"""A set of rigid directions is dependent where its smallest singular value, relative to its
largest (rows of unit length, lengths in units of the mechanism's size), is below this: one
direction within 1e-6 rad of the others' span. The model's multipliers along the near-
dependent motion would then be a million times what equilibrium needs of them, already
meaningless, and exact dependence (leaves parallel as written) lands at round-off, 1e-16."""


def redundant_connectors(
    mechanism: Mechanism, connectors: Sequence[Connector], below: float = DEPENDENT_BELOW
) -> list[str]:
    """The connectors whose rigid directions at rest are dependent (none: the model is
    statically determinate), in the connectors' order.

    Rows are the directions' (:meth:`Connector.rigid_directions`) relative
    motions of the connectors' two bodies in the bodies' translations and
    rotations (the ground's left out), each scaled to unit length with
    positions in units of ``mechanism.size()``; the connectors named are those
    whose rows take part in a dependence (a left null vector of the rows,
    ``below`` the largest singular value).
    """
    found = [(c, point, direction) for c in connectors for point, direction in c.rigid_directions()]
    if len(found) < 2 or all(_is_pin(c) for c, _, _ in found):
        return []  # one row, or pins alone (a scene's pins are checked independent)
    movable = [b for b in mechanism.bodies if b != mechanism.ground]
    column = {b: 3 * i for i, b in enumerate(movable)}
    size = mechanism.size()
    rows = np.zeros((len(found), 3 * len(movable)))
    for r, (c, point, direction) in enumerate(found):
        p = np.asarray(point, float) / size
        e = np.asarray(direction, float)
        motion = np.array([e[0], e[1], e[1] * p[0] - e[0] * p[1]])
        for body, sign in zip(c.bodies, (-1.0, 1.0)):
            if body in column:
                rows[r, column[body] : column[body] + 3] += sign * motion
    norms = np.linalg.norm(rows, axis=1)
    rows = rows[norms > 0.0] / norms[norms > 0.0, None]
    owners = [c.name for (c, _, _), n in zip(found, norms) if n > 0.0]
    left, values, _ = np.linalg.svd(rows)
    rank = int(np.sum(values > below * values[0])) if values.size else 0
    if rank >= len(owners):
        return []
    dependent = np.abs(left[:, rank:]).max(axis=1) > below
    named = {name for name, taking in zip(owners, dependent) if taking}
    return [c.name for c in connectors if c.name in named]


def _is_pin(connector: Connector) -> bool:
    """Whether ``connector`` is a pin (whose own rows a scene keeps independent)."""
    return isinstance(connector, PinConnector)
