"""ContinuumConnector: one meshed flexure as a connector of the multibody core.

Its internal coordinates are the displacements (mm) of the mesh nodes that
are not on an end face, two per node. The nodes of each end face follow
their rigid body exactly: x = x_body + R(theta) (X - X_ref_body). The strain
energy of the solid is then a function of [pose_a, pose_b, internal]; its
gradient and Hessian follow by the chain rule of :mod:`.endfaces`, over the
index arrays this connector builds once (:meth:`ContinuumConnector._build_expansion`):
every nodal dof expands into one (free) or two (face: body translation and
rotation) coordinates. Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp

from flexval.geometry import Flexure, Mechanism
from flexval.geometry.kinematics import rigid_points
from flexval.geometry.mesh import FlexureMesh
from flexval.geometry.outline import flexure_mesh
from flexval.reducedmodels.core.connector import Connector, ConnectorGroup, LocalState
from flexval.reducedmodels.core.inertia import MassPoints
from flexval.reducedmodels.core.sections import (
    polyline_fractions,
)

from .endfaces import HeldEndFaces
from .group import ContinuumGroup
from .mass import face_accelerations, node_jacobian, scalar_mass
from .material import make_law
from .polar import cross_sections
from .recovery import PatchRecovery
from .solid import Solid


class ContinuumConnector(HeldEndFaces, Connector):
    """A flexure meshed as a 2D hyperelastic solid (a :class:`reducedmodels.Connector`).

    Parameters
    ----------
    flexure : Flexure
    mechanism : Mechanism
        Gives the material and the bodies' reference points.
    level : int
        Mesh level (see :mod:`flexval.geometry.mesh`).
    law : {'svk', 'neo-hookean'}
    plane : {'stress', 'strain'}
    mesh : FlexureMesh, optional
        A ready mesh (default: :func:`flexval.geometry.outline.flexure_mesh` of the flexure:
        the true outline of a varying section or a free-form centre line).
    """

    update_above = 0.0
    """Newton corrections always go through :meth:`update_internal`: mesh nodes are a
    fraction of the thickness apart, so a scaled correction of 1e-4 (of the
    mechanism size) already turns a section by ~1e-2 rad and a linear update
    leaves a stretch of ~5e-5, forces tens of times the open chain's loads;
    updating always cut open-chain f+ from 77 to 54 Newton iterations."""

    def __init__(
        self,
        flexure: Flexure,
        mechanism: Mechanism,
        level: int,
        law: str = "svk",
        plane: str = "stress",
        mesh: FlexureMesh | None = None,
    ):
        self.name = flexure.name
        self.bodies = tuple(flexure.bodies)
        self.mesh = flexure_mesh(flexure.shape, flexure.section, level) if mesh is None else mesh
        self.law, self.plane, self.material = law, plane, mechanism.material
        self.solid = Solid(
            self.mesh.nodes,
            self.mesh.elements,
            make_law(law, plane, self.material.youngs_modulus, self.material.poisson_ratio),
            flexure.section.depth,
        )
        faces = [self.mesh.start_face, self.mesh.end_face]
        if flexure.start_body != self.bodies[0]:
            faces.reverse()
        self.end_faces = faces  # end-face nodes held by body a, by body b
        role = np.full(self.mesh.nodes.shape[0], -1)
        role[faces[0]], role[faces[1]] = 0, 1
        self.end_offsets = [
            self.mesh.nodes[faces[s]] - mechanism.bodies[self.bodies[s]].reference for s in (0, 1)
        ]
        self._free = np.flatnonzero(role < 0)
        self.end_slot = self.bodies.index(flexure.end_body)
        self._centre_fractions = polyline_fractions(self.mesh.nodes[self.mesh.centre_line])
        end_face = self.end_faces[self.end_slot]
        self.elastic = self.solid  # what HeldEndFaces evaluates
        self._end_kernel = self.solid.kernel.subset(
            np.flatnonzero(np.isin(self.mesh.elements, end_face).any(axis=1))
        )
        self.n_internal = 2 * self._free.size
        self._n = 6 + self.n_internal
        self.sections = cross_sections(self.mesh)
        self._unit_mass = None  # kron(scalar mass, I2), on first use
        self._build_expansion(role)

    # --- the fixed index structure of T ------------------------------------
    def _build_expansion(self, role: np.ndarray) -> None:
        """Index arrays of T: nodal dofs -> coordinates, element entries -> Hessian entries.

        ``role`` is -1 for a free node, 0 or 1 for a node held by body a or b.
        """
        n_nodes = role.size
        counts = np.where(role < 0, 1, 2).repeat(2)  # per nodal dof
        start = np.concatenate([[0], np.cumsum(counts)])
        exp_dof = np.repeat(np.arange(2 * n_nodes), counts)
        exp_z = np.empty(start[-1], np.int64)
        free_dofs = (2 * self._free[:, None] + np.arange(2)).ravel()
        exp_z[start[free_dofs]] = 6 + np.arange(free_dofs.size)
        theta_pos = []
        for s in (0, 1):
            d = (2 * self.end_faces[s][:, None] + np.arange(2)).ravel()  # (x, y) per face node
            exp_z[start[d]] = 3 * s + np.tile([0, 1], self.end_faces[s].size)
            exp_z[start[d] + 1] = 3 * s + 2
            theta_pos.append(start[d] + 1)
        self.exp_dof, self.exp_z = exp_dof, exp_z
        self.theta_pos = theta_pos  # positions of the rotation coefficients
        # element-matrix entries -> pairs of expansions
        r, c = self.solid.rows, self.solid.cols
        nr, nc = counts[r], counts[c]
        total = nr * nc
        t = np.repeat(np.arange(r.size), total)
        within = np.arange(total.sum()) - np.repeat(np.cumsum(total) - total, total)
        p = start[r][t] + within // nc[t]
        q = start[c][t] + within % nc[t]
        plain = (counts[r][t] == 1) & (counts[c][t] == 1)
        self.plain_src = t[plain]
        self.mixed = (t[~plain], p[~plain], q[~plain])
        self.mixed_first = within[~plain] == 0  # both first expansions: coefficient 1
        rows = np.concatenate([exp_z[p[plain]], exp_z[p[~plain]], [2, 5]])
        cols = np.concatenate([exp_z[q[plain]], exp_z[q[~plain]], [2, 5]])
        self.pattern_rows, self.pattern_cols = rows, cols

    @classmethod
    def group(cls, connectors: Sequence[ContinuumConnector]) -> ConnectorGroup:
        """One :class:`.group.ContinuumGroup` when the flexures share law, plane and material
        (the run's case: one stacked element kernel), else one by one."""
        first = connectors[0]
        key = (first.law, first.plane, first.material)
        if all((c.law, c.plane, c.material) == key for c in connectors):
            return ContinuumGroup(connectors)
        return ConnectorGroup(connectors)

    @functools.cached_property
    def _alone(self) -> ContinuumGroup:
        """A group of this connector alone: its predictor and Newton update."""
        return ContinuumGroup([self])

    @functools.cached_property
    def recovery(self) -> PatchRecovery:
        """Stress recovery at the nodes (:mod:`.recovery`), built on first use."""
        return PatchRecovery(self.solid.mesh, self.mesh.elements, self.sections)

    @property
    def free_nodes(self) -> np.ndarray:
        """Mesh nodes whose displacements are the internal coordinates, in their order."""
        return self._free

    # --- Connector protocol --------------------------------------------------
    def positions(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Current positions of all mesh nodes (n_nodes, 2), mm."""
        x = self.mesh.nodes.copy()
        x[self._free] += internal.reshape(-1, 2)
        for s, pose in enumerate((pose_a, pose_b)):
            x[self.end_faces[s]] = rigid_points(np.asarray(pose, float), self.end_offsets[s])[0]
        return x

    def predict_internal(
        self,
        states: Sequence[LocalState],
        weights: Sequence[float],
        pose_a: np.ndarray,
        pose_b: np.ndarray,
    ) -> np.ndarray:
        """Interior nodes extrapolated section by section (mm; the load stepping's predictor).

        Chord lengths and directions between the section centres, section
        rotations and the nodes' offsets in their section's frame are
        extrapolated with ``weights`` over the converged ``states``
        (:mod:`.polar`), and the sections are rebuilt between the end faces
        at the bodies' predicted poses ``pose_a``, ``pose_b``.
        """
        return self._alone.predict_internal(
            [[state] for state in states], weights, [(pose_a, pose_b)]
        )

    def update_internal(self, old: LocalState, new: LocalState) -> np.ndarray:
        """Interior nodes after a Newton correction, turned section by section (mm).

        ``new`` is the linearly corrected state; the rule (and why) is
        :meth:`.group.ContinuumGroup.update_internal`'s, for this one flexure.
        """
        return self._alone.update_internal([old], [new])

    def _min_det(self, x: np.ndarray) -> np.ndarray:
        """Each element's smallest det F over its quadrature points at positions ``x``."""
        F = self.solid.deformation_gradient(x)
        return (F[..., 0, 0] * F[..., 1, 1] - F[..., 0, 1] * F[..., 1, 0]).min(axis=1)

    # --- optional mass hook (flexval.reducedmodels.core.inertia) ---------------------------
    def mass_points(self, density: float) -> MassPoints:
        """Each node's row sum of the consistent mass (t) as a point: carries the weight."""
        lumped = np.asarray(scalar_mass(self.solid).sum(axis=1)).ravel() * density
        dofs = np.full((lumped.size, 3), -1)
        rel = np.zeros((lumped.size, 2))
        dofs[self._free, 0] = 6 + 2 * np.arange(self._free.size)
        dofs[self._free, 1] = dofs[self._free, 0] + 1
        for s in (0, 1):
            dofs[self.end_faces[s]] = np.arange(3 * s, 3 * s + 3)
            rel[self.end_faces[s]] = self.end_offsets[s]
        return MassPoints(dofs, rel, lumped, np.zeros(lumped.size))

    def _mass_kinematics(
        self, density: float, pose_a: np.ndarray, pose_b: np.ndarray
    ) -> tuple[sp.csr_matrix, list[np.ndarray], sp.csr_matrix]:
        """The nodal consistent mass (t), the end faces' rotated offsets (mm) and T = dx/dq."""
        if self._unit_mass is None:  # density-free, assembled once
            self._unit_mass = sp.kron(scalar_mass(self.solid), sp.identity(2), format="csr")
        rotated = [
            rigid_points(np.asarray(p, float), r)[0] - np.asarray(p, float)[:2]
            for p, r in zip((pose_a, pose_b), self.end_offsets)
        ]
        T = node_jacobian(self.mesh.nodes.shape[0], self._free, self.end_faces, rotated)
        return self._unit_mass * density, rotated, T

    def mass_matrix(
        self, density: float, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> sp.csr_matrix:
        """Consistent mass T^T M T (t, t mm, t mm^2) over [pose_a, pose_b, internal]."""
        m, _, T = self._mass_kinematics(density, pose_a, pose_b)
        return (T.T @ m @ T).tocsr()

    def convective_forces(
        self,
        density: float,
        pose_a: np.ndarray,
        pose_b: np.ndarray,
        internal: np.ndarray,
        velocity: np.ndarray,
    ) -> np.ndarray:
        """T^T M a_c (N, N mm): the end faces' centripetal inertia (see :mod:`.mass`).

        ``velocity`` holds the local coordinates' rates (mm/s, rad/s).
        """
        m, rotated, T = self._mass_kinematics(density, pose_a, pose_b)
        a_c = face_accelerations(
            self.mesh.nodes.shape[0],
            self.end_faces,
            rotated,
            (float(velocity[2]), float(velocity[5])),
        )
        return T.T @ (m @ a_c)

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Deformed centre line (nodes at mid-thickness, start to end), mm."""
        return self.positions(pose_a, pose_b, internal)[self.mesh.centre_line]
