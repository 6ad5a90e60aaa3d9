"""The numbering of a mechanism's unknowns for its linear response at rest.

The linear response (``ee``, alone in :func:`.models.linear_response` or for
many copies in :mod:`.linearbatch`) numbers the unknowns as a
:class:`~flexval.reducedmodels.core.system.System` does and assembles K0 the same
way, without the index maps, groups and solver state a System builds for
many Newton assemblies.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flexval.geometry import Mechanism

from .connector import Connector
from .tangent import TangentLayout


@dataclass(frozen=True)
class RestNumbering:
    """The unknowns and assembly maps of a mechanism's linear response at rest (shared by the
    copies of one topology in a batch: copy 0's).

    Numbered as a :class:`~flexval.reducedmodels.core.system.System` numbers them: the moving
    bodies' poses, then each connector's internal
    coordinates in turn; every connector's local coordinates laid end to end.

    Attributes
    ----------
    n : int
        Unknowns.
    bodies : list of str
        The moving bodies, in order (body k's pose is unknowns 3k .. 3k + 2).
    dofs : int array (d,)
        The unknown of every local coordinate (-1: the ground's).
    gather : int array (d,)
        Its place in [q, ground pose].
    places, bounds : list of int
        Where each connector's local coordinates start and end.
    local_rows, local_cols : int arrays (h,)
        Every Hessian value's local row and column, connectors end to end.
    keep : bool array (h,)
        The values that enter K0 (no ground row or column).
    layout : TangentLayout
        K0's storage.
    patterns : list of (rows, cols)
        Each connector's Hessian pattern (what every copy's connectors must have).
    """

    n: int
    bodies: list
    dofs: np.ndarray
    gather: np.ndarray
    places: list
    bounds: list
    local_rows: np.ndarray
    local_cols: np.ndarray
    keep: np.ndarray
    layout: TangentLayout
    patterns: list

    @classmethod
    def of(cls, mechanism: Mechanism, connectors: Sequence[Connector]) -> RestNumbering:
        """The numbering of ``mechanism`` joined by ``connectors``."""
        ground, bodies = mechanism.ground, mechanism.moving_bodies
        first = {b: 3 * k for k, b in enumerate(bodies)}
        first[ground] = None
        n = 3 * len(bodies)
        dofs, places, patterns, start = [], [], [], 0
        for c in connectors:
            ends = [
                (-1, -1, -1) if first[b] is None else range(first[b], first[b] + 3)
                for b in c.bodies
            ]
            dofs += [*ends[0], *ends[1], *range(n, n + c.n_internal)]
            pattern = c.hessian_pattern()
            m = 6 + c.n_internal
            patterns.append(
                (np.repeat(np.arange(m), m), np.tile(np.arange(m), m))
                if pattern is None
                else pattern
            )
            places.append(start)
            start += m
            n += c.n_internal
        dofs = np.array(dofs)
        local_rows = np.concatenate([rows + k for (rows, _), k in zip(patterns, places)])
        local_cols = np.concatenate([cols + k for (_, cols), k in zip(patterns, places)])
        rows, cols = dofs[local_rows], dofs[local_cols]
        keep = (rows >= 0) & (cols >= 0)
        diagonal = np.arange(n)
        layout = TangentLayout(
            n,
            np.concatenate([rows[keep], diagonal]),
            np.concatenate([cols[keep], diagonal]),
            sum(c.n_multipliers for c in connectors),
        )
        return cls(
            n,
            list(bodies),
            dofs,
            np.where(dofs >= 0, dofs, n + np.arange(dofs.size) % 3),
            places,
            [*places[1:], start],
            local_rows,
            local_cols,
            keep,
            layout,
            patterns,
        )

    def fits(self, connectors: Sequence[Connector]) -> bool:
        """True if ``connectors`` assemble with these maps (the same Hessian patterns)."""
        for c, (rows, cols) in zip(connectors, self.patterns):
            pattern = c.hessian_pattern()
            if pattern is None:
                m = 6 + c.n_internal
                if rows.size != m * m:
                    return False
            elif pattern[0] is rows and pattern[1] is cols:  # one layout's tables, shared
                continue
            elif not (np.array_equal(pattern[0], rows) and np.array_equal(pattern[1], cols)):
                return False
        return True
