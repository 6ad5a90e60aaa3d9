"""A 3D hyperelastic solid of 27-node Lagrange hexahedra in total Lagrangian form.

The 3D counterpart of :mod:`.solid` (no plane assumption): the unknowns are
the current positions x (mm) of the nodes, three per node (dof ``3 n + i``).
The element is the triquadratic 27-node Lagrange hexahedron, the product of
the in-plane quad9 (Gmsh node order) and the 1D quadratic through the depth
(local node ``k * 9 + a``, :mod:`flexval.geometry.extrude`); it is
isoparametric and integrated with 3 x 3 x 3 Gauss points (full integration).
Shape functions and quadrature are the closed forms below, computed once.

The laws are those of the 2D model in 3D:

* Saint Venant-Kirchhoff, W = lam/2 (tr E)^2 + mu E:E, S = lam tr E I + 2 mu E;
* compressible neo-Hookean, W = mu/2 (I1 - 3) - mu ln J + lam/2 (ln J)^2,
  S = mu (I - C^-1) + lam ln J C^-1.

Both first elasticity tensors A_iJkL = dP_iJ / dF_kL have a closed form of
the shape ``delta_ik X_JL + a1 U_iJ U_kL + a2 U_iL U_kJ + Y_ik delta_JL``:
SVK with U = F, X = S, a1 = lam, a2 = mu, Y = mu F F^T; neo-Hookean with
U = F^-T, X = S + c C^-1, a1 = lam, a2 = c = mu - lam ln J, Y = 0. The
element tangent is then ``K_(a i)(b k) = sum_q dN_a/dX_J A_iJkL dN_b/dX_L w_q``,
batched over a chunk of elements at a time (two batched matrix products; the
81 x 81 element matrices of a chunk stay in a few MB).
Units: mm, N, MPa, N mm.
"""

from __future__ import annotations

import numpy as np

from .material import LAWS, lame

CHUNK = 64
"""Elements evaluated at once: their temporaries (27 points x 27 x 243 products each,
~1.3 MB per element) stay within a few tens of MB."""

_GAUSS = np.array([-np.sqrt(0.6), 0.0, np.sqrt(0.6)])
_GAUSS_W = np.array([5.0, 8.0, 5.0]) / 9.0
QUAD9_REFERENCE = np.array(
    [[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0], [0, 0]], float
)
"""Reference coordinates of the quad9 nodes in Gmsh order."""


