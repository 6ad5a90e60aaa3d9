"""Gmsh meshes of one flexure as a 2D solid (second-order structured quadrilaterals).

An arc flexure is the annular band between radii r - h/2 and r + h/2 over
the arc's polar angles (start at ``axis - width/2``); a straight
:class:`~flexval.geometry.shapes.Segment` is a rectangle of thickness h around it.
The band is meshed with Gmsh's transfinite algorithm into biquadratic
9-node quadrilaterals (quad9): ``n_t`` elements across the thickness and
``n_l`` along the length. Level 0 has one element across the thickness and
elements ``ASPECT_RATIO * h`` long on the centre line; each level halves the
element size in both directions (``n_t = 2**level``, ``n_l = n_l(0) * 2**level``),
so refinement is shape-regular.

Why quad9 and square elements (ASPECT_RATIO = 1): a biquadratic element carries
a strip's pure bending exactly, and the parasitic membrane strain of a curved
element, whose relative error grows like A^4 (h/r)^2 with the aspect ratio A,
is negligible from A = 1 on (measured in the documentation's models page,
``continuum``). Every node is put exactly on the polar map of the band; the
end faces are Gmsh physical groups ``start`` and ``end``, checked
geometrically; meshes are cached on disk (:func:`flexval.geometry.files.cache_dir`)
under a hash of the exact values that define them, and an entry that fails its
checksum is discarded with a :class:`flexval.geometry.files.CacheWarning` and
rebuilt (ARCHITECTURE.md, "Geometry"). Nothing here knows about a solver.

Units: mm, rad.
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
import zipfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .files import CacheWarning, atomic_path, cache_dir
from .shapes import Arc, FlexureShape

MESH_VERSION = 2
"""Bumped whenever the meshing code changes what it produces (invalidates the cache)."""

ELEMENT_ORDER = 2
"""Polynomial order of the elements (quad9)."""

ASPECT_RATIO = 1.0
"""Element length along the centre line over element size across the thickness."""

MAX_LEVEL = 8

CACHE_FORMAT = 2
"""Layout of a cached mesh file (2: with a checksum); part of the key."""

_ARRAYS = ("nodes", "elements", "start_face", "end_face", "centre_line")

# quad9 node order (Gmsh and meshio): corners 0-3 counterclockwise, then
# mid-edge nodes of edges 0-1, 1-2, 2-3, 3-0, then the centre.  Natural
# coordinates (xi, eta) of each node in [0, 1]^2:
_QUAD9_NATURAL = np.array(
    [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5], [0.5, 0.5]]
)
_QUAD9_REVERSED = np.array([0, 3, 2, 1, 7, 6, 5, 4, 8])


@dataclass(frozen=True)
class FlexureMesh:
    """A quad9 mesh of one flexure.

    Attributes
    ----------
    nodes : ndarray (n_nodes, 2)
        Node coordinates, mm.
    elements : ndarray (n_elements, 9)
        Node indices per element in quad9 order, counterclockwise.
    start_face, end_face : ndarray (2 n_t + 1,)
        Nodes on the start and end faces, ordered from the inner (r - h/2,
        or the right-hand side of a segment) to the outer edge.
    centre_line : ndarray (2 n_l + 1,)
        Nodes on the centre line, from start to end.
    level, n_t, n_l : int
        Mesh level and elements across the thickness and along the length.
    """

    nodes: np.ndarray
    elements: np.ndarray
    start_face: np.ndarray
    end_face: np.ndarray
    centre_line: np.ndarray
    level: int
    n_t: int
    n_l: int


def divisions(shape: FlexureShape, thickness: float, level: int) -> tuple[int, int]:
    """Elements (across the thickness, along the length) of a mesh level.

    Parameters
    ----------
    shape : Arc or Segment
    thickness : float
        In-plane thickness h, mm.
    level : int
        Mesh level (0 = coarsest).
    """
    if not 0 <= level <= MAX_LEVEL:
        raise ValueError(f"mesh level must be between 0 and {MAX_LEVEL}, got {level}")
    if not thickness > 0.0:
        raise ValueError(f"thickness must be positive, got {thickness}")
    n_l0 = max(1, math.ceil(shape.length / (ASPECT_RATIO * thickness) - 1e-9))
    return 2**level, n_l0 * 2**level


def _key(shape: FlexureShape, thickness: float, level: int) -> str:
    if isinstance(shape, Arc):
        desc = {
            "kind": "arc",
            "center": list(map(float.hex, map(float, shape.center))),
            "radius": float(shape.radius).hex(),
            "axis": float(shape.axis).hex(),
            "width": float(shape.width).hex(),
        }
    else:
        desc = {
            "kind": "segment",
            "start": list(map(float.hex, map(float, shape.start))),
            "end": list(map(float.hex, map(float, shape.end))),
        }
    desc.update(
        h=float(thickness).hex(),
        level=level,
        order=ELEMENT_ORDER,
        aspect=ASPECT_RATIO,
        version=MESH_VERSION,
        cache_format=CACHE_FORMAT,
    )
    return hashlib.sha256(json.dumps(desc, sort_keys=True).encode()).hexdigest()[:24]


def _checksum(key: str, arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 of the key and every array's dtype, shape and bytes."""
    h = hashlib.sha256(key.encode())
    for name in _ARRAYS:
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def mesh_flexure(
    shape: FlexureShape, thickness: float, level: int, use_cache: bool = True
) -> FlexureMesh:
    """Structured quad9 mesh of one flexure (cached on disk).

    Parameters
    ----------
    shape : Arc or Segment
        Centre line of the flexure.
    thickness : float
        In-plane thickness h, mm (for an arc, h < 2 r).
    level : int
        Mesh level, 0 .. MAX_LEVEL.
    use_cache : bool
        Read and write the on-disk cache.
    """
    n_t, n_l = divisions(shape, thickness, level)
    if thickness >= shape.max_thickness:
        raise ValueError(
            f"thickness {thickness} must be smaller than the diameter {shape.max_thickness}"
        )

    def build() -> FlexureMesh:
        nodes, elements, faces = _gmsh_band(shape, thickness, n_t, n_l)
        if isinstance(shape, Arc):
            nodes = _snap_polar(nodes, elements, shape)
        elements = counterclockwise(nodes, elements)
        start, end = (
            _face_nodes(nodes, faces[k], _face_segment(shape, thickness, k), thickness)
            for k in (0, 1)
        )
        centre = _centre_line(nodes, shape, thickness, 2 * n_l + 1)
        return FlexureMesh(nodes, elements, start, end, centre, level, n_t, n_l)

    return cached_mesh(_key(shape, thickness, level), level, n_t, n_l, build, use_cache)


