"""A flexure's quad9 mesh extruded through its depth into 27-node Lagrange hexahedra.

The 3D continuum reference (``continuum:LEVEL[3d]``) meshes a flexure as a
solid: the same in-plane quad9 mesh the 2D continuum uses at that level
(:func:`flexval.geometry.outline.flexure_mesh`), repeated on layers across the
out-of-plane depth b. By default only half the depth is meshed, z in
[0, b/2]: a planar mechanism loads its flexures symmetrically about the
mid-plane z = 0, so the mid-plane nodes keep z = 0 and the half carries half
the energy.

Layers. A strip bent in its plane curls the other way across its depth
(anticlastic curvature); the out-of-plane free faces z = +-b/2 then carry a
boundary layer of width about ``delta = sqrt(R h)`` (R the radius of
curvature, h the in-plane thickness: the decay length of a bent plate's edge
effect), outside which the section is in plane strain across the depth. The
layers are graded towards the free face so that the outer half of them lies
within ``delta`` of it, their thicknesses a geometric progression from the
mid-plane outwards (ratio ``r <= 1``, closed form in :func:`layer_bounds`);
when ``delta`` covers half the half-depth or more the layers are uniform. A
straight flexure takes ``delta = b`` (uniform layers). The count is
``2**(level + 1)`` layers across the half-depth, so that each level halves
the element size in all three directions.

Node numbering is layer-major: node ``j * n2 + i`` is the 2D mesh's node i
on node layer j (``2 n_z + 1`` node layers: the layers' bounds and their
mid-planes). An element's 27 nodes are ``k * 9 + a``: node a of the quad9
(Gmsh order) on the element's node layer k = 0, 1, 2 (bottom, middle, top).

Units: mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .mesh import FlexureMesh
from .outline import flexure_mesh


@dataclass(frozen=True)
class ExtrudedMesh:
    """A 27-node hexahedral mesh of one flexure (see the module docstring).

    Attributes
    ----------
    plane : FlexureMesh
        The in-plane quad9 mesh every node layer repeats.
    z : ndarray (2 n_z + 1,)
        The node layers' out-of-plane coordinates, mm, increasing.
    nodes : ndarray (n_nodes, 3)
        Node coordinates, mm (layer-major).
    elements : ndarray (n_elements, 27)
        Node indices per element, local node ``k * 9 + a``.
    half : bool
        True if only z in [0, b/2] is meshed (symmetry about the mid-plane).
    """

    plane: FlexureMesh
    z: np.ndarray
    nodes: np.ndarray
    elements: np.ndarray
    half: bool

    @property
    def per_layer(self) -> int:
        """Nodes on one node layer (the 2D mesh's)."""
        return self.plane.nodes.shape[0]

    def layer_nodes(self, nodes2d: np.ndarray, layers: np.ndarray | None = None) -> np.ndarray:
        """The 3D nodes (layers, len(nodes2d)) of 2D nodes ``nodes2d`` on node ``layers``
        (default all)."""
        layers = np.arange(self.z.size) if layers is None else np.asarray(layers)
        return layers[:, None] * self.per_layer + np.asarray(nodes2d)[None, :]

    @property
    def mid_layer(self) -> int:
        """Index of the node layer at z = 0."""
        return int(np.argmin(np.abs(self.z)))

    @property
    def centre_line(self) -> np.ndarray:
        """The centre line's nodes on the mid-plane z = 0, start to end."""
        return self.layer_nodes(self.plane.centre_line, [self.mid_layer])[0]


def mean_radius(plane: FlexureMesh) -> float:
    """Length over total turning of the mesh's centre line, mm (inf: straight).

    The radius of an arc (to the chords' (angle per chord)^2 / 24, below 1e-4 on any
    mesh level); for any other centre line its mean radius of curvature. The turning
    is taken between the first and the last chord, over the length between their
    midpoints.
    """
    line = plane.nodes[plane.centre_line]
    d = np.diff(line, axis=0)
    angles = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    turning = abs(angles[-1] - angles[0])
    chords = np.hypot(d[:, 0], d[:, 1])
    length = float(chords.sum() - 0.5 * (chords[0] + chords[-1]))
    return math.inf if turning < 1e-9 else length / turning


def boundary_layer(radius: float, thickness: float, depth: float) -> float:
    """Width delta = sqrt(R h) of the anticlastic boundary layer at a free face, mm.

    ``radius`` R (inf: straight, then delta = the depth b), ``thickness`` h, ``depth`` b, mm.
    """
    return depth if math.isinf(radius) else math.sqrt(radius * thickness)


def layers(level: int) -> int:
    """Element layers across the half-depth at mesh ``level``: 2, 4, 8, ..."""
    return 2 ** (level + 1)


def layer_bounds(half_depth: float, delta: float, count: int) -> np.ndarray:
    """Bounds (count + 1,) of ``count`` layers over [0, half_depth], graded towards half_depth.

    Thicknesses t_k = t_0 r^k (k = 0 at the mid-plane). The outer m =
    count // 2 layers cover the fraction f = min(1/2, delta / half_depth) of
    the half-depth, i.e. r^m / (1 + r^m) = f for an even count, so
    r = (f / (1 - f))^(1/m); f = 1/2 gives uniform layers. All lengths mm.
    """
    if count < 2 or count % 2:
        raise ValueError(f"the layer count must be even and at least 2, got {count}")
    f = min(0.5, delta / half_depth)
    r = (f / (1.0 - f)) ** (1.0 / (count // 2))
    t = r ** np.arange(count)
    return half_depth * np.concatenate([[0.0], np.cumsum(t) / t.sum()])


def extrude(plane: FlexureMesh, bounds: np.ndarray, half: bool = True) -> ExtrudedMesh:
    """Extrude ``plane`` over the layers between ``bounds`` (mm, increasing from 0).

    ``half``: mesh z in [0, bounds[-1]] only; otherwise the mirror image too
    (z in [-bounds[-1], bounds[-1]]), for checks of the symmetry.
    """
    bounds = np.asarray(bounds, float)
    if not half:
        bounds = np.concatenate([-bounds[:0:-1], bounds])
    mids = 0.5 * (bounds[:-1] + bounds[1:])
    z = np.empty(2 * mids.size + 1)
    z[0::2], z[1::2] = bounds, mids
    n2, n_z = plane.nodes.shape[0], mids.size
    nodes = np.column_stack([np.tile(plane.nodes, (z.size, 1)), np.repeat(z, n2)])
    k = 2 * np.arange(n_z)[:, None, None] + np.arange(3)[None, :, None]  # node layers
    elements = (k[:, None] * n2 + plane.elements[None, :, None, :]).reshape(-1, 27)
    return ExtrudedMesh(plane, z, nodes, elements, half)


def extruded_mesh(
    shape, section, level: int, half: bool = True, use_cache: bool = True
) -> ExtrudedMesh:
    """The 27-node mesh of a flexure at ``level`` (layers and grading: the module docstring).

    Parameters
    ----------
    shape : Shape
        Centre line, mm.
    section : Section
        Depth b and thickness h (uniform or h(s); the grading uses its smallest h), mm.
    level : int
        Mesh level, 0 .. MAX_LEVEL, of the in-plane mesh and of the layers.
    half : bool
        Only the half z >= 0 (default).
    use_cache : bool
        Read and write the in-plane mesh's on-disk cache.
    """
    plane = flexure_mesh(shape, section, level, use_cache)
    delta = boundary_layer(mean_radius(plane), section.thickness, section.depth)
    return extrude(plane, layer_bounds(0.5 * section.depth, delta, layers(level)), half)