def _lagrange(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic Lagrange functions through -1, 0, 1 and their derivatives at t, shape (3, ...)."""
    values = np.stack([0.5 * t * (t - 1.0), 1.0 - t * t, 0.5 * t * (t + 1.0)])
    slopes = np.stack([t - 0.5, -2.0 * t, t + 0.5])
    return values, slopes


def shape_functions(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 27 shape functions (m, 27) and their reference gradients (m, 27, 3) at
    ``points`` (m, 3) of the reference cube [-1, 1]^3 (local node k * 9 + a)."""
    lx, dx = _lagrange(points[:, 0])
    ly, dy = _lagrange(points[:, 1])
    lz, dz = _lagrange(points[:, 2])
    ia = (QUAD9_REFERENCE[:, 0] + 1).astype(int)
    ja = (QUAD9_REFERENCE[:, 1] + 1).astype(int)
    n2, n2x, n2y = lx[ia] * ly[ja], dx[ia] * ly[ja], lx[ia] * dy[ja]  # (9, m)
    values = (lz[:, None] * n2[None]).reshape(27, -1)
    grad = np.stack(
        [
            (lz[:, None] * n2x[None]).reshape(27, -1),
            (lz[:, None] * n2y[None]).reshape(27, -1),
            (dz[:, None] * n2[None]).reshape(27, -1),
        ],
        axis=-1,
    )
    return values.T, grad.transpose(1, 0, 2)


def gauss_points() -> tuple[np.ndarray, np.ndarray]:
    """The 3 x 3 x 3 Gauss points (27, 3) of [-1, 1]^3 and their weights (27,)."""
    p = np.stack(np.meshgrid(_GAUSS, _GAUSS, _GAUSS, indexing="ij"), -1).reshape(-1, 3)
    w = np.einsum("i,j,k->ijk", _GAUSS_W, _GAUSS_W, _GAUSS_W).ravel()
    return p, w


def reference_gradients(
    nodes: np.ndarray, elements: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shape-function gradients (n_el, 27 q, 27 a, 3) in 1/mm, det J (n_el, 27) and the Gauss
    weights (27,) at the quadrature points of the isoparametric elements.

    Raises
    ------
    ValueError
        If an element's Jacobian is not positive at a quadrature point (a
        folded or left-handed element).
    """
    points, weights = gauss_points()
    _, dref = shape_functions(points)  # (q, a, 3)
    xe = nodes[elements]  # (n_el, a, 3)
    jac = np.einsum("eai,qaj->eqij", xe, dref)  # dX_i / dxi_j
    det = np.linalg.det(jac)
    if not np.all(det > 0.0):
        raise ValueError("3D mesh: an element has a non-positive Jacobian")
    inv = np.linalg.inv(jac)  # dxi_j / dX_i  [j, i]
    grad = np.einsum("qaj,eqji->eqai", dref, inv)
    return grad, det, weights


def _svk(C: np.ndarray, lam: float, mu: float) -> tuple[np.ndarray, np.ndarray]:
    E = 0.5 * (C - np.eye(3))
    tr = np.trace(E, axis1=-2, axis2=-1)
    W = 0.5 * lam * tr**2 + mu * np.einsum("...ij,...ij->...", E, E)
    return W, 2.0 * mu * E + (lam * tr)[..., None, None] * np.eye(3)


def _neo_hookean(C: np.ndarray, lam: float, mu: float):
    Ci = np.linalg.inv(C)
    logJ = 0.5 * np.log(np.linalg.det(C))
    W = 0.5 * mu * (np.trace(C, axis1=-2, axis2=-1) - 3.0) - mu * logJ + 0.5 * lam * logJ**2
    S = mu * (np.eye(3) - Ci) + (lam * logJ)[..., None, None] * Ci
    return W, S, Ci, logJ


class Law3D:
    """A 3D hyperelastic law, ``'svk'`` or ``'neo-hookean'``, with the 3D Lame constants (MPa).

    Parameters
    ----------
    name : {'svk', 'neo-hookean'}
    youngs_modulus : float
        E, MPa.
    poisson_ratio : float
    """

    def __init__(self, name: str, youngs_modulus: float, poisson_ratio: float):
        if name not in LAWS:
            raise ValueError(f"unknown hyperelastic law {name!r}; expected one of {LAWS}")
        self.name = name
        self.lam, self.mu = lame(youngs_modulus, poisson_ratio)

    def stress(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Energy density W (MPa) and second Piola-Kirchhoff stress S (..., 3, 3), MPa, at F."""
        C = np.swapaxes(F, -1, -2) @ F
        if self.name == "svk":
            return _svk(C, self.lam, self.mu)
        W, S, _, _ = _neo_hookean(C, self.lam, self.mu)
        return W, S

    def tangent(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """W (MPa), S (..., 3, 3) and the first elasticity tensor A (..., 3, 3, 3, 3), MPa
        (the module docstring's closed forms)."""
        C = np.swapaxes(F, -1, -2) @ F
        eye = np.eye(3)
        if self.name == "svk":
            W, S = _svk(C, self.lam, self.mu)
            U, X, a2 = F, S, np.full(F.shape[:-2], self.mu)
            Y = self.mu * (F @ np.swapaxes(F, -1, -2))
        else:
            W, S, Ci, logJ = _neo_hookean(C, self.lam, self.mu)
            a2 = self.mu - self.lam * logJ
            U = np.swapaxes(np.linalg.inv(F), -1, -2)
            X, Y = S + a2[..., None, None] * Ci, None
        e = (...,) + (None,) * 4
        A = (
            eye[:, None, :, None] * X[..., None, :, None, :]
            + self.lam * U[..., :, :, None, None] * U[..., None, None, :, :]
            + a2[e] * U[..., :, None, None, :] * np.swapaxes(U, -1, -2)[..., None, :, :, None]
        )
        if Y is not None:
            A = A + Y[..., :, None, :, None] * eye[None, :, None, :]
        return W, S, A


class Solid3D:
    """A hexahedral hyperelastic solid (27-node Lagrange elements).

    Parameters
    ----------
    nodes : array (n_nodes, 3)
        Reference node positions, mm.
    elements : array (n_el, 27)
        Connectivity, local node ``k * 9 + a`` (:mod:`flexval.geometry.extrude`).
    law : Law3D
    factor : float
        Multiplies every integral (2 for a half-depth mesh: the mirror half's share).
    """

    def __init__(self, nodes: np.ndarray, elements: np.ndarray, law: Law3D, factor: float = 1.0):
        self.nodes = np.asarray(nodes, float)
        self.elements = np.asarray(elements, np.int64)
        self.law, self.factor = law, float(factor)
        grad, det, gw = reference_gradients(self.nodes, self.elements)
        self.grad = grad  # (n_el, q, a, 3)
        self._grad_a = np.ascontiguousarray(grad.transpose(0, 2, 1, 3)).reshape(-1, 27, 81)
        self.weight = factor * det * gw  # (n_el, q), mm^3
        n_el = self.elements.shape[0]
        self.element_dofs = (3 * self.elements[:, :, None] + np.arange(3)).reshape(n_el, 81)
        self.n_dofs = 3 * self.nodes.shape[0]

    @property
    def volume(self) -> float:
        """The mesh's volume times ``factor``, mm^3."""
        return float(self.weight.sum())

    def subset(self, elements: np.ndarray) -> Solid3D:
        """The solid of some of the elements (indices ``elements``), same node numbering."""
        part = object.__new__(Solid3D)
        part.nodes, part.law, part.factor = self.nodes, self.law, self.factor
        part.elements = self.elements[elements]
        part.grad, part.weight = self.grad[elements], self.weight[elements]
        part._grad_a = self._grad_a[elements]
        part.element_dofs, part.n_dofs = self.element_dofs[elements], self.n_dofs
        return part

    def _chunks(self):
        n_el = self.elements.shape[0]
        for lo in range(0, n_el, CHUNK):
            yield slice(lo, min(lo + CHUNK, n_el))

    def min_det(self, x: np.ndarray) -> np.ndarray:
        """Smallest det F (n_el,) over each element's quadrature points; x (n_nodes, 3), mm."""
        return np.concatenate(
            [
                np.linalg.det(self.deformation_gradient(x, part, check=False)).min(axis=1)
                for part in self._chunks()
            ]
        )

    def deformation_gradient(
        self, x: np.ndarray, part: slice = slice(None), check: bool = True
    ) -> np.ndarray:
        """F (n_el, 27, 3, 3) at the quadrature points of the elements ``part``; x (n_nodes, 3), mm.

        Raises
        ------
        ValueError
            If ``check`` and an element is inverted (det F <= 0 at a quadrature
            point): the multibody core then refuses the state and cuts the step.
        """
        xe = x[self.elements[part]]
        xe = xe - xe[:, :1]  # sum_a dN_a = 0: removes a translation, limits round-off
        F = np.swapaxes(xe, -1, -2)[:, None] @ self.grad[part]  # (e, q, i, J)
        if check and not np.all(np.linalg.det(F) > 0.0):
            raise ValueError("continuum 3D: inverted element (det F <= 0)")
        return F

    def energy(self, x: np.ndarray) -> float:
        """Strain energy, N mm, at node positions x (n_nodes, 3), mm."""
        total = 0.0
        for part in self._chunks():
            W, _ = self.law.stress(self.deformation_gradient(x, part))
            total += float(np.sum(W * self.weight[part]))
        return total

    def forces(self, x: np.ndarray) -> np.ndarray:
        """Nodal forces (n_dofs,) in N at node positions x (n_nodes, 3), mm (no tangent)."""
        f = np.empty((self.elements.shape[0], 81))
        for part in self._chunks():
            F = self.deformation_gradient(x, part)
            _, S = self.law.stress(F)
            f[part] = self._element_forces(F, S, part)
        return np.bincount(self.element_dofs.ravel(), weights=f.ravel(), minlength=self.n_dofs)

    def _element_forces(self, F: np.ndarray, S: np.ndarray, part: slice) -> np.ndarray:
        """sum_q dN_a/dX_J P_iJ w per element (e, 81), P = F S: one product of the gradients
        (e, a, (q J)) by the weighted P^T (e, (q J), i)."""
        PwT = np.swapaxes(F @ S, -1, -2) * self.weight[part][..., None, None]  # (e, q, J, i)
        return (self._grad_a[part] @ PwT.reshape(-1, 81, 3)).reshape(-1, 81)

    def evaluate(self, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """Energy (N mm), nodal forces (n_dofs,) in N and element tangents (n_el, 81, 81), N/mm.

        The tangents are in local dof order ``3 a + i`` (the rows and columns
        of :attr:`element_dofs`).
        """
        n_el = self.elements.shape[0]
        energy = 0.0
        f = np.empty((n_el, 81))
        K = np.empty((n_el, 81, 81))
        for part in self._chunks():
            F = self.deformation_gradient(x, part)
            W, S, A = self.law.tangent(F)
            w = self.weight[part]
            energy += float(np.sum(W * w))
            f[part] = self._element_forces(F, S, part)
            G = self.grad[part]  # (e, q, a, J)
            ne = G.shape[0]
            Aw = np.empty((ne, 27, 3, 3, 3, 3))  # weighted A, laid out [J, i, k, L]
            np.multiply(A.transpose(0, 1, 3, 2, 4, 5), w[..., None, None, None, None], out=Aw)
            T = Aw.reshape(ne, 27, 27, 3) @ np.swapaxes(G, -1, -2)  # (e, q, (J i k), b)
            Ke = self._grad_a[part] @ T.reshape(ne, 81, 243)  # (e, a, (i k b))
            K[part] = Ke.reshape(ne, 27, 3, 3, 27).transpose(0, 1, 2, 4, 3).reshape(ne, 81, 81)
        forces = np.bincount(self.element_dofs.ravel(), weights=f.ravel(), minlength=self.n_dofs)
        return energy, forces, K
