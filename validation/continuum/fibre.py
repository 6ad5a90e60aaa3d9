"""The continuum's own peak fibre stress, outside the end faces' boundary layers.

The section resultants (:meth:`.connector.ContinuumConnector.section_forces`)
turn into stress through the beam formula |N|/A + |M| h/(2I), which treats
every section as straight. The solid itself knows better: on a thick curved
flexure the bending stress piles up at the inner fibre (Winkler-Bach). This
module reads it off the solution: the Cauchy normal stress along the fibres,

    sigma_tt = t . sigma . t,    t = F T / |F T|,

at the 2 x 2 Gauss points of every element (T: the undeformed fibre's
tangent there, the mesh's line along the flexure through the point),
recovered at the nodes by superconvergent patch recovery
(:mod:`.recovery`; the peak lies on a surface, where there are nodes but no
Gauss points). Measured on a curved bar in pure bending (r/h = 10), whose
exact inner-fibre stress (Golovin) is 3.455 % above M h/(2I): the recovered
peak is 3.352, 3.431, 3.451 and 3.454 % above it at mesh levels 0 to 3,
where an L2 projection of the 3 x 3 quadrature values onto the nodes gives
5.83, 4.09, 3.62 and 3.50 % (second order). Its largest magnitude is taken
outside a boundary
layer at each end face. The end faces are held rigidly, so their corners
are stress singularities and the raw maximum grows with mesh refinement;
one thickness away (Saint-Venant) the field is regular.

Units: mm, MPa.
"""

from __future__ import annotations

import numpy as np

from flexval.reducedmodels.sections import polyline_fractions

from .connector import ContinuumConnector
from .material import out_of_plane
from .solid import ElementKernel


def fibre_stress_field(
    conn: ContinuumConnector, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
) -> np.ndarray:
    """Cauchy normal stress along the fibres at every mesh node (n_nodes,), MPa, tension
    positive, recovered from the 2 x 2 Gauss points (see the module text)."""
    recovery = conn.recovery
    kernel = ElementKernel(
        conn.mesh.elements,
        recovery.grad,
        recovery.basis.dx,
        conn.solid.kernel.law,
        conn.mesh.nodes.shape[0],
    )
    st = kernel.state(conn.positions(pose_a, pose_b, internal))
    c33, _ = out_of_plane(
        conn.law, conn.plane, conn.material.youngs_modulus, conn.material.poisson_ratio, st.C
    )
    J = (st.F[..., 0, 0] * st.F[..., 1, 1] - st.F[..., 0, 1] * st.F[..., 1, 0]) * np.sqrt(c33)
    sigma = np.matmul(np.matmul(st.F, st.S), np.swapaxes(st.F, -1, -2)) / J[..., None, None]
    t = np.einsum("...ij,...j->...i", st.F, recovery.fibre)
    t /= np.linalg.norm(t, axis=-1)[..., None]
    return recovery.recover_fibre_field(np.einsum("...i,...ij,...j->...", t, sigma, t))


def fibre_stress_peak(
    conn: ContinuumConnector,
    pose_a: np.ndarray,
    pose_b: np.ndarray,
    internal: np.ndarray,
    layer: float,
) -> tuple[float, float]:
    """Largest |fibre normal stress| (MPa) outside ``layer`` mm of each end, and where.

    Parameters
    ----------
    conn : ContinuumConnector
    pose_a, pose_b, internal :
        A converged local state.
    layer : float
        Width of the excluded boundary layer at each end face, as arc length
        along the centre line (mm); typically the flexure's thickness.

    Returns
    -------
    stress : float
        MPa.
    at : float
        Arc-length fraction of that node from the flexure's first end.

    Raises
    ------
    ValueError
        If the layers cover the whole flexure.
    """
    line = conn.mesh.nodes[conn.mesh.centre_line]
    fractions = polyline_fractions(line)
    length = float(np.sum(np.hypot(*np.diff(line, axis=0).T)))
    if 2.0 * layer >= length:
        raise ValueError(
            f"boundary layers of {layer:g} mm cover the whole flexure ({length:g} mm long)"
        )
    nodal = np.abs(fibre_stress_field(conn, pose_a, pose_b, internal))
    s_node = fractions[conn.recovery.node_along.astype(np.int64)]
    inside = (s_node * length >= layer) & ((1.0 - s_node) * length >= layer)
    k = int(np.argmax(np.where(inside, nodal, -1.0)))
    return float(nodal[k]), float(s_node[k])


LAYER_THICKNESSES = 2.0
"""Boundary layer excluded at each end face, in flexure thicknesses: with one thickness the
peak of a thick arc under a pure moment still sat at the layer's edge (end-face influence);
with two it lies inside the flexure and matches Winkler-Bach to 0.01 % at r/h = 4 (mesh level 2)."""


def fibre_stresses(system, state: np.ndarray) -> dict[str, dict]:
    """Each continuum flexure's peak fibre stress at a converged ``state`` of ``system``.

    Returns {flexure: {"stress": MPa, "at": fraction from its first end, "layer": mm}},
    the layer being :data:`LAYER_THICKNESSES` times the flexure's thickness.
    """
    thickness = {f.name: f.section.thickness for f in system.mechanism.flexures}
    out = {}
    for conn, local in zip(system.connectors, system.local_states(state)):
        if conn.name not in thickness or not hasattr(conn, "solid"):
            continue
        layer = LAYER_THICKNESSES * thickness[conn.name]
        stress, at = fibre_stress_peak(conn, *local, layer)
        out[conn.name] = {"stress": stress, "at": at, "layer": layer}
    return out
