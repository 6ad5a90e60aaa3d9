"""Optional outputs of the continuum model: VTU fields and a PNG picture.

Nodal fields of each flexure at a state of the multibody system:
displacement (mm), Green-Lagrange strain E (xx, yy, xy) and von Mises
equivalent Cauchy stress (MPa), the last two L2-projected from the
quadrature points onto the quad9 space with scikit-fem, and the Cauchy
normal stress along the fibres (MPa) as the reported peak fibre stress
reads it (:func:`.fibre.fibre_stress_field`: patch recovery). The
out-of-plane stretch and stress of the law (plane stress: S33 = 0; plane
strain: C33 = 1) enter the 3D Cauchy stress sigma = F3 S3 F3^T / J.

The VTU keeps the reference mesh with its fields (for ParaView: warp by
``displacement``); the PNG is the designer's picture of the deformed
mechanism (:mod:`.picture`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from flexval.geometry import LoadCase, Mechanism
from flexval.geometry.files import atomic_path

from .connector import ContinuumConnector
from .fibre import LAYER_THICKNESSES, fibre_stress_field
from .material import out_of_plane


def nodal_fields(
    conn: ContinuumConnector, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
) -> dict[str, np.ndarray]:
    """Positions and nodal fields of one flexure.

    Returns
    -------
    dict
        ``position`` (n, 2) mm, ``displacement`` (n, 2) mm, ``strain`` (n, 3)
        Green-Lagrange (xx, yy, xy), ``von_mises`` (n,) MPa, ``fibre_stress``
        (n,) MPa: the signed Cauchy normal stress along the fibres (tension
        positive).
    """
    x = conn.positions(pose_a, pose_b, internal)
    solid = conn.solid
    st = solid.state(x)
    E = 0.5 * (st.C - np.eye(2))
    c33, s33 = out_of_plane(
        conn.law, conn.plane, conn.material.youngs_modulus, conn.material.poisson_ratio, st.C
    )
    lam3 = np.sqrt(c33)
    J = (st.F[..., 0, 0] * st.F[..., 1, 1] - st.F[..., 0, 1] * st.F[..., 1, 0]) * lam3
    sig = np.matmul(np.matmul(st.F, st.S), st.F.transpose(0, 1, 3, 2)) / J[..., None, None]
    s33 = c33 * s33 / J
    s11, s22, s12 = sig[..., 0, 0], sig[..., 1, 1], sig[..., 0, 1]
    vm = np.sqrt(0.5 * ((s11 - s22) ** 2 + (s22 - s33) ** 2 + (s33 - s11) ** 2) + 3.0 * s12**2)
    qp = [E[..., 0, 0], E[..., 1, 1], E[..., 0, 1], vm]
    nodal = [solid.basis.project(v)[solid.node_dofs] for v in qp]
    return {
        "position": x,
        "displacement": x - conn.mesh.nodes,
        "strain": np.column_stack(nodal[:3]),
        "von_mises": nodal[3],
        "fibre_stress": fibre_stress_field(conn, pose_a, pose_b, internal),
    }


def _pad3(a: np.ndarray) -> np.ndarray:
    """2D vectors (n, 2) as 3D (n, 3) with z = 0."""
    return np.column_stack([a, np.zeros(a.shape[0])])


def write_vtu(
    path: str | Path,
    conns: Sequence[ContinuumConnector],
    states: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]],
) -> Path:
    """Write all flexures (reference geometry, quad9 cells) with their nodal fields.

    ``states[k]`` is (pose_a, pose_b, internal) of ``conns[k]``; connectors
    other than meshed flexures (pins) are left out. Warp by the
    ``displacement`` point data (mm) to see the deformed mechanism; the point
    data ``von_mises`` and ``fibre_stress`` are in MPa.
    """
    import meshio

    pts, cells, disp, strain, vm, fibre, flex = [], [], [], [], [], [], []
    offset = 0
    meshed = [(c, st) for c, st in zip(conns, states) if isinstance(c, ContinuumConnector)]
    for k, (c, st) in enumerate(meshed):
        f = nodal_fields(c, *st)
        pts.append(c.mesh.nodes)
        cells.append(c.mesh.elements + offset)
        offset += c.mesh.nodes.shape[0]
        disp.append(f["displacement"]), strain.append(f["strain"]), vm.append(f["von_mises"])
        fibre.append(f["fibre_stress"])
        flex.append(np.full(c.mesh.elements.shape[0], k))
    mesh = meshio.Mesh(
        _pad3(np.vstack(pts)),
        [("quad9", np.vstack(cells))],
        point_data={
            "displacement": _pad3(np.vstack(disp)),
            "green_lagrange_strain": np.vstack(strain),
            "von_mises": np.concatenate(vm),
            "fibre_stress": np.concatenate(fibre),
        },
        cell_data={"flexure": [np.concatenate(flex)]},
    )
    return save_vtu(path, mesh)


def save_vtu(path: str | Path, mesh) -> Path:
    """Write the meshio Mesh ``mesh`` to ``path`` as VTU, atomically (its folder made if
    missing); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        mesh.write(tmp, file_format="vtu")
    return path


