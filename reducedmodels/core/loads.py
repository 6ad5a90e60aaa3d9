"""Dead loads of one load case in the core's dof numbering: potential, gradient, load vector.

A dead force F acts at a material point x = p + R(theta) rel of a body,
a dead moment M on a body's rotation. At load factor lambda their
potential is

    V = -lambda (sum F . x + sum M theta),

so they add -lambda J^T F (and -lambda M) to the gradient of the total
potential and -lambda F . d2x/dtheta2 = lambda F . R(theta) rel to its
theta-theta tangent entry. The load vector f = -d(grad V)/d(lambda) = J^T F
(+ M) is what arc-length continuation borders the tangent with. Both come
from :meth:`Loads.add_to`, the one place the loads' kinematics is
written. A prescribed motion (:mod:`flexval.reducedmodels.core.drives`) is a
constant load m on its constraint's multipliers, held with the moments
(a potential -lambda m mu, linear in its coordinate as a moment's is).

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from flexval.geometry import Force, LoadCase, Moment

MANY_LOADS = 16
"""Loads from which :meth:`Loads.add_to` takes one numpy pass instead of a loop on floats
(a mechanism has a few; a batch of copies has a few per copy)."""


@dataclass
class Loads:
    """Dead loads of one load case at full value (load factor 1).

    Attributes
    ----------
    dofs : array (k, 3) of int
        Global dofs (x, y, theta) of the body each force acts on (-1: ground).
    forces : array (k, 2)
        Force vectors, N.
    rels : array (k, 2)
        Initial offsets of the loaded points from their body's reference point, mm.
    moment_dofs : array (j,) of int
        Global theta dof of the body each moment acts on (-1: ground).
    moments : array (j,)
        Moments, N mm.
    scale : float
        Force scale for relative tolerances, N: the largest force component
        or moment / mechanism size.
    """

    dofs: np.ndarray
    forces: np.ndarray
    rels: np.ndarray
    moment_dofs: np.ndarray
    moments: np.ndarray
    scale: float

    @classmethod
    def of_case(
        cls,
        case: LoadCase,
        pose_dofs: Callable[[str], np.ndarray],
        reference: Mapping[str, np.ndarray],
        size: float,
        multipliers: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> Loads:
        """The loads of ``case`` in ``pose_dofs(body)`` numbering; bodies' reference points in mm.

        ``size`` (mm) turns moments into forces for :attr:`scale`. ``multipliers``:
        the global dofs of a drive's multipliers and their loads (N,
        :meth:`flexval.reducedmodels.core.drives.DriveConnector.multiplier_loads`), required
        where ``case`` prescribes a motion.

        Raises
        ------
        ValueError
            If ``case`` prescribes a motion and no ``multipliers`` are given (a
            System built without the case's drive: it would silently not move).
        """
        if case.drive is not None and multipliers is None:
            raise ValueError(
                f"load case {case.name!r} prescribes a motion of body {case.drive.body!r}; "
                "this system was built without its drive (Mechanism.driven_by)"
            )
        fd, ff, fr, md, mv = [], [], [], [], []
        for comp in case.components:
            dofs = pose_dofs(comp.body)
            if isinstance(comp, Force):
                fd.append(dofs)
                ff.append(comp.vector)
                fr.append(np.asarray(comp.point, float) - reference[comp.body])
            elif isinstance(comp, Moment):
                md.append(dofs[2])
                mv.append(comp.value)
        forces = np.array(ff).reshape(-1, 2)
        moments = np.array(mv, float)
        # plain floats: a load case has a few components
        scale = max(
            [
                max(map(abs, forces.ravel().tolist()), default=0.0),
                max(map(abs, moments.tolist()), default=0.0) / size,
                1e-300,
            ]
        )
        if multipliers is not None:  # a drive's loads (N) on its multipliers, with the moments
            dofs, values = multipliers
            md += np.asarray(dofs, int).tolist()
            moments = np.concatenate([moments, np.asarray(values, float)])
            scale = max([scale, *map(abs, np.asarray(values, float).tolist())])
        return cls(
            np.array(fd, int).reshape(-1, 3),
            forces,
            np.array(fr).reshape(-1, 2),
            np.array(md, int),
            moments,
            scale,
        )

    def __post_init__(self) -> None:
        self.many = False
        if len(self.dofs) + len(self.moment_dofs) > MANY_LOADS:  # perhaps many on moving bodies
            loaded = self.dofs[:, 0] >= 0  # forces on moving bodies (the ground's do no work)
            if np.count_nonzero(loaded) + np.count_nonzero(self.moment_dofs >= 0) > MANY_LOADS:
                self.diagonal_dofs = list(dict.fromkeys(self.dofs[loaded, 2].tolist()))
                self.vectorise()
                return
        # the loads on moving bodies as plain numbers, read at every assembly
        self._points = [
            (ix, iy, it, fx, fy, rx, ry)
            for (ix, iy, it), (fx, fy), (rx, ry) in zip(
                self.dofs.tolist(), self.forces.tolist(), self.rels.tolist()
            )
            if ix >= 0
        ]
        self._moments = [
            (dof, m) for dof, m in zip(self.moment_dofs.tolist(), self.moments.tolist()) if dof >= 0
        ]
        #: the rotation dofs whose tangent diagonal :meth:`add_to` may change (each once)
        self.diagonal_dofs = list(dict.fromkeys(it for _, _, it, *_ in self._points))

    def vectorise(self) -> None:
        """Take one numpy pass over all loads in :meth:`add_to` from now on (many loads: a
        batch of copies, whose copies then see the same arithmetic however many they are)."""
        self.many = True
        loaded = self.dofs[:, 0] >= 0
        self._point_dofs = np.ascontiguousarray(self.dofs[loaded].T, np.int64)  # ix, iy, it
        self._point_values = np.concatenate(  # fx, fy, rx, ry
            [np.asarray(self.forces, float)[loaded].T, np.asarray(self.rels, float)[loaded].T]
        )
        moved = self.moment_dofs >= 0
        self._moment_dofs = np.asarray(self.moment_dofs[moved], np.int64)
        self._moment_values = np.asarray(self.moments[moved], float)
        self.diagonal_array = np.array(self.diagonal_dofs, np.int64)

    def add_to(self, q: np.ndarray, factor: float, grad: np.ndarray, diagonal: np.ndarray) -> float:
        """Add the loads at ``factor`` to ``grad`` and the tangent ``diagonal`` (in place).

        Returns their potential, N mm. On plain floats (q read with
        ``item``): called at every assembly, where numpy scalars cost more
        than the arithmetic of a few loads.
        """
        if self.many:
            return self._add_many(q, float(factor), grad, diagonal)
        energy, factor, item = 0.0, float(factor), q.item
        for ix, iy, it, fx, fy, rx, ry in self._points:
            theta = item(it)
            c, s = math.cos(theta), math.sin(theta)
            rrx, rry = c * rx - s * ry, s * rx + c * ry  # R(theta) rel (rotate_xy)
            energy -= factor * (fx * (item(ix) + rrx) + fy * (item(iy) + rry))
            grad[ix] -= factor * fx
            grad[iy] -= factor * fy
            grad[it] -= factor * (fy * rrx - fx * rry)  # F . dx/dtheta
            diagonal[it] += factor * (fx * rrx + fy * rry)  # -F . d2x/dtheta2
        for dof, m in self._moments:
            energy -= factor * m * item(dof)
            grad[dof] -= factor * m
        return energy

    def _add_many(
        self, q: np.ndarray, factor: float, grad: np.ndarray, diagonal: np.ndarray
    ) -> float:
        """:meth:`add_to` in one numpy pass over all loads (the same terms)."""
        (ix, iy, it), (fx, fy, rx, ry) = self._point_dofs, self._point_values
        theta = q[it]
        c, s = np.cos(theta), np.sin(theta)
        rrx, rry = c * rx - s * ry, s * rx + c * ry
        energy = -factor * float(np.sum(fx * (q[ix] + rrx) + fy * (q[iy] + rry)))
        np.add.at(grad, ix, -factor * fx)
        np.add.at(grad, iy, -factor * fy)
        np.add.at(grad, it, -factor * (fy * rrx - fx * rry))
        np.add.at(diagonal, it, factor * (fx * rrx + fy * rry))
        dofs, moments = self._moment_dofs, self._moment_values
        energy -= factor * float(np.sum(moments * q[dofs]))
        np.add.at(grad, dofs, -factor * moments)
        return energy

    def vector(self, q: np.ndarray) -> np.ndarray:
        """Generalised load at unit factor in state q, J^T F and M (N, N mm), (n_dofs = q.size).

        Minus the derivative of the total-potential gradient with respect to
        the load factor: what :meth:`add_to` adds to a zero gradient at
        factor -1 (subtracting -1 times each term adds the term exactly).
        """
        f = np.zeros(q.size)
        self.add_to(q, -1.0, f, np.zeros(q.size))
        return f