def cached_mesh(
    key: str, level: int, n_t: int, n_l: int, build: Callable[[], FlexureMesh], use_cache: bool
) -> FlexureMesh:
    """The mesh stored under ``key`` in the cache folder, else ``build()`` (then stored).

    A stored mesh is used only if its level and divisions are those asked
    for; with ``use_cache`` False the cache is neither read nor written.
    """
    root = cache_dir() if use_cache else None  # None also when the folder cannot be used
    path = root / "meshes" / f"{key}.npz" if root is not None else None
    if path is not None:
        cached = _load(path, key, level, n_t, n_l)
        if cached is not None:
            return cached
    mesh = build()
    if path is not None:
        _save(path, key, mesh)
    return mesh


def _load(path: Path, key: str, level: int, n_t: int, n_l: int) -> FlexureMesh | None:
    """The cached mesh at ``path``, or None (a damaged entry is discarded with a warning)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {name: z[name] for name in _ARRAYS}
            stored = str(z["checksum"])
    except FileNotFoundError:
        return None
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        return _discard(path, f"unreadable ({type(exc).__name__})")
    if stored != _checksum(key, arrays):
        return _discard(path, "checksum mismatch")
    mesh = FlexureMesh(*(arrays[name] for name in _ARRAYS), level, n_t, n_l)
    if not _consistent(mesh):
        return _discard(path, f"not a level-{level} mesh of {n_t} x {n_l} elements")
    return mesh


def _consistent(mesh: FlexureMesh) -> bool:
    """Array shapes, dtypes and index ranges match a structured quad9 mesh of its divisions."""
    n_nodes = (2 * mesh.n_t + 1) * (2 * mesh.n_l + 1)
    indices = (mesh.elements, mesh.start_face, mesh.end_face, mesh.centre_line)
    return (
        mesh.nodes.shape == (n_nodes, 2)
        and mesh.nodes.dtype == np.float64
        and bool(np.all(np.isfinite(mesh.nodes)))
        and mesh.elements.shape == (mesh.n_t * mesh.n_l, 9)
        and mesh.start_face.shape == mesh.end_face.shape == (2 * mesh.n_t + 1,)
        and mesh.centre_line.shape == (2 * mesh.n_l + 1,)
        and all(
            np.issubdtype(a.dtype, np.integer) and a.size and 0 <= a.min() and a.max() < n_nodes
            for a in indices
        )
    )


def _discard(path: Path, reason: str) -> None:
    warnings.warn(
        f"cached mesh {path} discarded ({reason}); rebuilding it", CacheWarning, stacklevel=3
    )
    path.unlink(missing_ok=True)
    return None


def _save(path: Path, key: str, mesh: FlexureMesh) -> None:
    """Store ``mesh`` atomically with its checksum (a failure only warns: caching is optional)."""
    arrays = {name: getattr(mesh, name) for name in _ARRAYS}
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, checksum=np.array(_checksum(key, arrays)), **arrays)
    except OSError as exc:
        warnings.warn(f"mesh not cached: {exc}", CacheWarning, stacklevel=3)


@contextmanager
def _gmsh_session() -> Iterator[object]:
    """A quiet Gmsh model; initialises/finalises Gmsh only if nobody else has."""
    import gmsh

    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
        previous = None
    else:
        previous = gmsh.model.getCurrent()
    terminal = gmsh.option.getNumber("General.Terminal")
    gmsh.option.setNumber("General.Terminal", 0)
    name = "flexval_flexure"
    gmsh.model.add(name)
    try:
        yield gmsh
    finally:
        gmsh.model.setCurrent(name)
        gmsh.model.remove()
        if owner:
            gmsh.finalize()
        else:
            gmsh.option.setNumber("General.Terminal", terminal)
            if previous:
                gmsh.model.setCurrent(previous)


def _gmsh_band(
    shape: FlexureShape, h: float, n_t: int, n_l: int
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """Gmsh quad9 mesh of the band; returns nodes, elements and the two faces' nodes."""
    with _gmsh_session() as gmsh:
        occ = gmsh.model.occ
        if isinstance(shape, Arc):
            # full-sweep OCC circles (a three-point arc would take the short way round)
            cx, cy = map(float, shape.center)
            r_in, r_out = shape.radius - 0.5 * h, shape.radius + 0.5 * h
            inner = occ.addCircle(
                cx, cy, 0.0, r_in, angle1=shape.start_angle, angle2=shape.end_angle
            )
            outer = occ.addCircle(
                cx, cy, 0.0, r_out, angle1=shape.start_angle, angle2=shape.end_angle
            )
            occ.synchronize()
            face = _face_segment(shape, h, 0)  # [inner, outer] start corners
            at_start, at_end = [], []
            for k, curve in enumerate((inner, outer)):
                ends = [t for _, t in gmsh.model.getBoundary([(1, curve)], oriented=False)]
                dist = [np.hypot(*(gmsh.model.getValue(0, t, [])[:2] - face[k])) for t in ends]
                at_start.append(ends[int(np.argmin(dist))])
                at_end.append(ends[1 - int(np.argmin(dist))])
            start = occ.addLine(at_start[0], at_start[1])
            end = occ.addLine(at_end[1], at_end[0])
            p = [at_start[0], at_start[1], at_end[1], at_end[0]]
        else:
            s0, s1 = np.asarray(shape.start, float), np.asarray(shape.end, float)
            t = (s1 - s0) / np.hypot(*(s1 - s0))
            n = np.array([-t[1], t[0]]) * 0.5 * h
            corners = [s0 - n, s0 + n, s1 + n, s1 - n]
            p = [occ.addPoint(float(x), float(y), 0.0) for x, y in corners]
            start, outer = occ.addLine(p[0], p[1]), occ.addLine(p[1], p[2])
            end, inner = occ.addLine(p[2], p[3]), occ.addLine(p[3], p[0])
        loop = occ.addCurveLoop([start, outer, end, inner])
        surf = occ.addPlaneSurface([loop])
        occ.synchronize()
        mesh = gmsh.model.mesh
        for curve, n in ((start, n_t), (end, n_t), (outer, n_l), (inner, n_l)):
            mesh.setTransfiniteCurve(curve, n + 1)
        mesh.setTransfiniteSurface(surf, cornerTags=p)
        mesh.setRecombine(2, surf)
        gmsh.model.addPhysicalGroup(1, [start], name="start")
        gmsh.model.addPhysicalGroup(1, [end], name="end")
        gmsh.model.addPhysicalGroup(2, [surf], name="flexure")
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
        mesh.generate(2)
        mesh.setOrder(ELEMENT_ORDER)
        tags, coords, _ = mesh.getNodes()
        index = np.full(int(tags.max()) + 1, -1)
        index[tags.astype(int)] = np.arange(tags.size)
        nodes = coords.reshape(-1, 3)[:, :2].copy()
        etypes, _, enodes = mesh.getElements(2, surf)
        quad9 = gmsh.model.mesh.getElementType("Quadrangle", ELEMENT_ORDER)
        if list(etypes) != [quad9]:
            raise RuntimeError(f"gmsh produced element types {list(etypes)}, expected quad9")
        elements = index[enodes[0].astype(int)].reshape(-1, 9)
        faces = tuple(
            index[gmsh.model.mesh.getNodesForPhysicalGroup(1, g)[0].astype(int)] for g in (1, 2)
        )
    return nodes, elements, faces