def render_png(
    png: str | Path,
    system,
    state: np.ndarray,
    case: LoadCase,
    title: str = "",
    quantity: str = "fibre_stress",
    load_factor: float = 1.0,
) -> Path:
    """The picture of the deformed mechanism at ``state``, flexures coloured by stress (PNG).

    Parameters
    ----------
    png : path
        The file to write (atomically).
    system : reducedmodels.System
        The continuum system; its continuum connectors are drawn as meshes.
    state : ndarray
        Its coordinates (mm, rad), e.g. the converged state at full load.
    case : LoadCase
        The load case drawn.
    title : str
    quantity : {'fibre_stress', 'von_mises'}
        The stress (MPa) the flexures are coloured by.
    load_factor : float
        The load factor of ``state`` (1: full load), for the captions.

    See :func:`.picture.continuum_figure` for what the picture shows.
    """
    mech = system.mechanism
    conns, states = [], []
    for c, st in zip(system.connectors, system.local_states(state)):
        if isinstance(c, ContinuumConnector):
            conns.append(c)
            states.append(st)
    poses = {b: np.asarray(system.pose(state, b), float) for b in mech.bodies}
    fields = flexure_fields(mech, conns, states)
    return write_picture(png, mech, case, fields, poses, title, quantity, load_factor)


def flexure_fields(
    mechanism: Mechanism,
    conns: Sequence[ContinuumConnector],
    states: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]],
) -> list:
    """The :class:`.picture.FlexureField` of each flexure at its local state: mesh, current
    positions (mm), nodal stresses (MPa) and the nodes outside the end layers
    (:data:`.fibre.LAYER_THICKNESSES` thicknesses of each end face, each node placed on
    the centre line by the recovery's section map: the rule of the reported peak fibre
    stress, :func:`.fibre.fibre_stress_peak`)."""
    from .picture import FlexureField, interior_nodes

    thickness = {f.name: f.section.thickness for f in mechanism.flexures}
    out = []
    for c, st in zip(conns, states):
        f = nodal_fields(c, *st)
        layer = LAYER_THICKNESSES * thickness[c.name]
        interior, fraction = interior_nodes(
            c.mesh.nodes, c.mesh.centre_line, layer, along=c.recovery.node_along
        )
        out.append(
            FlexureField(
                name=c.name,
                reference=c.mesh.nodes,
                position=f["position"],
                elements=c.mesh.elements,
                centre_line=c.mesh.centre_line,
                stress={"fibre_stress": f["fibre_stress"], "von_mises": f["von_mises"]},
                interior=interior,
                arc_fraction=fraction,
                layer=layer,
                thickness=thickness[c.name],
            )
        )
    return out


def write_picture(
    png: str | Path,
    mechanism: Mechanism,
    case: LoadCase,
    fields: Sequence,
    poses: dict[str, np.ndarray],
    title: str = "",
    quantity: str = "fibre_stress",
    load_factor: float = 1.0,
) -> Path:
    """Draw :func:`.picture.continuum_figure` (arguments as there) and write it to ``png``
    atomically (PNG, or the format of the suffix)."""
    import matplotlib.pyplot as plt

    from ..outputs import save_figure
    from .picture import continuum_figure

    fig = continuum_figure(mechanism, case, fields, poses, title, quantity, load_factor)
    png = Path(png)
    png.parent.mkdir(parents=True, exist_ok=True)
    try:
        save_figure(fig, png, dpi=120)
    finally:
        plt.close(fig)
    return png
