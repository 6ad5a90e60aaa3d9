"""Continuum3DConnector: one flexure meshed as a 3D solid, a connector of the multibody core.

The flexure is its in-plane quad9 mesh extruded through the depth into
27-node Lagrange hexahedra (:mod:`flexval.geometry.extrude`), by default
over half the depth, z in [0, b/2]: a planar mechanism loads it
symmetrically about the mid-plane, so the mid-plane nodes keep z = 0 and the
energy, gradient and Hessian of the half are doubled (a weight factor of 2
in :class:`.solid3d.Solid3D`).

Internal coordinates: the in-plane displacements (mm) of the nodes off the
end faces, node layer by node layer (within a layer in the order of the 2D
connector's free nodes), then the out-of-plane displacements of those not
on the mid-plane. The nodes of each end face, all through the depth, follow
their rigid body exactly in plane, (x, y) = x_body + R(theta) (X - X_body),
and keep their reference z: the bodies' out-of-plane motions are held, as
in a planar mechanism. The chain rule over these constraints is that of the
2D :class:`.connector.ContinuumConnector` (g = T^T f, H = T^T K T plus the
faces' second derivatives in theta), with nodal dofs that expand into two
coordinates (an end face's x or y: the body's translation and rotation),
one (a free dof) or none (an end face's z, a mid-plane z).

Every node layer is a deformed copy of the 2D mesh, so the 2D load-stepping
predictor and Newton update (:mod:`.polar`: section by section, as finite
turns) apply layer by layer to the in-plane coordinates; the out-of-plane
ones are extrapolated and updated linearly.
Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np

from flexval.geometry import Flexure, Mechanism
from flexval.geometry.extrude import ExtrudedMesh, extruded_mesh
from flexval.geometry.kinematics import rigid_points
from flexval.reducedmodels.core.connector import Connector, LocalState
from flexval.reducedmodels.core.sections import (
    polyline_fractions,
)

from .connector import ContinuumConnector
from .endfaces import HeldEndFaces
from .group import ContinuumGroup
from .solid3d import Law3D, Solid3D


class Continuum3DConnector(HeldEndFaces, Connector):
    """A flexure meshed as a 3D hyperelastic solid (a :class:`reducedmodels.Connector`).

    Parameters
    ----------
    flexure : Flexure
    mechanism : Mechanism
        Gives the material and the bodies' reference points.
    level : int
        Mesh level: the in-plane mesh of ``continuum:LEVEL`` and the layers
        through the depth (:func:`flexval.geometry.extrude.layers`).
    law : {'svk', 'neo-hookean'}
    half : bool
        Mesh half the depth and double it (default); False meshes the whole
        depth (no symmetry used; for checks).
    mesh : ExtrudedMesh, optional
        A ready mesh (default: :func:`flexval.geometry.extrude.extruded_mesh`).
    """

    node_dim = 3
    update_above = 0.0
    """Newton corrections always go through :meth:`update_internal` (as in the 2D connector:
    mesh nodes are a fraction of the thickness apart)."""

    def __init__(
        self,
        flexure: Flexure,
        mechanism: Mechanism,
        level: int,
        law: str = "svk",
        half: bool = True,
        mesh: ExtrudedMesh | None = None,
    ):
        self.name = flexure.name
        self.bodies = tuple(flexure.bodies)
        self.law, self.material = law, mechanism.material
        if mesh is None:
            mesh = extruded_mesh(flexure.shape, flexure.section, level, half)
        self.mesh = mesh
        # the 2D connector of the same in-plane mesh: its end faces, free nodes and
        # cross-sections, whose polar predictor and update serve every node layer
        self.plane = ContinuumConnector(flexure, mechanism, level, law, "stress", mesh.plane)
        self.solid3d = Solid3D(
            mesh.nodes,
            mesh.elements,
            Law3D(law, self.material.youngs_modulus, self.material.poisson_ratio),
            2.0 if mesh.half else 1.0,
        )
        n_layers = mesh.z.size
        self._n_layers = n_layers
        self.end_faces = [mesh.layer_nodes(self.plane.end_faces[s]).ravel() for s in (0, 1)]
        self.end_offsets = [np.tile(self.plane.end_offsets[s], (n_layers, 1)) for s in (0, 1)]
        self._free = mesh.layer_nodes(self.plane.free_nodes).ravel()
        z_layers = np.arange(n_layers)
        if mesh.half:
            z_layers = z_layers[z_layers != mesh.mid_layer]
        self._free_z = mesh.layer_nodes(self.plane.free_nodes, z_layers).ravel()
        self.end_slot = self.plane.end_slot
        self._centre_fractions = polyline_fractions(mesh.plane.nodes[mesh.plane.centre_line])
        end_face = self.end_faces[self.end_slot]
        self.elastic = self.solid3d  # what HeldEndFaces evaluates
        self._end_kernel = self.solid3d.subset(
            np.flatnonzero(np.isin(mesh.elements, end_face).any(axis=1))
        )
        self.n_internal = 2 * self._free.size + self._free_z.size
        self._n = 6 + self.n_internal
        self._build_expansion()

    # --- the fixed index structure of T ------------------------------------
    def _build_expansion(self) -> None:
        """Index arrays of T: nodal dofs -> coordinates, element entries -> Hessian entries.

        Each nodal dof ``3 n + i`` expands into ``counts`` coordinates: 1 (a
        free dof, coefficient 1), 2 (an end face's x or y: the body's
        translation, coefficient 1, and rotation, coefficient dx/dtheta) or 0.
        """
        n_dofs = self.solid3d.n_dofs
        counts = np.zeros(n_dofs, np.int64)
        first = np.full(n_dofs, -1, np.int64)
        n_free = self._free.size
        for i in (0, 1):
            counts[3 * self._free + i] = 1
            first[3 * self._free + i] = 6 + 2 * np.arange(n_free) + i
        counts[3 * self._free_z + 2] = 1
        first[3 * self._free_z + 2] = 6 + 2 * n_free + np.arange(self._free_z.size)
        face_dofs = []
        for s in (0, 1):
            d = (3 * self.end_faces[s][:, None] + np.arange(2)).ravel()  # (x, y) per face node
            counts[d] = 2
            first[d] = 3 * s + np.tile([0, 1], self.end_faces[s].size)
            face_dofs.append(d)
        start = np.concatenate([[0], np.cumsum(counts)])
        exp_dof = np.repeat(np.arange(n_dofs), counts)
        exp_z = np.empty(start[-1], np.int64)
        used = counts > 0
        exp_z[start[:-1][used]] = first[used]
        theta_pos = []
        for s, d in enumerate(face_dofs):
            exp_z[start[d] + 1] = 3 * s + 2
            theta_pos.append(start[d] + 1)
        self.exp_dof, self.exp_z, self.theta_pos = exp_dof, exp_z, theta_pos
        # element-matrix entries (e, r, c), flat, -> plain ones and expanded ones
        edofs = self.solid3d.element_dofs
        per_el = 81 * 81
        r_of = np.repeat(np.arange(81), 81)
        c_of = np.tile(np.arange(81), 81)
        plain_src, mixed = [], []
        for e0 in range(0, edofs.shape[0], 256):  # bounded temporaries
            dofs = edofs[e0 : e0 + 256]
            r, c = dofs[:, r_of].ravel(), dofs[:, c_of].ravel()
            nr, nc = counts[r], counts[c]
            base = e0 * per_el
            plain = (nr == 1) & (nc == 1)
            plain_src.append(base + np.flatnonzero(plain))
            rest = np.flatnonzero(~plain & (nr > 0) & (nc > 0))
            mixed.append((base + rest, r[rest], c[rest]))
        # int32 where it fits: the largest index array, one entry per plain Hessian value
        index = np.int32 if edofs.shape[0] * per_el < 2**31 else np.int64
        self.plain_src = np.concatenate(plain_src).astype(index)
        t = np.concatenate([m[0] for m in mixed])
        r = np.concatenate([m[1] for m in mixed])
        c = np.concatenate([m[2] for m in mixed])
        nr, nc = counts[r], counts[c]
        total = nr * nc
        tt = np.repeat(np.arange(t.size), total)
        within = np.arange(total.sum()) - np.repeat(np.cumsum(total) - total, total)
        p = start[r][tt] + within // nc[tt]
        q = start[c][tt] + within % nc[tt]
        self.mixed = (t[tt], p, q)
        flat_r = edofs[self.plain_src // per_el, r_of[self.plain_src % per_el]]
        flat_c = edofs[self.plain_src // per_el, c_of[self.plain_src % per_el]]
        self.pattern_rows = np.concatenate([first[flat_r], exp_z[p], [2, 5]])
        self.pattern_cols = np.concatenate([first[flat_c], exp_z[q], [2, 5]])

    @functools.cached_property
    def _layers(self) -> ContinuumGroup:
        """The 2D connector once per node layer: the in-plane predictor and update."""
        return ContinuumGroup([self.plane] * self._n_layers)

    def _split(self, internal: np.ndarray) -> list[np.ndarray]:
        """The in-plane coordinates of each node layer (views of ``internal``)."""
        return np.split(internal[: 2 * self._free.size], self._n_layers)

    # --- Connector protocol --------------------------------------------------
    def positions(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Current positions of all mesh nodes (n_nodes, 3), mm."""
        x = self.mesh.nodes.copy()
        n = 2 * self._free.size
        x[self._free, :2] += internal[:n].reshape(-1, 2)
        x[self._free_z, 2] += internal[n:]
        for s, pose in enumerate((pose_a, pose_b)):
            x[self.end_faces[s], :2] = rigid_points(np.asarray(pose, float), self.end_offsets[s])[0]
        return x

    def predict_internal(
        self,
        states: Sequence[LocalState],
        weights: Sequence[float],
        pose_a: np.ndarray,
        pose_b: np.ndarray,
    ) -> np.ndarray:
        """In-plane coordinates extrapolated section by section on every node layer
        (:meth:`.group.ContinuumGroup.predict_internal`), out-of-plane ones linearly, mm."""
        past = [[(s[0], s[1], xy) for xy in self._split(s[2])] for s in states]
        xy = self._layers.predict_internal(past, weights, [(pose_a, pose_b)] * self._n_layers)
        n = 2 * self._free.size
        z = sum(w * s[2][n:] for w, s in zip(weights, states))
        return np.concatenate([xy, z])

    def update_internal(self, old: LocalState, new: LocalState) -> np.ndarray:
        """In-plane coordinates after a Newton correction turned section by section on every
        node layer (:meth:`.group.ContinuumGroup.update_internal`), out-of-plane ones linear."""
        layers_old = [(old[0], old[1], xy) for xy in self._split(old[2])]
        layers_new = [(new[0], new[1], xy) for xy in self._split(new[2])]
        xy = self._layers.update_internal(layers_old, layers_new)
        return np.concatenate([xy, new[2][2 * self._free.size :]])

    def _min_det(self, x: np.ndarray) -> np.ndarray:
        """Each element's smallest det F over its quadrature points at positions ``x``."""
        return self.solid3d.min_det(x)

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Deformed centre line on the mid-plane (start to end), (x, y) in mm."""
        return self.positions(pose_a, pose_b, internal)[self.mesh.centre_line, :2]
