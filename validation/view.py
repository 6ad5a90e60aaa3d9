"""``flexval view``: a result's VTK files in a PyVista window, or as a picture.

Reads a time series of ``flexval run --vtu`` (``.pvd``: the deformed mechanism at every
level, :mod:`flexval.validation.series`) or a single ``.vtu`` (one level of it, or the
continuum's stress field on its reference mesh, which is drawn warped by its
``displacement``). The window has a slider over the levels; ``--screenshot`` renders one
level off-screen to a PNG instead (no display needed). Lengths in mm, stresses in MPa.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE

FIELDS = ("fibre_stress", "displacement", "von_mises")
"""The point data a view can colour by: signed fibre stress (MPa), displacement magnitude
(mm), the continuum's von Mises stress (MPa)."""

UNITS = {"fibre_stress": "MPa", "displacement": "mm", "von_mises": "MPa"}


def has_display() -> bool:
    """Whether an interactive window can open: always on Windows and macOS, on other systems
    where ``DISPLAY`` or ``WAYLAND_DISPLAY`` is set."""
    if sys.platform.startswith(("win", "darwin")):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def read_levels(path: str | Path) -> list:
    """Every level of a result as a PyVista dataset: the grids of a ``.pvd`` series in its
    order, or the one grid of a ``.vtu``.

    Raises
    ------
    SceneError
        Naming the path when it is missing, of another kind, or unreadable.
    """
    import pyvista

    _quiet_vtk()
    target = Path(path)
    if target.suffix.lower() not in (".pvd", ".vtu"):
        raise SceneError(COMMAND_LINE, "RESULT", str(path), "expected a .pvd series or a .vtu file")
    if not target.is_file():
        raise SceneError(COMMAND_LINE, "RESULT", str(path), "no such file")
    try:
        if target.suffix.lower() == ".vtu":
            return [pyvista.read(target)]
        reader = pyvista.get_reader(str(target))
        levels = []
        for time in reader.time_values:
            reader.set_active_time_value(time)
            found = reader.read()
            levels.append(found[0] if isinstance(found, pyvista.MultiBlock) else found)
    except Exception as exc:  # VTK's readers raise many kinds on a damaged file
        raise SceneError(
            COMMAND_LINE, "RESULT", str(path), f"not readable as VTK ({type(exc).__name__}: {exc})"
        ) from None
    if not levels:
        raise SceneError(COMMAND_LINE, "RESULT", str(path), "holds no level")
    empty = [k for k, g in enumerate(levels) if g is None or g.n_points == 0]
    if empty:
        raise SceneError(
            COMMAND_LINE,
            "RESULT",
            str(path),
            f"level {empty[0]} holds no mesh (its file missing or damaged)",
        )
    return levels


def _quiet_vtk() -> None:
    """Keep VTK's own log off the terminal: a reader's failure is raised and reported as
    bad input, and an off-screen render's failed X connection before its fallback is not
    the user's concern."""
    from vtkmodules.vtkCommonCore import vtkLogger, vtkObject

    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    vtkObject.GlobalWarningDisplayOff()


def prepared(grid, field: str):
    """``grid`` ready to draw coloured by ``field``: a reference mesh (the continuum's field
    file, no ``level`` in its field data) warped by its displacement; the displacement
    coloured by its magnitude (mm).

    Raises
    ------
    SceneError
        If ``grid`` has no such point data (naming the fields it has).
    """
    if field not in grid.point_data:
        raise SceneError(
            COMMAND_LINE,
            "--field",
            field,
            f"not in this result (it has: {sorted(grid.point_data.keys())})",
        )
    shown = grid.copy()
    if "level" not in grid.field_data and "displacement" in grid.point_data:
        shown = shown.warp_by_vector("displacement")
    if field == "displacement":
        shown.point_data["|displacement|"] = np.linalg.norm(grid.point_data[field], axis=1)
    return shown


def _scalars(field: str) -> str:
    return "|displacement|" if field == "displacement" else field


def _title(grid, level: int, field: str) -> str:
    load = grid.field_data.get("load")
    unit = grid.field_data.get("load_unit")
    text = f"level {level}"
    if load is not None and unit is not None:
        text += f", load {float(np.asarray(load)[0]):.4g} {np.asarray(unit)[0]}"
    return f"{text}: {field} ({UNITS.get(field, '')})"


def _add(plotter, grid, level: int, field: str, limits) -> None:
    plotter.add_mesh(
        prepared(grid, field),
        scalars=_scalars(field),
        clim=limits,
        cmap="coolwarm" if field == "fibre_stress" else "viridis",
        show_edges=False,
        name="mechanism",
        scalar_bar_args={"title": f"{field} ({UNITS.get(field, '')})"},
    )
    plotter.add_text(_title(grid, level, field), name="title", font_size=10)


def _limits(levels: list, field: str) -> tuple[float, float]:
    """Colour range over every level, symmetric about zero for a signed stress."""
    values = [np.asarray(prepared(g, field).point_data[_scalars(field)]) for g in levels]
    low = min(float(v.min()) for v in values)
    high = max(float(v.max()) for v in values)
    if field == "fibre_stress":
        top = max(abs(low), abs(high)) or 1.0
        return -top, top
    return (low, high) if high > low else (low, low + 1.0)


def screenshot(levels: list, level: int, field: str, png: Path) -> Path:
    """Render ``levels[level]`` off-screen, in the plane, coloured by ``field``; write ``png``
    atomically."""
    import pyvista

    from flexval.geometry.files import atomic_path

    _quiet_vtk()
    plotter = pyvista.Plotter(off_screen=True, window_size=(1200, 900))
    _add(plotter, levels[level], level % len(levels), field, _limits(levels, field))
    plotter.view_xy()
    plotter.enable_parallel_projection()
    png.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(png) as tmp:
        plotter.screenshot(str(tmp))
    plotter.close()
    return png


def show(levels: list, level: int, field: str) -> None:
    """Open the interactive window, a slider over the levels where there are several."""
    import pyvista

    limits = _limits(levels, field)
    plotter = pyvista.Plotter(title="flexval view")
    _add(plotter, levels[level], level % len(levels), field, limits)
    if len(levels) > 1:

        def pick(value: float) -> None:
            k = int(round(value))
            _add(plotter, levels[k], k, field, limits)

        plotter.add_slider_widget(
            pick,
            [0, len(levels) - 1],
            value=level % len(levels),
            title="level",
            fmt="%.0f",
        )
    plotter.view_xy()
    plotter.enable_parallel_projection()
    plotter.show()


def check_level(levels: list, level: int) -> int:
    """``level`` as an index into ``levels`` (negative from the end).

    Raises
    ------
    SceneError
        Naming ``--level`` when it is out of range.
    """
    if not -len(levels) <= level < len(levels):
        raise SceneError(
            COMMAND_LINE,
            "--level",
            level,
            f"this result has {len(levels)} level(s): 0..{len(levels) - 1} (or -1 for the last)",
        )
    return level % len(levels)
