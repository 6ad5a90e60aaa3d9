"""Pictures onto your own Matplotlib axes (``flexval.plot``): a mechanism, its load paths,
its deformed shapes. The report's figures are drawn by the same functions.

Each function takes an optional ``ax`` (a new figure's axes where None) and returns the axes
it drew on, so that it composes with a notebook's or a paper's own figures::

    import matplotlib.pyplot as plt
    import flexval

    scene = flexval.load_scene("notch_fourbar")
    paths = [flexval.run_model(scene, m, "f+", record_poses=True, record_shapes=True)
             for m in ("beam:20", "prbm")]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 5))
    flexval.plot.deformed(scene, paths[0], ax=left)
    flexval.plot.load_path(paths, "dx", ax=right)

Lengths in mm, rotations in degrees on the axes, loads in N or N mm.
"""

from __future__ import annotations

from collections.abc import Sequence

from flexval.geometry import Scene
from flexval.reducedmodels import LoadPath

from .report.drawing import draw_mechanism
from .report.figures import draw_component, draw_deformed, legend_entries, load_path_curves

COMPONENTS = {
    "dx": "target point dx (mm)",
    "dy": "target point dy (mm)",
    "displacement": "target point |d| (mm)",
    "rotation": "target body rotation (deg)",
}
"""The components :func:`load_path` draws, and their axis labels."""


def _axes(ax, size: tuple[float, float]):
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=size)[1]


def mechanism(scene: Scene, ax=None, load_case: str | None = None):
    """Draw the undeformed mechanism: flexures at their true thickness, rigid links, the
    ground, pins, the target point and the loads (of ``load_case`` only, where given).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, (6, 6))
    draw_mechanism(scene, ax, load_case=load_case)
    return ax


def load_path(paths: LoadPath | Sequence[LoadPath], component: str = "displacement", ax=None):
    """Draw one component of one or more load paths versus |load| (N or N mm), each model in
    its report style, bifurcations marked with a cross and limit points with a diamond.

    Parameters
    ----------
    paths : LoadPath or sequence of LoadPath
        Paths of one load case (one curve each, labelled with its model).
    component : {'dx', 'dy', 'displacement', 'rotation'}
        Target point displacement (mm) or target body rotation (drawn in degrees).
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.axes.Axes

    Raises
    ------
    ValueError
        For an unknown component.
    """
    if component not in COMPONENTS:
        raise ValueError(f"component {component!r}: expected one of {sorted(COMPONENTS)}")
    chosen = [paths] if isinstance(paths, LoadPath) else list(paths)
    ax = _axes(ax, (6.5, 4.2))
    curves = load_path_curves({lp.model: lp for lp in chosen})
    unit = chosen[0].load_unit if chosen else None
    draw_component(ax, curves, component, unit, COMPONENTS[component])
    if chosen:
        ax.legend(*legend_entries(ax, curves), fontsize=8)
    return ax


def deformed(scene: Scene, path: LoadPath, ax=None, scale: float | None = None):
    """Draw the mechanism deformed at about five levels of ``path`` over its undeformed
    outline, with the tracing point's path; small motions are magnified by a round factor
    stated in the title (or by ``scale``).

    ``path`` must have been run with ``record_poses=True, record_shapes=True``.

    Returns
    -------
    matplotlib.axes.Axes

    Raises
    ------
    ValueError
        If the path holds no poses or shapes.
    """
    ax = _axes(ax, (7, 7))
    draw_deformed(ax, scene, path.load_case, path, scale)
    return ax
