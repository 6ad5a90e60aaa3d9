"""VTU output of the 3D continuum: the flexures' hexahedra and their displacements.

The cells are VTK's triquadratic hexahedra (meshio ``hexahedron27``), whose
node order differs from the 27-node element's own (``k * 9 + a``, the quad9's
node a on node layer k: :mod:`flexval.geometry.extrude`): corners, the
twelve edge midpoints (bottom, top, vertical), the face centres of the
faces y = -1, x = +1, y = +1, x = -1, z = -1, z = +1 (reference coordinates),
then the centre. Only the meshed half (z >= 0) is written; the mirror half
is its reflection. Units: mm.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .connector3d import Continuum3DConnector
from .output import save_vtu

VTK_ORDER = np.array(
    [
        0,
        1,
        2,
        3,
        18,
        19,
        20,
        21,
        4,
        5,
        6,
        7,
        22,
        23,
        24,
        25,
        9,
        10,
        11,
        12,
        13,
        14,
        15,
        16,
        8,
        26,
        17,
    ]
)
"""The element's local node at each position of VTK's hexahedron27 order."""


def write_vtu_3d(
    path: str | Path,
    conns: Sequence,
    states: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]],
) -> Path:
    """Write every 3D flexure (reference geometry, hexahedron27 cells) with its displacement.

    ``states[k]`` is (pose_a, pose_b, internal) of ``conns[k]``; other
    connectors (pins) are left out. Warp by the ``displacement`` point data
    (mm) to see the deformed half; the cell data ``flexure`` numbers the
    flexures. Written atomically.
    """
    import meshio

    points, cells, disp, flex = [], [], [], []
    offset = 0
    meshed = [(c, s) for c, s in zip(conns, states) if isinstance(c, Continuum3DConnector)]
    for k, (c, state) in enumerate(meshed):
        points.append(c.mesh.nodes)
        disp.append(c.positions(*state) - c.mesh.nodes)
        cells.append(c.mesh.elements[:, VTK_ORDER] + offset)
        flex.append(np.full(c.mesh.elements.shape[0], k))
        offset += c.mesh.nodes.shape[0]
    mesh = meshio.Mesh(
        np.vstack(points),
        [("hexahedron27", np.vstack(cells))],
        point_data={"displacement": np.vstack(disp)},
        cell_data={"flexure": [np.concatenate(flex)]},
    )
    return save_vtu(path, mesh)
