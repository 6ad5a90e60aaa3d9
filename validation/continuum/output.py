"""Optional outputs of the continuum model: VTU fields and an off-screen PNG.

Nodal fields of each flexure at a state of the multibody system:
displacement (mm), Green-Lagrange strain E (xx, yy, xy) and von Mises
equivalent Cauchy stress (MPa), the last two L2-projected from the
quadrature points onto the quad9 space with scikit-fem. The out-of-plane
stretch and stress of the law (plane stress: S33 = 0; plane strain:
C33 = 1) enter the 3D Cauchy stress sigma = F3 S3 F3^T / J.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from flexval.geometry.files import atomic_path

from .connector import ContinuumConnector
from .material import out_of_plane


def nodal_fields(
    conn: ContinuumConnector, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
) -> dict[str, np.ndarray]:
    """Positions and nodal fields of one flexure.

    Returns
    -------
    dict
        ``position`` (n, 2) mm, ``displacement`` (n, 2) mm, ``strain`` (n, 3)
        Green-Lagrange (xx, yy, xy), ``von_mises`` (n,) MPa.
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

    ``states[k]`` is (pose_a, pose_b, internal) of ``conns[k]``. Warp by the
    ``displacement`` point data to see the deformed mechanism.
    """
    import meshio

    pts, cells, disp, strain, vm, flex = [], [], [], [], [], []
    offset = 0
    for k, (c, st) in enumerate(zip(conns, states)):
        f = nodal_fields(c, *st)
        pts.append(c.mesh.nodes)
        cells.append(c.mesh.elements + offset)
        offset += c.mesh.nodes.shape[0]
        disp.append(f["displacement"]), strain.append(f["strain"]), vm.append(f["von_mises"])
        flex.append(np.full(c.mesh.elements.shape[0], k))
    mesh = meshio.Mesh(
        _pad3(np.vstack(pts)),
        [("quad9", np.vstack(cells))],
        point_data={
            "displacement": _pad3(np.vstack(disp)),
            "green_lagrange_strain": np.vstack(strain),
            "von_mises": np.concatenate(vm),
        },
        cell_data={"flexure": [np.concatenate(flex)]},
    )
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        mesh.write(tmp, file_format="vtu")
    return path


def render_png(vtu: str | Path, png: str | Path, title: str = "") -> Path:
    """Off-screen PyVista picture of a :func:`write_vtu` file, deformed, coloured by von Mises."""
    import pyvista

    pyvista.OFF_SCREEN = True
    grid = pyvista.read(str(vtu)).warp_by_vector("displacement")
    vm = np.asarray(grid.point_data["von_mises"])
    with pyvista.vtk_verbosity("error"):  # no display: VTK warns, renders off-screen anyway
        plotter = pyvista.Plotter(off_screen=True, window_size=(1200, 900))
        # the clamp corners are stress singularities: scale the colours to the 99th percentile
        plotter.add_mesh(
            grid,
            scalars="von_mises",
            cmap="viridis",
            clim=[0.0, float(np.percentile(vm, 99))],
            scalar_bar_args={"title": "von Mises (MPa)"},
        )
        if title:
            plotter.add_text(title, font_size=12)
        plotter.view_xy()
        png = Path(png)
        png.parent.mkdir(parents=True, exist_ok=True)
        try:
            with atomic_path(png) as tmp:
                plotter.screenshot(str(tmp))
        finally:
            plotter.close()
    return png
