"""Superconvergent patch recovery (Zienkiewicz-Zhu) of the fibre stress on a flexure mesh.

The stresses of a quad9 solution are most accurate at the 2 x 2 Gauss points of each
element (the Barlow points: O(h^3) against O(h^2) elsewhere on a regular mesh), but a
flexure's peak stress lies at a free surface, where there are nodes and no such points. The
recovery fits, per patch of 2 x 2 elements, a polynomial to the values at the patch's 16
Barlow points by least squares and evaluates it at the nodes: quadratic along the flexure,
cubic across it, where the stress varies most and where a notch root's concentration sits
(a quadratic fit through the whole thickness would see only the linear part).

The fit is made in the mesh's logical coordinates (a node of section k along the flexure at
position m across it sits at (k, m): the mesh is a structured stack of cross-sections,
:func:`.polar.cross_sections`), so every patch has the same design matrix. What is fitted is
the fibre stress times the fibres' length per logical unit, |dX/dk|, and the result is
divided by the same fit of |dX/dk|: that product is linear across a section even on a curved
flexure (Winkler-Bach), so a mesh with one element across still reproduces the inner fibre's
excess stress. The method and its accuracy are in the documentation's models page
(``continuum``, "Stress recovery"); the patches and the fit each node takes are in
ARCHITECTURE.md.

Units: the recovered values carry the sampled field's unit (MPa for stresses).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import CellBasis, ElementQuad2

BARLOW_ORDER = 3
"""scikit-fem integration order whose tensor Gauss rule is the 2 x 2 points of a quad9."""


class PatchRecovery:
    """The fixed linear map from values at the Barlow points to recovered nodal values.

    Parameters
    ----------
    mesh : skfem.MeshQuad2
        The solid's scikit-fem mesh (:attr:`.solid.Solid.mesh`).
    elements : int array (n_el, 9)
        Quad9 connectivity in the mesh's node numbering.
    sections : int array (2 n_l + 1, 2 n_t + 1)
        Node indices of every cross-section (:func:`.polar.cross_sections`).

    Attributes
    ----------
    basis : skfem.CellBasis
        Quad9 basis at the 2 x 2 Gauss points: sample a field there.
    grad : float array (n_el, 4, 9, 2)
        Reference shape-function gradients at the Barlow points, 1/mm.
    along, across : float arrays (n_el, 4)
        Logical coordinates of each element's Barlow points.
    node_along, node_across : float arrays (n_nodes,)
        Logical coordinates (k, m) of every node.
    fibre : float array (n_el, 4, 2)
        Unit tangent of the fibre through each Barlow point (undeformed).
    fibre_length : float array (n_el, 4)
        |dX/dk| there: the fibre's length per logical unit along, mm.
    """

    def __init__(self, mesh, elements: np.ndarray, sections: np.ndarray) -> None:
        self.basis = CellBasis(mesh, ElementQuad2(), intorder=BARLOW_ORDER)
        n_nodes = sections.size
        n_k, n_m = sections.shape
        n_l, n_t = (n_k - 1) // 2, (n_m - 1) // 2
        k = np.empty(n_nodes)
        m = np.empty(n_nodes)
        k[sections] = np.arange(n_k)[:, None]
        m[sections] = np.arange(n_m)[None, :]
        self.node_along, self.node_across = k, m
        # the basis's local functions follow quad9 order (checked by Solid)
        values = np.stack([np.asarray(self.basis.basis[a][0]) for a in range(9)])  # (9, n_el, n_q)
        self.along = np.einsum("aeq,ea->eq", values, k[elements])
        self.across = np.einsum("aeq,ea->eq", values, m[elements])
        self._elements = elements
        grads = np.stack([self.basis.basis[a][0].grad for a in range(9)])  # (9, 2, n_el, n_q)
        self.grad = np.ascontiguousarray(grads.transpose(2, 3, 0, 1))
        i = (k[elements].min(axis=1) // 2).astype(np.int64)  # element's place along
        j = (m[elements].min(axis=1) // 2).astype(np.int64)  # and across
        self._matrix = _recovery_matrix(k, m, self.along, self.across, i, j, n_l, n_t)
        # fibres: normal to grad m; dX/dk is the first column of the inverse of d(k, m)/dX
        gm, gk = self.gradient(m), self.gradient(k)
        norm = np.hypot(gm[..., 0], gm[..., 1])
        self.fibre = np.stack([gm[..., 1], -gm[..., 0]], axis=-1) / norm[..., None]
        self.fibre_length = norm / np.abs(gk[..., 0] * gm[..., 1] - gk[..., 1] * gm[..., 0])
        self._nodal_length = self.recover(self.fibre_length)

    def gradient(self, nodal: np.ndarray) -> np.ndarray:
        """Reference gradient (n_el, 4, 2) at the Barlow points of a nodal field (unit per mm)."""
        return np.einsum("eqaJ,ea->eqJ", self.grad, np.asarray(nodal, float)[self._elements])

    def recover(self, samples: np.ndarray) -> np.ndarray:
        """Nodal values (n_nodes,) recovered from values at the Barlow points (n_el, 4)."""
        return self._matrix @ np.asarray(samples, float).ravel()

    def recover_fibre_field(self, samples: np.ndarray) -> np.ndarray:
        """Nodal values (n_nodes,) of a fibre quantity (a fibre stress) given at the Barlow
        points (n_el, 4): its product with the fibre length recovered, over the recovered
        fibre length (see the module text)."""
        return self.recover(np.asarray(samples, float) * self.fibre_length) / self._nodal_length


def _patches(n: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The patches along one direction of ``n`` elements: each patch's first element, its
    centre (logical coordinate) and its number of elements."""
    if n == 1:
        return np.array([0]), np.array([1.0]), 1
    first = np.arange(n - 1)  # the patch of interior vertex K = first + 1
    return first, 2.0 * (first + 1), 2


