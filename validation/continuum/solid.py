"""A 2D hyperelastic solid in total Lagrangian form: energy, internal forces, tangent.

The unknowns are the current positions x (mm) of the mesh nodes, two per
node (dof ``2 n + i``). scikit-fem provides the mesh (:class:`MeshQuad2`,
isoparametric quad9), the 3x3 Gauss quadrature, the reference shape-function
gradients and the integration weights (``CellBasis``); these are computed
once. The nonlinear element kernels are then batched numpy over all
elements and quadrature points at once (no Python loop over elements or over
pairs of local basis functions): deformation gradient F, C = F^T F, the law's
W, S and CC, the first Piola stress P = F S, and the tangent

    A_iJkL = delta_ik S_JL + F_iM CC_MJNL F_kN,
    K_(a i)(b k) = sum_q dN_a/dX_J A_iJkL dN_b/dX_L  b w_q.

(An skfem ``BilinearForm`` over ``ElementVector(ElementQuad2())`` gives the
same matrix but loops over the 18 x 18 local pairs in Python and measured
30 times slower on a 4000-element flexure.) The element matrices are
returned as data for a fixed COO pattern computed once. Energies are per
unit depth multiplied by the depth b. Units: mm, N, MPa, N mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import CellBasis, ElementQuad2, MeshQuad2

from .material import Law

_QUADRATURE_ORDER = 4   # 3 x 3 Gauss points: full integration of quad9
_VOIGT = (np.array([0, 1, 0]), np.array([0, 1, 1]))   # (M, N) of E11, E22, 2 E12


@dataclass
class ElementState:
    """Kinematics and stresses at the quadrature points (all shaped (n_el, n_q, ...))."""

    F: np.ndarray     # deformation gradient (2, 2)
    C: np.ndarray     # right Cauchy-Green tensor (2, 2)
    W: np.ndarray     # energy density, MPa
    S: np.ndarray     # second Piola-Kirchhoff stress (2, 2), MPa
    CC: np.ndarray    # material tangent (2, 2, 2, 2), MPa


class ElementKernel:
    """The nonlinear element computations over a set of quad9 elements (no scikit-fem objects).

    Parameters
    ----------
    elements : array (n_el, 9)
        Quad9 connectivity into a node array of ``n_nodes`` nodes.
    grad : array (n_el, n_q, 9, 2)
        Reference shape-function gradients at the quadrature points, 1/mm.
    weight : array (n_el, n_q)
        Integration weights times the depth, mm^3.
    law : callable
        C -> (W, S, CC), see :mod:`.material`.
    n_nodes : int
    """

    def __init__(self, elements: np.ndarray, grad: np.ndarray, weight: np.ndarray, law: Law,
                 n_nodes: int):
        self.elements, self.grad, self.weight, self.law = elements, grad, weight, law
        n_el, n_q = weight.shape
        self._grad_qb = np.ascontiguousarray(
            grad.transpose(0, 1, 3, 2).reshape(n_el, 2 * n_q, 9))          # [(q, L), b]
        edofs = (2 * elements[:, :, None] + np.arange(2)).reshape(n_el, 18)
        self.element_dofs = edofs
        self.rows = np.repeat(edofs, 18, axis=1).ravel()
        self.cols = np.tile(edofs, (1, 18)).ravel()
        self.n_dofs = 2 * n_nodes

    @classmethod
    def stack(cls, kernels: "list[ElementKernel]") -> "ElementKernel":
        """One kernel over the elements of all ``kernels`` (their nodes numbered one after the
        other, in order); the first kernel's law serves all."""
        offsets = np.cumsum([0] + [k.n_dofs // 2 for k in kernels])
        return cls(np.concatenate([k.elements + o for k, o in zip(kernels, offsets)]),
                   np.concatenate([k.grad for k in kernels]),
                   np.concatenate([k.weight for k in kernels]), kernels[0].law, int(offsets[-1]))

    def subset(self, elements: np.ndarray) -> "ElementKernel":
        """The kernel of some of the elements (indices ``elements``), same node numbering."""
        return ElementKernel(self.elements[elements], self.grad[elements], self.weight[elements],
                             self.law, self.n_dofs // 2)

    def deformation_gradient(self, x: np.ndarray) -> np.ndarray:
        """Deformation gradient F (n_el, n_q, 2, 2) at the quadrature points; x: node positions, mm."""
        xe = x[self.elements]
        xe = xe - xe[:, :1]            # sum_a dN_a = 0: removes a translation, limits round-off
        n_el, n_q = self.weight.shape
        F = np.matmul(xe.transpose(0, 2, 1), self._grad_qb.transpose(0, 2, 1))   # [i, (q, J)]
        return F.reshape(n_el, 2, n_q, 2).transpose(0, 2, 1, 3)

    def state(self, x: np.ndarray) -> ElementState:
        """Kinematics and stresses at the quadrature points for node positions x (n_nodes, 2).

        Raises
        ------
        ValueError
            If an element is inverted (det F <= 0 at a quadrature point): the
            multibody core then treats the state as refused and cuts the step.
        """
        F = self.deformation_gradient(x)                                   # (n_el, n_q, 2, 2)
        F00, F01, F10, F11 = F[..., 0, 0], F[..., 0, 1], F[..., 1, 0], F[..., 1, 1]
        if not np.all(F00 * F11 - F01 * F10 > 0.0):
            raise ValueError("continuum: inverted element (det F <= 0)")
        C = np.empty(F.shape)                                               # F^T F
        C[..., 0, 0] = F00 * F00 + F10 * F10
        C[..., 1, 1] = F01 * F01 + F11 * F11
        C[..., 0, 1] = C[..., 1, 0] = F00 * F01 + F10 * F11
        W, S, CC = self.law(C)
        return ElementState(F, C, W, S, CC)

    def _strain_operator(self, F: np.ndarray) -> np.ndarray:
        """B[(q, v), (a, i)] (n_el, 3 n_q, 18): dE_v = B dx_(a, i), v = E11, E22, 2 E12."""
        g0, g1 = self.grad[..., 0], self.grad[..., 1]                       # (n_el, n_q, 9)
        n_el, n_q = self.weight.shape
        B = np.empty((n_el, n_q, 3, 9, 2))
        for i in (0, 1):
            f0, f1 = F[..., i, 0, None], F[..., i, 1, None]
            B[:, :, 0, :, i] = g0 * f0
            B[:, :, 1, :, i] = g1 * f1
            B[:, :, 2, :, i] = g1 * f0 + g0 * f1
        return B.reshape(n_el, 3 * n_q, 18)

    def _nodal_forces(self, B: np.ndarray, sw: np.ndarray) -> np.ndarray:
        """Nodal forces (n_dofs,) in N, sum_q B^T S w, from the weighted Voigt stresses sw."""
        fe = np.matmul(sw.reshape(sw.shape[0], 1, -1), B)
        return np.bincount(self.element_dofs.ravel(), weights=fe.ravel(), minlength=self.n_dofs)

    def forces(self, x: np.ndarray) -> np.ndarray:
        """Nodal forces (n_dofs,) in N at node positions x (n_nodes, 2), mm (no tangent)."""
        st = self.state(x)
        return self._nodal_forces(self._strain_operator(st.F),
                                  st.S[..., _VOIGT[0], _VOIGT[1]] * self.weight[..., None])

    def evaluate(self, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """Energy (N mm), nodal forces (n_dofs,) in N and element tangents (n_el, 18, 18) in N/mm.

        The tangents are the data of the COO pattern ``(rows, cols)``
        (``Ke.ravel()``), duplicates to be summed.
        """
        st = self.state(x)
        S, w = st.S, self.weight
        g0, g1 = self.grad[..., 0], self.grad[..., 1]                       # (n_el, n_q, 9)
        n_el, n_q = w.shape
        B = self._strain_operator(st.F)                                     # [(q, v), (a, i)]
        sw = S[..., _VOIGT[0], _VOIGT[1]] * w[..., None]                    # (n_el, n_q, 3)
        forces = self._nodal_forces(B, sw)
        # material part sum_q B^T D B w, D the Voigt form of CC
        D = st.CC[..., _VOIGT[0][:, None], _VOIGT[1][:, None], _VOIGT[0], _VOIGT[1]] \
            * w[..., None, None]
        DB = np.matmul(D, B.reshape(n_el, n_q, 3, 18)).reshape(n_el, 3 * n_q, 18)
        Ke = np.matmul(B.transpose(0, 2, 1), DB)                            # (n_el, 18, 18)
        # geometric part delta_ik sum_q (g S g^T)_ab w
        GS = np.empty((n_el, n_q, 2, 9))
        GS[:, :, 0] = (sw[..., 0, None] * g0 + sw[..., 2, None] * g1)
        GS[:, :, 1] = (sw[..., 2, None] * g0 + sw[..., 1, None] * g1)
        Kg = np.matmul(GS.reshape(n_el, 2 * n_q, 9).transpose(0, 2, 1), self._grad_qb)
        Ke[:, 0::2, 0::2] += Kg
        Ke[:, 1::2, 1::2] += Kg
        return float(np.sum(st.W * self.weight)), forces, Ke


class Solid:
    """Quad9 hyperelastic solid of depth b.

    Parameters
    ----------
    nodes : array (n_nodes, 2)
        Reference node positions, mm.
    elements : array (n_el, 9)
        Quad9 connectivity (Gmsh/meshio order, counterclockwise).
    law : callable
        C -> (W, S, CC), see :mod:`.material`.
    depth : float
        Out-of-plane depth b, mm.
    """

    def __init__(self, nodes: np.ndarray, elements: np.ndarray, law: Law, depth: float):
        self.nodes = np.asarray(nodes, float)
        self.elements = np.asarray(elements, np.int64)
        self.law = law
        self.depth = float(depth)
        self.mesh = MeshQuad2(np.ascontiguousarray(self.nodes.T),
                              np.ascontiguousarray(self.elements.T))
        self.basis = CellBasis(self.mesh, ElementQuad2(), intorder=_QUADRATURE_ORDER)
        # skfem renumbers nodes (vertices first); keep the mesh's own numbering
        # and check that skfem's local basis order is the quad9 order
        locs = self.basis.doflocs[:, self.basis.element_dofs].T        # (n_el, 9, 2)
        if not np.allclose(locs, self.nodes[self.elements], rtol=0.0, atol=1e-12 * self.scale):
            raise RuntimeError("skfem local node order differs from quad9 order")
        self.node_dofs = np.empty(self.nodes.shape[0], np.int64)   # skfem dof of each node
        self.node_dofs[self.elements] = self.basis.element_dofs.T
        grads = np.stack([self.basis.basis[a][0].grad for a in range(9)])   # (9, 2, n_el, n_q)
        self.grad = np.ascontiguousarray(grads.transpose(2, 3, 0, 1))       # (n_el, n_q, 9, 2)
        self.weight = self.depth * self.basis.dx                            # (n_el, n_q), mm^3
        self.kernel = ElementKernel(self.elements, self.grad, self.weight, law,
                                    self.nodes.shape[0])
        self.element_dofs, self.rows, self.cols = (self.kernel.element_dofs, self.kernel.rows,
                                                   self.kernel.cols)
        self.n_dofs = self.kernel.n_dofs

    @property
    def scale(self) -> float:
        """Size of the mesh's bounding box, mm."""
        return float(np.ptp(self.nodes, axis=0).max())

    def deformation_gradient(self, x: np.ndarray) -> np.ndarray:
        """Deformation gradient F (n_el, n_q, 2, 2) at the quadrature points; x: node positions, mm."""
        return self.kernel.deformation_gradient(x)

    def state(self, x: np.ndarray) -> ElementState:
        """Kinematics and stresses at the quadrature points (see :meth:`ElementKernel.state`)."""
        return self.kernel.state(x)

    def evaluate(self, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """Energy, nodal forces and element tangents (see :meth:`ElementKernel.evaluate`)."""
        return self.kernel.evaluate(x)
