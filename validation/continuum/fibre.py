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
peak is 3.352, 3.462, 3.456 and 3.454 % above it at mesh levels 0 to 3,
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

from flexval.reducedmodels.core.sections import polyline_fractions

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
    layer: float | tuple[float, float],
) -> tuple[float, float]:
    """Largest |fibre normal stress| (MPa) outside ``layer`` mm of each end, and where.

    The window between the layers holds the nodes inside it and, on every
    fibre, the recovered field interpolated (quadratic in arc length, the
    elements' own interpolation) at the window's two edges, so that a peak
    at an edge is the field's value there, not that of the node nearest to it.

    Parameters
    ----------
    conn : ContinuumConnector
    pose_a, pose_b, internal :
        A converged local state.
    layer : float or (float, float)
        Width of the excluded boundary layer at each end face (or at the
        first and at the second end), as arc length along the centre line
        (mm); typically twice the end face's thickness.

    Returns
    -------
    stress : float
        MPa.
    at : float
        Arc-length fraction of that point from the flexure's first end.

    Raises
    ------
    ValueError
        If the layers cover the whole flexure.
    """
    first, last = (layer, layer) if np.isscalar(layer) else map(float, layer)
    fractions, length = _sections_along(conn)
    if first + last >= length:
        raise ValueError(
            f"boundary layers of {first:g} and {last:g} mm cover the whole flexure "
            f"({length:g} mm long)"
        )
    nodal = np.abs(fibre_stress_field(conn, pose_a, pose_b, internal))[conn.sections]
    s = fractions * length  # of every section, mm
    per_section = nodal.max(axis=1)
    candidates = [
        (float(_interpolated(nodal, s, edge).max()), edge / length)
        for edge in (first, length - last)
    ]
    inside = np.flatnonzero((s >= first) & (s <= length - last))
    if inside.size:
        k = inside[np.argmax(per_section[inside])]
        candidates.append((float(per_section[k]), float(fractions[k])))
    return max(candidates)


