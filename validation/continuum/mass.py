"""Mass of a meshed flexure: the consistent mass matrix from scikit-fem.

M_(a i)(b k) = delta_ik rho b int N_a N_b dA over the quad9 mesh (the same
basis and 3 x 3 Gauss rule as the stiffness, exact for the product of two
biquadratic functions on straight-sided elements). The nodes of an end face
follow their rigid body, x = p + R(theta) rel, so over the connector's
coordinates [pose_a, pose_b, internal] the mass is T^T M T with T = dx/dq at
the current state. The weight of node a is (sum_b M_ab) g, the consistent
load of a uniform body force.

The inertia forces of the coordinates are T^T M x'' with
x'' = T q'' + T' q' (Lagrange's equations for a kinetic energy
1/2 x'^T M x' with M constant and x = x(q)): the mass T^T M T times q''
plus the convective forces T^T M a_c, where a_c = T' q' is zero on the free
nodes and the centripetal -theta_s'^2 R(theta_s) rel on the nodes of end
face s.

Units: t/mm^3 (density), t, mm.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import BilinearForm

from .solid import Solid


@BilinearForm
def _mass_form(u, v, _):
    return u * v


def scalar_mass(solid: Solid) -> sp.csr_matrix:
    """int N_a N_b b dA over the mesh, in the mesh's node numbering (mm^3)."""
    m = _mass_form.assemble(solid.basis).tocsr() * solid.depth
    order = solid.node_dofs  # skfem dof of each mesh node
    return m[order][:, order].tocsr()


def node_jacobian(
    n_nodes: int, free: np.ndarray, faces: list[np.ndarray], rotated: list[np.ndarray]
) -> sp.csr_matrix:
    """dx/dq (2 n_nodes, 6 + 2 n_free) of the node positions with respect to the coordinates.

    Free node j's (x, y) are the coordinates 6 + 2 j + i; an end-face node
    of slot s moves with its body's pose: d/d(x_s, y_s) = identity,
    d/dtheta_s = k x R(theta_s) rel = (-r_y, r_x) with ``rotated`` r.
    """
    rows, cols, vals = [], [], []
    for i in range(2):
        rows.append(2 * free + i)
        cols.append(6 + 2 * np.arange(free.size) + i)
        vals.append(np.ones(free.size))
    for s, (face, r) in enumerate(zip(faces, rotated)):
        for i in range(2):
            rows += [2 * face + i, 2 * face + i]
            cols += [np.full(face.size, 3 * s + i), np.full(face.size, 3 * s + 2)]
            vals += [np.ones(face.size), -r[:, 1] if i == 0 else r[:, 0]]
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(2 * n_nodes, 6 + 2 * free.size),
    )


def face_accelerations(
    n_nodes: int, faces: list[np.ndarray], rotated: list[np.ndarray], rates: tuple[float, float]
) -> np.ndarray:
    """a_c = T' q' (2 n_nodes, mm/s^2): -omega_s^2 r on the nodes of end face s, 0 elsewhere.

    ``rotated`` holds each face's current offsets r = R(theta_s) rel (mm) and
    ``rates`` the two bodies' angular velocities omega_s (rad/s).
    """
    a = np.zeros(2 * n_nodes)
    for face, r, omega in zip(faces, rotated, rates):
        a[2 * face] = -(omega**2) * r[:, 0]
        a[2 * face + 1] = -(omega**2) * r[:, 1]
    return a