def _node_patch(logical: np.ndarray, n: int, shift: int) -> np.ndarray:
    """The patch (along one direction of ``n`` elements) a node at ``logical`` takes: its
    vertex's, or with ``shift`` 0 and 1 the two around it, clipped to the interior ones."""
    if n == 1:
        return np.zeros(logical.shape, np.int64)
    return np.clip(np.floor((logical + shift) / 2.0).astype(np.int64), 1, n - 1) - 1


def _recovery_matrix(
    k: np.ndarray,
    m: np.ndarray,
    along: np.ndarray,
    across: np.ndarray,
    i: np.ndarray,
    j: np.ndarray,
    n_l: int,
    n_t: int,
) -> sp.csr_matrix:
    """Sparse (n_nodes, 4 n_el) map from Barlow-point values to recovered nodal values.

    ``k``, ``m``: the nodes' logical coordinates; ``along``, ``across``: the
    Barlow points'; ``i``, ``j``: each element's place along and across.
    """
    n_el, n_q = along.shape
    if n_q != 4:
        raise RuntimeError(f"expected the 2 x 2 Barlow points, got {n_q} points per element")
    first_l, centre_l, span_l = _patches(n_l)
    first_t, centre_t, span_t = _patches(n_t)
    # quadratic along, cubic across; linear in a direction of one element (two Barlow points)
    powers = [(a, b) for a in range(min(3, 2 * span_l)) for b in range(min(4, 2 * span_t))]
    element_at = np.full((n_l, n_t), -1)
    element_at[i, j] = np.arange(n_el)
    pl, pt = (
        g.ravel()
        for g in np.meshgrid(np.arange(first_l.size), np.arange(first_t.size), indexing="ij")
    )
    di, dj = (g.ravel() for g in np.meshgrid(np.arange(span_l), np.arange(span_t), indexing="ij"))
    members = element_at[first_l[pl][:, None] + di, first_t[pt][:, None] + dj]
    samples = (members[:, :, None] * n_q + np.arange(n_q)).reshape(members.shape[0], -1)
    # logical coordinates about each patch's centre, in units of one element (2 logical)
    centre_k, centre_m = centre_l[pl], centre_t[pt]
    u = (along.ravel()[samples] - centre_k[:, None]) / 2.0
    v = (across.ravel()[samples] - centre_m[:, None]) / 2.0
    design = np.stack([u**a * v**b for a, b in powers], axis=-1)  # (n_patch, n_samples, n_terms)
    # least squares by the normal equations: coordinates within +-1, condition at most 3.3e3
    transposed = design.transpose(0, 2, 1)
    fit = np.linalg.solve(transposed @ design, transposed)
    # each node: the mean over its patches along times its patches across (4 terms)
    rows, cols, vals = [], [], []
    for shift_l in (0, 1):
        for shift_t in (0, 1):
            patch = _node_patch(k, n_l, shift_l) * first_t.size + _node_patch(m, n_t, shift_t)
            uu = (k - centre_k[patch]) / 2.0
            vv = (m - centre_m[patch]) / 2.0
            phi = np.stack([uu**a * vv**b for a, b in powers], axis=-1)  # (n_nodes, n_terms)
            rows.append(np.repeat(np.arange(k.size), samples.shape[1]))
            cols.append(samples[patch].ravel())
            vals.append(np.einsum("nt,nts->ns", phi, fit[patch]).ravel() / 4.0)
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(k.size, n_el * n_q),
    )
