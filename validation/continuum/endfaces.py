"""The chain rule of a solid whose end faces follow two rigid bodies (2D and 3D connectors).

A continuum connector's energy is the solid's strain energy at node
positions x(q) of its local coordinates q = [pose_a, pose_b, internal]: the
free nodes move with the internal coordinates, the nodes of each end face
follow their body in plane, x = x_body + R(theta) (X - X_ref_body). So

    g = T^T f,    H = T^T K T + sum_face nodes f_node . d2x/dtheta2  (theta-theta entry),

with T = dx/dq (identity on free dofs, the rigid Jacobian on face dofs) and
f, K the solid's nodal forces and tangent. T^T K T is computed on the COO
level: each connector builds, once, the index arrays that expand every nodal
dof into the coordinates it depends on and every element-matrix entry into
the products of its row and column expansions; only the rotation
coefficients change from one evaluation to the next. This module holds what
the plane (:mod:`.connector`) and the 3D (:mod:`.connector3d`) connectors do
with those arrays alike: the Hessian pattern, the evaluation, the validity
screen and the section resultants from the end face's reaction. Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import functools

import numpy as np

from flexval.geometry.kinematics import rigid_points
from flexval.reducedmodels.core.sections import SectionForces, polyline_axes, statics_section_forces
from flexval.reducedmodels.core.validity import MIN_DET_F, stretch_reasons


def _lengths(d: np.ndarray) -> np.ndarray:
    """Lengths of the rows of ``d`` (2 or 3 columns), by hypot: no overflow, and for two
    columns exactly ``np.hypot(d[:, 0], d[:, 1])``."""
    return functools.reduce(np.hypot, d.T)


class HeldEndFaces:
    """The evaluation of a meshed flexure whose end faces follow their bodies (a mixin).

    The class using it provides ``positions(pose_a, pose_b, internal)`` (node
    positions, (n_nodes, dim) mm), ``shape(...)`` (the deformed centre line,
    (n, 2) mm), ``_min_det(x)`` (each element's smallest det F), ``mesh`` (its
    ``nodes`` and ``centre_line``) and the attributes below.

    Attributes
    ----------
    node_dim : int
        Coordinates per node (2 or 3); the first two are in plane.
    elastic
        The whole mesh's kernel: ``evaluate(x) -> (energy N mm, nodal forces N,
        element matrices)``.
    _end_kernel
        The kernel of the elements touching the end face of body ``end_slot``:
        ``forces(x)`` (N).
    end_faces, end_offsets
        Each body's end-face nodes and their offsets from the body's reference (mm).
    exp_dof, exp_z, theta_pos, mixed, mixed_first, plain_src, pattern_rows, pattern_cols, _n
        The expansion's index arrays (see the module docstring).
    end_slot, _centre_fractions
        The body whose face reaction gives the section forces, and the centre-line
        nodes' arc-length fractions.
    """

    node_dim: int = 2

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """Local (rows, cols) of the Hessian values :meth:`evaluate` returns (duplicates sum)."""
        return self.pattern_rows, self.pattern_cols

    def evaluate(
        self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Energy (N mm), gradient (6 + n) and Hessian values over [pose_a, pose_b, internal].

        The Hessian values belong to the entries of :meth:`hessian_pattern`.

        Raises
        ------
        ValueError
            If the kernel refuses the state (an inverted element; the core cuts the step).
        """
        x = self.positions(pose_a, pose_b, internal)
        energy, forces, Ke = self.elastic.evaluate(x)
        nodal = forces.reshape(-1, self.node_dim)
        coef = np.ones(self.exp_z.size)
        second = np.zeros(2)
        for s, pose in enumerate((pose_a, pose_b)):
            _, jac, d2 = rigid_points(np.asarray(pose, float), self.end_offsets[s])
            coef[self.theta_pos[s]] = jac[:, :, 2].ravel()
            second[s] = np.sum(nodal[self.end_faces[s], :2] * d2)
        grad = np.bincount(self.exp_z, weights=forces[self.exp_dof] * coef, minlength=self._n)
        ke = Ke.ravel()
        t, p, q = self.mixed
        n_plain = self.plain_src.size
        hess = np.empty(self.pattern_rows.size)  # filled in place: no third copy of the entries
        np.take(ke, self.plain_src, out=hess[:n_plain])
        hess[n_plain:-2] = ke[t] * coef[p] * coef[q]
        hess[-2:] = second
        return energy, grad, hess

    def validity(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> list[str]:
        """Centre-line fibre stretch beyond MAX_STRAIN; elements near inversion (det F < MIN_DET_F).

        See :mod:`flexval.reducedmodels.core.validity`; ``_min_det(x)`` gives each element's
        smallest det F.
        """
        x = self.positions(pose_a, pose_b, internal)
        line = self.mesh.centre_line
        d, d0 = np.diff(x[line], axis=0), np.diff(self.mesh.nodes[line], axis=0)
        reasons = stretch_reasons("centre-line segment", _lengths(d), _lengths(d0))
        det = self._min_det(x)
        k = int(np.argmin(det))
        if det[k] < MIN_DET_F:
            reasons.append(
                f"element {k + 1} near inversion: det F {det[k]:.3g} (limit {MIN_DET_F:.3g})"
            )
        return reasons

    def section_forces(
        self,
        pose_a: np.ndarray,
        pose_b: np.ndarray,
        internal: np.ndarray,
        gradient: np.ndarray | None = None,
    ) -> SectionForces:
        """Section resultants N (N) and M (N mm) along the deformed centre line.

        By equilibrium of the part of the solid beyond a cut, the resultant
        of the stresses on any cross-section through a centre-line node is
        the end face's reaction (the gradient on the end body's pose: the
        sum of the face's nodal forces, the whole depth's) carried there by
        statics. Unlike the raw peak stress, which is singular at the corners
        of the rigidly held end faces, it converges with the mesh at the rate
        of the reactions.
        """
        s = self.end_slot
        pose = np.asarray((pose_a, pose_b)[s], float)
        if gradient is not None:
            wrench = gradient[3 * s : 3 * s + 3]
        else:  # the end face's nodal forces: only its elements contribute
            x = self.positions(pose_a, pose_b, internal)
            face = self.end_faces[s]
            f = self._end_kernel.forces(x).reshape(-1, self.node_dim)[face]
            arm = x[face, :2] - pose[:2]
            wrench = np.array(
                [f[:, 0].sum(), f[:, 1].sum(), np.sum(arm[:, 0] * f[:, 1] - arm[:, 1] * f[:, 0])]
            )
        line = self.shape(pose_a, pose_b, internal)
        return statics_section_forces(
            line, self._centre_fractions, wrench, pose, axes=polyline_axes(line)
        )