def _polar(points: np.ndarray, arc: Arc) -> tuple[np.ndarray, np.ndarray]:
    """Radius (mm) and polar angle from the arc's start (rad, in [-gap/2, width + gap/2))."""
    d = points - np.asarray(arc.center, float)
    rho = np.hypot(d[..., 0], d[..., 1])
    phi = np.mod(np.arctan2(d[..., 1], d[..., 0]) - arc.start_angle, 2.0 * np.pi)
    gap = 2.0 * np.pi - arc.width
    return rho, np.where(phi > arc.width + 0.5 * gap, phi - 2.0 * np.pi, phi)


def _snap_polar(nodes: np.ndarray, elements: np.ndarray, arc: Arc) -> np.ndarray:
    """Move every node to the exact polar image of its element's (rho, phi) rectangle."""
    rho, phi = _polar(nodes[elements[:, :4]], arc)  # (n_el, 4) corners
    xi, eta = _QUAD9_NATURAL[:, 0], _QUAD9_NATURAL[:, 1]
    w = np.stack([(1 - xi) * (1 - eta), xi * (1 - eta), xi * eta, (1 - xi) * eta])  # (4, 9)
    r9, p9 = rho @ w, arc.start_angle + phi @ w  # (n_el, 9)
    out = nodes.copy()
    out[elements, 0] = arc.center[0] + r9 * np.cos(p9)
    out[elements, 1] = arc.center[1] + r9 * np.sin(p9)
    return out


