"""A load path as a VTK time series: the deformed mechanism at every level, for ParaView and
PyVista, from any model family.

Each level becomes one unstructured grid (``.vtu``, written with PyVista) holding

- every flexure as a solid strip: its centre line swept with its true thickness h(s) (a
  taper's or a notch's included), quadrilateral cells; the centre line is the model's own
  deformed shape (:attr:`~flexval.reducedmodels.LoadPath.shapes`); where the model's points
  lie on the flexure's centre line (beam nodes, DCMM chord ends, the continuum's mid-surface
  nodes) the true curved centre line between them is carried along with each chord, so that
  an arc drawn by a few chords stays an arc; a representative polyline off the centre line
  (the PRBM's pivots) is swept as it is;
- every rigid body (the ground included) as the polygon of its attachment points;

with the point data ``displacement`` (mm, from the rest state) and ``fibre_stress`` (MPa,
signed, tension positive: N/A +- M h / (2 I) on either face from the model's own section
forces, :attr:`~flexval.reducedmodels.LoadPath.section_forces`; zero on the rigid bodies),
the cell data ``part`` (index into the field data ``parts``) and ``rigid`` (1 on a body), and
the field data ``load`` (N or N mm), ``load_unit`` and ``level``. A ``.pvd`` collection lists
the levels (its time: the level's index, or the time of a dynamic run). In ParaView: open the
``.pvd``, colour by ``fibre_stress``, play the levels.

Lengths in mm, stresses in MPa.
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from flexval.geometry import Flexure, Scene
from flexval.geometry.files import atomic_path
from flexval.geometry.kinematics import place_points
from flexval.reducedmodels import LoadPath
from flexval.reducedmodels.core.sections import constants_at

from .outputs import inside, output_path, safe_name, write_text

PIECE_SAMPLES = 24
"""Points along each piece of a flexure's drawn centre line between two of the model's points
(with a notch's or taper's thickness change resolved by the flexure's whole length:
:data:`LENGTH_SAMPLES`)."""

LENGTH_SAMPLES = 200
"""At least this many points along each flexure's drawn centre line, mm-free (a fraction of
the length each)."""

ON_LINE = 1e-6
"""A model's shape point lies on the flexure's centre line when it is within this share of
the flexure's length of it at rest (beam nodes, chord ends: round-off; the PRBM's pivots lie
a sizable share off it)."""

_VTK_QUAD, _VTK_POLYGON, _VTK_LINE, _VTK_VERTEX = 9, 7, 3, 1


def _fractions(polyline: np.ndarray) -> np.ndarray:
    """Arc-length fraction (0..1) of each point of a polyline (m, 2)."""
    lengths = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(polyline, axis=0).T))])
    return lengths / lengths[-1] if lengths[-1] > 0.0 else np.linspace(0.0, 1.0, len(polyline))


def _sample_fractions(vertices: np.ndarray) -> np.ndarray:
    """Fractions at which a flexure is drawn: every vertex of the model's shape, and
    :data:`PIECE_SAMPLES` points in each piece between two, at least :data:`LENGTH_SAMPLES`
    in all."""
    uniform = np.linspace(0.0, 1.0, LENGTH_SAMPLES)
    pieces = [np.linspace(a, b, PIECE_SAMPLES) for a, b in zip(vertices[:-1], vertices[1:])]
    return np.unique(np.concatenate([uniform, vertices, *pieces]))


def _as_complex(points: np.ndarray) -> np.ndarray:
    return points[..., 0] + 1j * points[..., 1]


def _as_points(z: np.ndarray) -> np.ndarray:
    return np.column_stack([z.real, z.imag])


def _carried_line(
    flexure: Flexure, vertices: np.ndarray, deformed: np.ndarray, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rest and deformed centre line (mm) at fractions ``u``, and their unit left normals:
    each rest piece between two of the model's points (at fractions ``vertices``) carried by
    the rotation, stretch and shift that take its rest chord onto the deformed one."""
    length = flexure.shape.length
    rest = flexure.shape.point(u * length)
    tangent = _as_complex(flexure.shape.tangent(u * length))
    ends = _as_complex(flexure.shape.point(vertices * length))
    moved = _as_complex(deformed)
    piece = np.clip(np.searchsorted(vertices, u, side="right") - 1, 0, len(vertices) - 2)
    a, b, a2, b2 = ends[piece], ends[piece + 1], moved[piece], moved[piece + 1]
    chord = b - a
    factor = np.where(np.abs(chord) > 0.0, (b2 - a2) / np.where(chord == 0, 1.0, chord), 1.0)
    turned = tangent * factor / np.maximum(np.abs(factor), 1e-300)
    return (
        rest,
        _as_points(a2 + (_as_complex(rest) - a) * factor),
        _as_points(1j * tangent),
        _as_points(1j * turned),
    )