def surface_profile(
    conn: ContinuumConnector, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The largest |fibre normal stress| over each section of the mesh (MPa), and the
    sections' arc-length fractions from the flexure's first end: the surface fibre stress
    along the flexure (end faces' boundary layers included), as a notch hinge's calibration
    reads it (``benchmarks/calibrate_notch.py``)."""
    fractions, _ = _sections_along(conn)
    nodal = np.abs(fibre_stress_field(conn, pose_a, pose_b, internal))[conn.sections]
    return fractions, nodal.max(axis=1)


def _sections_along(conn: ContinuumConnector) -> tuple[np.ndarray, float]:
    """The mesh sections' arc-length fractions along the centre line, and its length (mm)."""
    line = conn.mesh.nodes[conn.mesh.centre_line]
    return polyline_fractions(line), float(np.sum(np.hypot(*np.diff(line, axis=0).T)))


def _interpolated(values: np.ndarray, s: np.ndarray, at: float) -> np.ndarray:
    """Values (n_sections, width) at the sections' arc lengths ``s`` (2 n_l + 1,),
    interpolated to arc length ``at`` by the quadratic through the three sections of the
    element holding it (one value per fibre)."""
    vertices = s[0::2]
    i = int(np.clip(np.searchsorted(vertices, at) - 1, 0, vertices.size - 2))
    x = s[2 * i : 2 * i + 3]
    weights = [np.prod([(at - x[b]) / (x[a] - x[b]) for b in range(3) if b != a]) for a in range(3)]
    return np.tensordot(weights, values[2 * i : 2 * i + 3], axes=1)


LAYER_THICKNESSES = 2.0
"""Boundary layer excluded at each end face, in thicknesses of that face: with one thickness
the peak of a thick arc under a pure moment still sat at the layer's edge (end-face
influence); with two it lies inside the flexure and matches the exact (Golovin) inner-fibre
stress to 0.02 % at r/h = 4 (mesh level 2)."""

THINNEST = 1e-9
"""Relative thickness above the smallest within which a station counts as the thinnest."""

LAYER_SAMPLES = 4096
"""Points along a varying section at which its thinnest part is looked for."""


def boundary_layers(flexure) -> tuple[float, float]:
    """Widths (mm) of the boundary layers excluded at a flexure's first and second end.

    :data:`LAYER_THICKNESSES` times each end face's thickness h(0), h(L). On
    a varying section a layer stops half-way to the thinnest part when that
    part does not reach its end: a notch hinge's ends are as thick as its
    blank (twice their thickness is often more than the notch is long), the
    rigid face's perturbation there is a small part of the stress at the
    root (it scales with 1/h^2 at the face), and a fillet's stress
    concentration lies where the fillet meets the thin stretch. A layer at
    an end that is the thinnest part (a taper's thin end) is kept whole.
    """
    section, length = flexure.section, flexure.shape.length
    if section.profile is None:
        layer = LAYER_THICKNESSES * section.thickness
        return layer, layer
    s = np.union1d(np.linspace(0.0, length, LAYER_SAMPLES + 1), section.profile.breakpoints)
    h = np.asarray(section.thickness_at(s), float)
    thin = np.flatnonzero(h <= h.min() * (1.0 + THINNEST))
    reach = (s[thin[0]], length - s[thin[-1]])  # from each end to the thinnest part
    ends = LAYER_THICKNESSES * np.asarray(section.thickness_at([0.0, length]), float)
    first, last = (float(e if d == 0.0 else min(e, 0.5 * d)) for e, d in zip(ends, reach))
    return first, last


def notch_concentration(
    conn: ContinuumConnector, local, flexure, stress: float
) -> dict[str, float]:
    """The fibre peak ``stress`` (MPa) against the beam formula at a flexure's thinnest section.

    ``nominal``: the largest |N|/A + |M| h/(2I) of the continuum's own section
    resultants over the centre-line stations of smallest thickness (MPa; one
    station at a rounded notch's root, the flat stretch of a corner-filleted
    one), ``thinnest``: that station's arc-length fraction, ``concentration``:
    stress / nominal (the stress-concentration factor of a notch hinge).
    """
    forces = conn.section_forces(*local)
    h = flexure.section.thickness_at(np.asarray(forces.at, float) * flexure.shape.length)
    beam = forces.fibre_stress(flexure.section)
    thinnest = np.flatnonzero(h <= h.min() * (1.0 + THINNEST))
    k = int(thinnest[np.argmax(beam[thinnest])])
    nominal = float(beam[k])
    return {"nominal": nominal, "thinnest": float(forces.at[k]), "concentration": stress / nominal}


def notch_peaks(system, state: np.ndarray) -> dict[str, tuple[float, float]]:
    """Each continuum notch hinge's peak fibre stress (MPa) and where (fraction from its first
    end) at a converged ``state`` of ``system``: :func:`fibre_stress_peak` outside
    :func:`boundary_layers`, as :func:`fibre_stresses` finds it at full load."""
    flexures = {f.name: f for f in system.mechanism.flexures}
    out = {}
    for conn, local in zip(system.connectors, system.local_states(state)):
        flexure = flexures.get(conn.name)
        if flexure is None or not hasattr(conn, "solid") or not _is_notch(flexure):
            continue
        out[conn.name] = fibre_stress_peak(conn, *local, boundary_layers(flexure))
    return out


def _is_notch(flexure) -> bool:
    profile = flexure.section.profile
    return profile is not None and profile.kind == "notch"


def fibre_stresses(system, state: np.ndarray) -> dict[str, dict]:
    """Each continuum flexure's peak fibre stress at a converged ``state`` of ``system``.

    Returns {flexure: {"stress": MPa, "at": fraction from its first end, "layer": mm,
    "layer_end": mm}}, the layers excluded at the first and second end being
    :func:`boundary_layers`; a notch hinge's entry adds its stress concentration
    (:func:`notch_concentration`: "nominal" MPa, "thinnest", "concentration").
    """
    flexures = {f.name: f for f in system.mechanism.flexures}
    out = {}
    for conn, local in zip(system.connectors, system.local_states(state)):
        if conn.name not in flexures or not hasattr(conn, "solid"):
            continue
        flexure = flexures[conn.name]
        first, last = boundary_layers(flexure)
        stress, at = fibre_stress_peak(conn, *local, (first, last))
        out[conn.name] = {"stress": stress, "at": at, "layer": first, "layer_end": last}
        if _is_notch(flexure):
            out[conn.name].update(notch_concentration(conn, local, flexure, stress))
    return out