def counterclockwise(nodes: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """Elements reordered so that all are counterclockwise (positive area)."""
    x = nodes[elements[:, :4]]
    area2 = np.sum(
        x[:, :, 0] * np.roll(x[:, :, 1], -1, axis=1) - np.roll(x[:, :, 0], -1, axis=1) * x[:, :, 1],
        axis=1,
    )
    if np.any(area2 == 0.0):
        raise RuntimeError("degenerate element in flexure mesh")
    return np.where((area2 < 0.0)[:, None], elements[:, _QUAD9_REVERSED], elements)


def _face_segment(shape: FlexureShape, h: float, which: int) -> np.ndarray:
    """End face ``which`` (0: start, 1: end) as a segment [inner, outer], mm.

    Inner is r - h/2 for an arc, the right-hand side (seen along the segment)
    for a segment.
    """
    if isinstance(shape, Arc):
        a = shape.start_angle if which == 0 else shape.end_angle
        u = np.array([math.cos(a), math.sin(a)])
        c = np.asarray(shape.center, float)
        return np.array([c + (shape.radius - 0.5 * h) * u, c + (shape.radius + 0.5 * h) * u])
    p = shape.end_points[which]
    t = shape.tangent(0.0)
    n = np.array([-t[1], t[0]])
    return np.array([p - 0.5 * h * n, p + 0.5 * h * n])


def _face_nodes(nodes: np.ndarray, tagged: np.ndarray, seg: np.ndarray, h: float) -> np.ndarray:
    """Nodes on segment ``seg`` ordered along it; checked against the Gmsh tag."""
    d = seg[1] - seg[0]
    rel = nodes - seg[0]
    s = rel @ d / (d @ d)
    off = np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0]) / np.hypot(*d)
    tol = 1e-6 * h
    on = np.flatnonzero((off <= tol) & (s >= -tol / h) & (s <= 1 + tol / h))
    if set(on.tolist()) != set(np.asarray(tagged).tolist()):
        raise RuntimeError("end-face nodes found geometrically differ from the Gmsh tag")
    return on[np.argsort(s[on])]


def _centre_line(nodes: np.ndarray, shape: FlexureShape, h: float, count: int) -> np.ndarray:
    """Nodes on the centre line, ordered from start to end."""
    tol = 1e-6 * h
    if isinstance(shape, Arc):
        rho, phi = _polar(nodes, shape)
        on = np.flatnonzero(np.abs(rho - shape.radius) <= tol)
        order = phi[on]
    else:
        p0 = np.asarray(shape.start, float)
        t = (np.asarray(shape.end, float) - p0) / shape.length
        rel = nodes - p0
        on = np.flatnonzero(np.abs(rel[:, 0] * t[1] - rel[:, 1] * t[0]) <= tol)
        order = rel[on] @ t
    if on.size != count:
        raise RuntimeError(f"found {on.size} centre-line nodes, expected {count}")
    return on[np.argsort(order)]