def _normals(line: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Unit left normals (m, 2) of a polyline sampled at fractions ``u``, from its
    tangents (second-order differences on the uneven spacing)."""
    tangent = np.gradient(line, u, axis=0)
    tangent /= np.maximum(np.hypot(*tangent.T), 1e-300)[:, None]
    return np.column_stack([-tangent[:, 1], tangent[:, 0]])


def _fibre_stresses(
    flexure: Flexure, forces: dict | None, level: int, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Signed outer-fibre stress (MPa) on the left and right faces at fractions ``u``:
    N/A + M h/(2I) on the left (a counterclockwise section moment on the part towards the
    end body compresses the right face), zero where the model has no section forces."""
    if forces is None or level >= len(forces["axial"]):
        return np.zeros(u.size), np.zeros(u.size)
    at = np.asarray(forces["at"], float)
    axial = np.interp(u, at, np.asarray(forces["axial"][level], float))
    moment = np.interp(u, at, np.asarray(forces["moment"][level], float))
    h, area, inertia = constants_at(flexure.section, u)
    bending = moment * h / (2.0 * inertia)
    return axial / area + bending, axial / area - bending


def flexure_strip(
    flexure: Flexure, shapes: list, level: int, forces: dict | None = None
) -> dict[str, np.ndarray]:
    """One flexure at ``level`` as a solid strip of its true thickness.

    Parameters
    ----------
    flexure : Flexure
    shapes : list
        The model's shape of the flexure at every level (``LoadPath.shapes[name]``, mm),
        from either end; level 0 is the rest state of a load path.
    level : int
    forces : dict, optional
        ``LoadPath.section_forces[name]`` (N, N mm); without it the stresses are zero.

    Returns
    -------
    dict
        ``points`` (2m, 2) deformed (left face, then right face), ``rest`` (2m, 2) the same
        material points at rest, mm; ``stress`` (2m,) signed fibre stress, MPa; ``quads``
        (m - 1, 4) point indices, counterclockwise at rest.
    """
    first = np.asarray(shapes[0], float)
    now = np.asarray(shapes[level], float)
    length = flexure.shape.length
    ends = flexure.shape.point(np.array([0.0, length]))
    if np.hypot(*(first[0] - ends[1])) < np.hypot(*(first[0] - ends[0])):
        first, now = first[::-1], now[::-1]  # a model's polyline drawn from the second end
    vertices = _fractions(first)
    off_line = np.hypot(*(flexure.shape.point(vertices * length) - first).T).max()
    u = _sample_fractions(vertices)
    if off_line <= ON_LINE * length:
        rest_line, line, rest_normal, normal = _carried_line(flexure, vertices, now, u)
    else:  # a representative polyline: swept as it is
        rest_line = np.column_stack([np.interp(u, vertices, first[:, k]) for k in (0, 1)])
        line = np.column_stack([np.interp(u, vertices, now[:, k]) for k in (0, 1)])
        rest_normal, normal = _normals(rest_line, u), _normals(line, u)
    half = 0.5 * flexure.section.thickness_at(u * length)[:, None]
    left, right = _fibre_stresses(flexure, forces, level, u)
    m = u.size
    quads = np.column_stack(
        [np.arange(m - 1), np.arange(m - 1) + m, np.arange(1, m) + m, np.arange(1, m)]
    )
    return {
        "points": np.vstack([line + half * normal, line - half * normal]),
        "rest": np.vstack([rest_line + half * rest_normal, rest_line - half * rest_normal]),
        "stress": np.concatenate([left, right]),
        "quads": quads,
    }


def level_grid(scene: Scene, path: LoadPath, level: int):
    """The deformed mechanism of ``path`` at ``level`` as a PyVista UnstructuredGrid (see the
    module's description; mm, MPa).

    Raises
    ------
    ValueError
        If ``path`` holds no poses or no shapes (run it with ``record_poses`` and
        ``record_shapes``).
    """
    import pyvista

    if path.poses is None or path.shapes is None:
        raise ValueError(
            f"{path.model} on {path.load_case}: a time series needs the poses and shapes "
            "of every level (run with record_poses=True, record_shapes=True)"
        )
    mech = scene.mechanism
    points, rest, stress, cells, types, part, rigid, names = [], [], [], [], [], [], [], []
    count = 0
    for flexure in mech.flexures:
        shapes = path.shapes.get(flexure.name)
        if not shapes:
            continue
        forces = (path.section_forces or {}).get(flexure.name)
        strip = flexure_strip(flexure, shapes, level, forces)
        points.append(strip["points"]), rest.append(strip["rest"]), stress.append(strip["stress"])
        for quad in strip["quads"] + count:
            cells.append([4, *quad.tolist()])
        types += [_VTK_QUAD] * len(strip["quads"])
        part += [len(names)] * len(strip["quads"])
        rigid += [0] * len(strip["quads"])
        names.append(flexure.name)
        count += len(strip["points"])
    for name, body in mech.bodies.items():
        poses = path.poses.get(name)
        at_rest = np.asarray(body.points, float)
        placed = (
            at_rest
            if not poses
            else place_points(np.asarray(poses[level], float), at_rest - body.reference)
        )
        n = len(at_rest)
        points.append(placed), rest.append(at_rest), stress.append(np.zeros(n))
        cells.append([n, *range(count, count + n)])
        types.append(_VTK_POLYGON if n >= 3 else _VTK_LINE if n == 2 else _VTK_VERTEX)
        part.append(len(names)), rigid.append(1)
        names.append(name)
        count += n
    xy, xy0 = np.vstack(points), np.vstack(rest)
    grid = pyvista.UnstructuredGrid(
        np.concatenate([np.asarray(c, np.int64) for c in cells]),
        np.asarray(types, np.uint8),
        np.column_stack([xy, np.zeros(len(xy))]),
    )
    grid.point_data["displacement"] = np.column_stack([xy - xy0, np.zeros(len(xy))])
    grid.point_data["fibre_stress"] = np.concatenate(stress)
    grid.cell_data["part"] = np.asarray(part, np.int32)
    grid.cell_data["rigid"] = np.asarray(rigid, np.uint8)
    grid.field_data["parts"] = np.asarray(names)
    grid.field_data["load"] = np.asarray([path.load[level]], float)
    grid.field_data["load_unit"] = np.asarray([path.load_unit])
    grid.field_data["level"] = np.asarray([level], np.int64)
    return grid


def series_stem(scene: Scene, path: LoadPath) -> str:
    """The file stem of a path's series: scene, load case and model."""
    return f"{scene.name}_{path.load_case}_{path.model.replace(':', '')}"


def write_series(folder: str | Path, scene: Scene, path: LoadPath) -> Path:
    """Write ``path`` as a time series into ``folder``: ``STEM.pvd`` and one
    ``STEM/level_KKK.vtu`` per level (:func:`level_grid`), each written atomically, the
    collection last. Returns the ``.pvd`` path.

    Raises
    ------
    ValueError
        As :func:`level_grid`.
    flexval.geometry.files.OutputError
        If a file cannot be written, or would land outside ``folder``.
    """
    stem = safe_name(series_stem(scene, path))
    collection = output_path(folder, stem, ".pvd")
    levels = inside(folder, stem)
    levels.mkdir(parents=True, exist_ok=True)
    times = path.time if path.time is not None else list(range(len(path.load)))
    entries = []
    for k in range(len(path.load)):
        name = f"level_{k:03d}.vtu"
        grid = level_grid(scene, path, k)
        with atomic_path(levels / name) as tmp:
            grid.save(tmp)
        entries.append(
            f'    <DataSet timestep="{float(times[k])!r}" group="" part="0" '
            f"file={quoteattr(f'{stem}/{name}')}/>"
        )
    write_text(
        collection,
        '<?xml version="1.0"?>\n'
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
        "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n",
    )
    return collection
