"""The continuum's own peak fibre stress, outside the end faces' boundary layers.

The section resultants (:meth:`.connector.ContinuumConnector.section_forces`)
turn into stress through the beam formula |N|/A + |M| h/(2I), which treats
every section as straight. The solid itself knows better: on a thick curved
flexure the bending stress piles up at the inner fibre (Winkler-Bach). This
module reads it off the solution: the Cauchy normal stress along the fibres,

    sigma_tt = t . sigma . t,    t = F T / |F T|,

at every quadrature point (T: the undeformed centre line's tangent at the
point's arc length), L2-projected onto the mesh's nodes (the peak lies on a
surface, where there are nodes but no quadrature points); its largest
magnitude is taken outside a boundary layer at each end face. The end faces are held rigidly, so
their corners are stress singularities and the raw maximum grows with mesh
refinement; one thickness away (Saint-Venant) the field is regular.

Units: mm, MPa.
"""

from __future__ import annotations

import numpy as np

from flexval.reducedmodels.sections import polyline_fractions

from .connector import ContinuumConnector
from .material import out_of_plane
from .polar import nearest


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
    solid = conn.solid
    X = np.asarray(solid.basis.global_coordinates()).transpose(1, 2, 0)  # (n_el, n_q, 2)
    # nearest centre-line vertex: the arc length and the tangent of each point
    closest = nearest(X, line)  # (n_el, n_q)
    tangent = np.gradient(line, axis=0)
    tangent /= np.hypot(tangent[:, 0], tangent[:, 1])[:, None]
    T = tangent[closest]  # (n_el, n_q, 2)
    st = solid.state(conn.positions(pose_a, pose_b, internal))
    c33, _ = out_of_plane(
        conn.law, conn.plane, conn.material.youngs_modulus, conn.material.poisson_ratio, st.C
    )
    J = (st.F[..., 0, 0] * st.F[..., 1, 1] - st.F[..., 0, 1] * st.F[..., 1, 0]) * np.sqrt(c33)
    sigma = np.matmul(np.matmul(st.F, st.S), np.swapaxes(st.F, -1, -2)) / J[..., None, None]
    t = np.einsum("...ij,...j->...i", st.F, T)
    t /= np.linalg.norm(t, axis=-1)[..., None]
    fibre = np.einsum("...i,...ij,...j->...", t, sigma, t)
    # the peak is at a surface: L2-project onto the quad9 space and read it at the nodes
    nodal = np.abs(solid.basis.project(fibre)[solid.node_dofs])
    s_node = fractions[nearest(conn.mesh.nodes, line)]
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
