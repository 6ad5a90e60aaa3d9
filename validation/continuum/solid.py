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
same matrix but loops over the 18 x 18 local pairs in Python, many times
slower on a flexure's mesh.) The kernel returns each element
matrix as its three distinct 9 x 9 node blocks (symmetry gives the fourth),
which the continuum group adds straight into the band storage; the full
matrices, data for a fixed COO pattern computed once, serve the connector
by connector path. Energies are per unit depth multiplied by the depth b.
Units: mm, N, MPa, N mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import CellBasis, ElementQuad2, MeshQuad2

from .material import BLOCK_COLS, BLOCK_ROWS, Law

_QUADRATURE_ORDER = 4  # 3 x 3 Gauss points: full integration of quad9


def _block_layout() -> tuple[np.ndarray, np.ndarray]:
    """Where the values of :meth:`ElementKernel.evaluate`'s tangent blocks sit in an 18 x 18
    element matrix (local dof 2 a + i).

    Value ``v = 27 a + 9 c + b`` (node rows a, blocks c of ``BLOCK_ROWS``/``BLOCK_COLS``,
    node columns b) is the entry ``(2 a + i_c, 2 b + k_c)`` of the flat matrix; the
    (0, 1) block's value is also the entry ``(2 b + 1, 2 a)`` (symmetry), the others
    have no mirror (-1).
    """
    a, c, b = np.meshgrid(np.arange(9), np.arange(3), np.arange(9), indexing="ij")
    entry = (2 * a + BLOCK_ROWS[c]) * 18 + 2 * b + BLOCK_COLS[c]
    mirror = np.where(c == 1, (2 * b + 1) * 18 + 2 * a, -1)
    return entry.ravel(), mirror.ravel()


BLOCK_ENTRY, BLOCK_MIRROR = _block_layout()


@dataclass
class ElementState:
    """Kinematics and stresses at the quadrature points (all shaped (n_el, n_q, ...))."""

    F: np.ndarray  # deformation gradient (2, 2)
    C: np.ndarray  # right Cauchy-Green tensor (2, 2)
    W: np.ndarray  # energy density, MPa
    S: np.ndarray  # second Piola-Kirchhoff stress (2, 2), MPa
    CC: np.ndarray  # material tangent (2, 2, 2, 2), MPa


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
    law : Law
        C -> (W, S, CC) and the tangent's blocks, see :mod:`.material`.
    n_nodes : int
    """

    def __init__(
        self, elements: np.ndarray, grad: np.ndarray, weight: np.ndarray, law: Law, n_nodes: int
    ):
        self.elements, self.grad, self.weight, self.law = elements, grad, weight, law
        n_el, n_q = weight.shape
        self._grad_aq = np.ascontiguousarray(
            grad.transpose(0, 2, 1, 3).reshape(n_el, 9, 2 * n_q)
        )  # [a, (q, J)]
        self._grad_lb = np.ascontiguousarray(grad.transpose(0, 1, 3, 2))  # [q, L, b]
        self.element_dofs = (2 * elements[:, :, None] + np.arange(2)).reshape(n_el, 18)
        self.n_dofs = 2 * n_nodes

    @classmethod
    def stack(cls, kernels: list[ElementKernel]) -> ElementKernel:
        """One kernel over the elements of all ``kernels`` (their nodes numbered one after the
        other, in order); the first kernel's law serves all."""
        offsets = np.cumsum([0] + [k.n_dofs // 2 for k in kernels])
        return cls(
            np.concatenate([k.elements + o for k, o in zip(kernels, offsets)]),
            np.concatenate([k.grad for k in kernels]),
            np.concatenate([k.weight for k in kernels]),
            kernels[0].law,
            int(offsets[-1]),
        )

    def subset(self, elements: np.ndarray) -> ElementKernel:
        """The kernel of some of the elements (indices ``elements``), same node numbering."""
        return ElementKernel(
            self.elements[elements],
            self.grad[elements],
            self.weight[elements],
            self.law,
            self.n_dofs // 2,
        )

    def deformation_gradient(self, x: np.ndarray) -> np.ndarray:
        """Deformation gradient F (n_el, n_q, 2, 2) at the quadrature points; x: node positions, mm.

        Held component by component (each F_iJ one contiguous (n_el, n_q)
        block, the array a transposed view): the point-wise arithmetic then
        runs over long contiguous vectors, not over innermost axes of length 2.
        """
        xe = x[self.elements]
        xe = xe - xe[:, :1]  # sum_a dN_a = 0: removes a translation, limits round-off
        n_el, n_q = self.weight.shape
        F = np.matmul(xe.transpose(0, 2, 1), self._grad_aq)  # [i, (q, J)]
        by_component = np.empty((2, 2, n_el, n_q))
        by_component[...] = F.reshape(n_el, 2, n_q, 2).transpose(1, 3, 0, 2)
        return by_component.transpose(2, 3, 0, 1)

    def state(self, x: np.ndarray) -> ElementState:
        """Kinematics and stresses at the quadrature points for node positions x (n_nodes, 2).

        Raises
        ------
        ValueError
            If an element is inverted (det F <= 0 at a quadrature point): the
            multibody core then treats the state as refused and cuts the step.
        """
        F = self.deformation_gradient(x)  # (n_el, n_q, 2, 2)
        F00, F01, F10, F11 = F[..., 0, 0], F[..., 0, 1], F[..., 1, 0], F[..., 1, 1]
        if not np.all(F00 * F11 - F01 * F10 > 0.0):
            raise ValueError("continuum: inverted element (det F <= 0)")
        C = np.empty_like(F)  # F^T F, F's layout
        C[..., 0, 0] = F00 * F00 + F10 * F10
        C[..., 1, 1] = F01 * F01 + F11 * F11
        C[..., 0, 1] = C[..., 1, 0] = F00 * F01 + F10 * F11
        W, S, CC = self.law(C)
        return ElementState(F, C, W, S, CC)

    def _nodal_forces(self, F: np.ndarray, sw: np.ndarray) -> np.ndarray:
        """Nodal forces (n_dofs,) in N, sum_q dN_a/dX_J P_iJ w, from F and weighted stresses sw."""
        n_el, n_q = self.weight.shape
        pw = np.empty((n_el, n_q, 2, 2))  # P^T w: [J, i]
        for i in (0, 1):
            for J in (0, 1):
                pw[..., J, i] = F[..., i, 0] * sw[..., 0, J] + F[..., i, 1] * sw[..., 1, J]
        fe = np.matmul(self._grad_aq, pw.reshape(n_el, 2 * n_q, 2))  # (n_el, 9, 2)
        return np.bincount(self.element_dofs.ravel(), weights=fe.ravel(), minlength=self.n_dofs)

    def forces(self, x: np.ndarray) -> np.ndarray:
        """Nodal forces (n_dofs,) in N at node positions x (n_nodes, 2), mm (no tangent)."""
        st = self.state(x)
        return self._nodal_forces(st.F, st.S * self.weight[..., None, None])

    def evaluate(self, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """Energy (N mm), nodal forces (n_dofs,) in N and element tangent blocks in N/mm.

        The tangent of element e is ``K_(a i)(b k) = sum_q dN_a/dX_J A_iJkL
        dN_b/dX_L w_q`` with ``A_iJkL = delta_ik S_JL + F_iM CC_MJNL F_kN``;
        it is returned as its three distinct 9 x 9 node blocks (i, k) = (0, 0),
        (0, 1), (1, 1) side by side, shape (n_el, 9, 27) (see
        :data:`BLOCK_ENTRY`; :meth:`element_matrices` gives the full 18 x 18
        matrices). Per point the weighted A blocks (:meth:`.material.Law.tangent_blocks`)
        times the gradients, then one product of 9 x 18 by 18 x 27 per element:
        about half the arithmetic of B^T D B with an 18-column strain operator.
        """
        st = self.state(x)
        w = self.weight
        n_el, n_q = w.shape
        sw = st.S * w[..., None, None]
        blocks = self.law.tangent_blocks(st.F, st.CC, w)  # [q, J, c, L]
        for J in (0, 1):  # delta_ik S_JL
            for L in (0, 1):
                blocks[..., J, 0, L] += sw[..., J, L]
                blocks[..., J, 2, L] += sw[..., J, L]
        blocks = np.ascontiguousarray(blocks).reshape(n_el, n_q, 6, 2)
        ag = np.matmul(blocks, self._grad_lb)  # [q, (J, c), b]
        tangent = np.matmul(self._grad_aq, ag.reshape(n_el, 2 * n_q, 27))  # [a, (c, b)]
        return float(np.sum(st.W * w)), self._nodal_forces(st.F, sw), tangent

    @staticmethod
    def element_matrices(blocks: np.ndarray) -> np.ndarray:
        """The full element tangents (n_el, 18, 18) in N/mm of :meth:`evaluate`'s blocks."""
        n_el = blocks.shape[0]
        Ke = np.empty((n_el, 18 * 18))
        values = blocks.reshape(n_el, -1)
        Ke[:, BLOCK_ENTRY] = values
        mirrored = BLOCK_MIRROR >= 0
        Ke[:, BLOCK_MIRROR[mirrored]] = values[:, mirrored]
        return Ke.reshape(n_el, 18, 18)


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
        self.mesh = MeshQuad2(
            np.ascontiguousarray(self.nodes.T), np.ascontiguousarray(self.elements.T)
        )
        self.basis = CellBasis(self.mesh, ElementQuad2(), intorder=_QUADRATURE_ORDER)
        # skfem renumbers nodes (vertices first); keep the mesh's own numbering
        # and check that skfem's local basis order is the quad9 order
        locs = self.basis.doflocs[:, self.basis.element_dofs].T  # (n_el, 9, 2)
        if not np.allclose(locs, self.nodes[self.elements], rtol=0.0, atol=1e-12 * self.scale):
            raise RuntimeError("skfem local node order differs from quad9 order")
        self.node_dofs = np.empty(self.nodes.shape[0], np.int64)  # skfem dof of each node
        self.node_dofs[self.elements] = self.basis.element_dofs.T
        grads = np.stack([self.basis.basis[a][0].grad for a in range(9)])  # (9, 2, n_el, n_q)
        self.grad = np.ascontiguousarray(grads.transpose(2, 3, 0, 1))  # (n_el, n_q, 9, 2)
        self.weight = self.depth * self.basis.dx  # (n_el, n_q), mm^3
        self.kernel = ElementKernel(self.elements, self.grad, self.weight, law, self.nodes.shape[0])
        self.element_dofs = edofs = self.kernel.element_dofs
        self.rows = np.repeat(edofs, 18, axis=1).ravel()  # COO pattern of evaluate()
        self.cols = np.tile(edofs, (1, 18)).ravel()
        self.n_dofs = self.kernel.n_dofs

    @property
    def scale(self) -> float:
        """Size of the mesh's bounding box, mm."""
        return float(np.ptp(self.nodes, axis=0).max())

    def deformation_gradient(self, x: np.ndarray) -> np.ndarray:
        """Deformation gradient F (n_el, n_q, 2, 2) at the quadrature points.

        ``x`` holds the node positions, mm.
        """
        return self.kernel.deformation_gradient(x)

    def state(self, x: np.ndarray) -> ElementState:
        """Kinematics and stresses at the quadrature points (see :meth:`ElementKernel.state`)."""
        return self.kernel.state(x)

    def evaluate(self, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """Energy (N mm), nodal forces (n_dofs,) in N and element tangents (n_el, 18, 18) in N/mm.

        The tangents are the data of the COO pattern ``(rows, cols)``
        (``Ke.ravel()``), duplicates to be summed; see :meth:`ElementKernel.evaluate`.
        """
        energy, forces, blocks = self.kernel.evaluate(x)
        return energy, forces, self.kernel.element_matrices(blocks)
