"""Pictures of a mechanism: the undeformed outline (paper Figs. 6 and 12 in outline, each
flexure at its true thickness: :func:`flexure_outline`) and the
pieces every mechanism picture shares: rigid links (at any poses), the hatched ground, pins,
the target point and the loads.

Matplotlib with the non-interactive Agg backend; lengths in mm, poses (x mm, y mm, theta rad).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from ..outputs import use_file_backend

use_file_backend()
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402

from flexval.geometry import Force, LoadCase, Mechanism, Moment, Scene  # noqa: E402
from flexval.geometry.kinematics import place_points  # noqa: E402

from ..outputs import save_figure  # noqa: E402

Poses = Mapping[str, np.ndarray]
"""Pose (x mm, y mm, theta rad) of each body, by name; a body left out stays undeformed."""

LINK_COLOUR = "0.15"
FAINT_COLOUR = "0.72"
GROUND_COLOUR = "0.3"


def link_points(mech: Mechanism, body: str, poses: Poses | None = None) -> np.ndarray:
    """The attachment points of ``body`` (and the target point, on the target body), mm,
    carried to the body's pose in ``poses`` (undeformed when ``poses`` is None or lacks it)."""
    b = mech.bodies[body]
    pts = np.asarray(b.points, float)
    if body == mech.target_body:
        pts = np.vstack([pts, mech.target_point])
    pose = None if poses is None else poses.get(body)
    if pose is None:
        return pts
    return place_points(np.asarray(pose, float), pts - b.reference)


def _label_point(pts: np.ndarray) -> np.ndarray:
    """Where a link's name goes: its centroid, or its middle for two points."""
    return pts.mean(axis=0)


def draw_links(
    ax,
    mech: Mechanism,
    poses: Poses | None = None,
    *,
    faint: bool = False,
    labels: bool = True,
    zorder: float = 3.0,
) -> None:
    """Draw every moving rigid link as the polygon of its attachment points (mm).

    Parameters
    ----------
    ax : matplotlib Axes
    mech : Mechanism
    poses : mapping, optional
        Body poses (x mm, y mm, theta rad); None: the undeformed mechanism.
    faint : bool
        Light grey, thin and unlabelled: an undeformed outline under a deformed picture.
    labels : bool
        Write each body's name in a circle at its centroid.
    zorder : float
    """
    colour = FAINT_COLOUR if faint else LINK_COLOUR
    for name, b in mech.bodies.items():
        if b.is_ground:
            continue
        pts = link_points(mech, name, poses)
        if len(pts) >= 3:
            ax.fill(
                pts[:, 0],
                pts[:, 1],
                color=colour,
                alpha=0.15 if faint else 0.3,
                lw=0,
                zorder=zorder - 0.1,
            )
            closed = np.vstack([pts, pts[:1]])
        else:
            closed = pts
        ax.plot(
            closed[:, 0],
            closed[:, 1],
            color=colour,
            lw=2.5 if faint else 5,
            solid_capstyle="round",
            alpha=0.9 if faint else 0.8,
            zorder=zorder,
            ls="--" if faint else "-",
        )
        if labels and not faint:
            _body_label(ax, name, _label_point(pts), zorder + 1)


def _body_label(ax, name: str, at: np.ndarray, zorder: float) -> None:
    ax.annotate(
        name,
        at,
        fontsize=11,
        weight="bold",
        color="darkred",
        ha="center",
        va="center",
        bbox=dict(
            boxstyle="circle,pad=0.2" if len(name) <= 2 else "round,pad=0.25",
            fc="white",
            ec="darkred",
        ),
        zorder=zorder,
    )


def _clamp_size(mech: Mechanism, end_thickness: float = 0.0) -> tuple[float, float]:
    """Width across and depth behind (mm) of the hatched ground block at a clamped end face
    ``end_thickness`` mm wide: wider than the face, a small fraction of the mechanism deep."""
    size = mech.size()
    width = max(1.6 * end_thickness, 0.06 * size)
    return width, min(0.5 * width, 0.08 * size)


def draw_ground(
    ax, mech: Mechanism, *, label: bool = True, zorder: float = 2.0
) -> list[np.ndarray]:
    """Draw the ground: a hatched block behind each end face a flexure is clamped to (its
    wall across the flexure's end tangent), a hatched support under each grounded pin.

    Parameters
    ----------
    ax : matplotlib Axes
    mech : Mechanism
    label : bool
        Write the ground body's name under it.
    zorder : float

    Returns
    -------
    list of ndarray
        Points (mm) the ground's symbols reach, for setting the axes' limits.
    """
    corners = []
    for f in mech.flexures:
        if mech.ground not in f.bodies:
            continue
        at_start = f.start_body == mech.ground
        s = 0.0 if at_start else f.shape.length
        w, depth = _clamp_size(mech, float(np.max(f.section.thickness_at(s))))
        p = np.asarray(f.shape.point(s), float)
        t = np.asarray(f.shape.tangent(s), float)
        t = t if at_start else -t  # into the flexure
        n = np.array([-t[1], t[0]])
        block = np.array(
            [
                p + 0.5 * w * n,
                p - 0.5 * w * n,
                p - 0.5 * w * n - depth * t,
                p + 0.5 * w * n - depth * t,
            ]
        )
        corners.append(block)
    for pin in mech.pins:
        if mech.ground not in pin.bodies:
            continue
        p = np.asarray(pin.point, float)
        w, depth = _clamp_size(mech)
        # a support below the pin: a triangle standing on a hatched block
        tri = np.array([p, p + [-0.4 * w, -0.6 * w], p + [0.4 * w, -0.6 * w]])
        ax.add_patch(Polygon(tri, closed=True, fc="white", ec=GROUND_COLOUR, lw=1.5, zorder=zorder))
        base = p + [0.0, -0.6 * w]
        corners.append(
            np.array(
                [
                    base + [-0.5 * w, 0.0],
                    base + [0.5 * w, 0.0],
                    base + [0.5 * w, -depth],
                    base + [-0.5 * w, -depth],
                ]
            )
        )
    for block in corners:
        ax.add_patch(
            Polygon(
                block,
                closed=True,
                fc="white",
                ec=GROUND_COLOUR,
                hatch="////",
                lw=0.8,
                zorder=zorder,
            )
        )
        ax.plot(*block[:2].T, color=GROUND_COLOUR, lw=2.5, zorder=zorder + 0.1)
    if label and corners:
        ground_pts = np.vstack(corners)
        centre = ground_pts.mean(axis=0)
        below = np.array([centre[0], ground_pts[:, 1].min() - 0.04 * mech.size()])
        _body_label(ax, mech.ground, below, zorder + 1)
        corners.append(below - [0.0, 0.03 * mech.size()])
    return corners


def draw_pins(ax, mech: Mechanism, poses: Poses | None = None, *, zorder: float = 4.0) -> None:
    """Draw each pin as an open circle at its position (carried by its first body's pose)."""
    for pin in mech.pins:
        body = pin.bodies[0] if pin.bodies[0] != mech.ground else pin.bodies[1]
        p = np.asarray(pin.point, float)
        pose = None if poses is None else poses.get(body)
        if pose is not None:
            p = place_points(np.asarray(pose, float), (p - mech.bodies[body].reference)[None])[0]
        ax.plot(*p, marker="o", ms=9, mfc="white", mec=LINK_COLOUR, mew=2, zorder=zorder)


def draw_target(ax, mech: Mechanism, poses: Poses | None = None, *, zorder: float = 6.0) -> None:
    """Mark the target (tracing) point with a star, at the target body's pose."""
    p = link_points(mech, mech.target_body, poses)[-1]
    ax.plot(*p, marker="*", ms=14, color="gold", mec="k", zorder=zorder)
    ax.annotate("target", p, xytext=(6, 6), textcoords="offset points", fontsize=9, zorder=zorder)


def load_label(case: LoadCase, component) -> str:
    """``name: value unit`` of one load of a case (N for a force, N mm for a moment)."""
    unit = "N" if isinstance(component, Force) else "N mm"
    sense = ""
    if isinstance(component, Moment):
        sense = " ccw" if component.value > 0 else " cw"
    return f"{case.name}: {abs(component.value):.3g} {unit}{sense}"


def _alignment(direction: np.ndarray) -> tuple[str, str]:
    """Text alignment (ha, va) of a label set off from its point along ``direction``."""
    dx, dy = direction
    ha = "center" if abs(dx) < 0.3 * abs(dy) else "left" if dx > 0 else "right"
    va = "center" if abs(dy) < 0.3 * abs(dx) else "bottom" if dy > 0 else "top"
    return ha, va


def draw_load(
    ax,
    mech: Mechanism,
    case: LoadCase,
    poses: Poses | None = None,
    *,
    colour: str = "tab:orange",
    values: bool = False,
    offset: int = 0,
    zorder: float = 7.0,
) -> list[np.ndarray]:
    """Draw the loads of ``case``: an arrow from each force's point along the force, a
    curved arrow round the loaded body for each moment (sense counterclockwise positive).

    Parameters
    ----------
    ax : matplotlib Axes
    mech : Mechanism
    case : LoadCase
    poses : mapping, optional
        Body poses (x mm, y mm, theta rad): the loaded points move with their bodies, a
        force keeps its direction (dead load). None: undeformed.
    colour : str
    values : bool
        Label each load with its full value and unit, else with the case name.
    offset : int
        Index of the case among several drawn on one picture (staggers moment labels).
    zorder : float

    Returns
    -------
    list of ndarray
        Points (mm) the loads' symbols reach, for setting the axes' limits.
    """
    size = mech.size()
    reach = []
    for c in case.components:
        text = load_label(case, c) if values else case.name
        if isinstance(c, Force):
            b = mech.bodies[c.body]
            p = np.asarray(c.point, float)
            pose = None if poses is None else poses.get(c.body)
            if pose is not None:
                p = place_points(np.asarray(pose, float), (p - b.reference)[None])[0]
            d = np.sign(c.value) * np.array([np.cos(c.angle), np.sin(c.angle)]) * 0.12 * size
            ax.annotate(
                "",
                xy=p + d,
                xytext=p,
                arrowprops=dict(
                    arrowstyle="-|>,head_width=0.4,head_length=0.8", color=colour, lw=2.5
                ),
                zorder=zorder,
            )
            side = np.array([-d[1], d[0]]) / np.hypot(*d)  # the label beside the arrow,
            if np.dot(side, p + 0.5 * d - _label_point(link_points(mech, c.body, poses))) < 0:
                side = -side  # on the side away from its body
            ha, va = _alignment(side)
            ax.annotate(
                text,
                p + 0.5 * d,
                xytext=tuple(7 * side),
                textcoords="offset points",
                ha=ha,
                va=va,
                color=colour,
                fontsize=9,
                weight="bold" if values else "normal",
                zorder=zorder,
            )
            # where the label may reach: about 0.012 size per character at the usual scales
            width = np.array([{"left": 1.0, "right": -1.0}.get(ha, 0.5), 0.0])
            label_end = p + 0.5 * d + size * (0.03 * side + 0.012 * len(text) * width)
            reach += [p, p + 1.15 * d, label_end]
        elif isinstance(c, Moment):
            centre = _label_point(link_points(mech, c.body, poses))
            r = 0.05 * size
            sense = 1.0 if c.value > 0 else -1.0
            phi = np.radians(np.linspace(-120.0, 150.0, 60)) * sense + np.pi / 2
            arc = centre + r * np.column_stack([np.cos(phi), np.sin(phi)])
            ax.plot(arc[:-1, 0], arc[:-1, 1], color=colour, lw=2.2, zorder=zorder)
            ax.annotate(
                "",
                xy=arc[-1],
                xytext=arc[-4],
                arrowprops=dict(
                    arrowstyle="-|>,head_width=0.4,head_length=0.8", color=colour, lw=2.2
                ),
                zorder=zorder,
            )
            ax.annotate(
                text,
                centre - [0.0, r],
                xytext=(0, -14 - 12 * offset),
                textcoords="offset points",
                color=colour,
                fontsize=9,
                ha="center",
                va="top",
                weight="bold" if values else "normal",
                zorder=zorder,
            )
            reach += [centre - r, centre + r]
    return reach


OUTLINE_SAMPLES = 400
"""Points along each side of a flexure's drawn outline (more near a notch's ends and middle)."""


def flexure_outline(flexure) -> np.ndarray:
    """The flexure's solid outline as a closed polygon (m, 2), mm.

    The centre line offset by +-h(s)/2 along its normal, with the true
    thickness h(s) of a taper or a notch; samples cluster where a notch's
    contour turns fastest (its ends and, for some contours, its middle) by a
    cosine spacing between the profile's breakpoints.
    """
    shape, section = flexure.shape, flexure.section
    length = shape.length
    breaks = () if section.profile is None else section.profile.breakpoints
    cuts = [0.0, *sorted(b for b in {*breaks, 0.5 * length} if 0.0 < b < length), length]
    per = max(8, OUTLINE_SAMPLES // (len(cuts) - 1))
    u = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, per)))
    s = np.unique(np.concatenate([a + (b - a) * u for a, b in zip(cuts[:-1], cuts[1:])]))
    centre = shape.point(s)
    tangent = shape.tangent(s)
    half = 0.5 * section.thickness_at(s)[:, None] * np.column_stack([-tangent[:, 1], tangent[:, 0]])
    return np.concatenate([centre + half, (centre - half)[::-1]])


def draw_mechanism(scene: Scene, ax=None, load_case: str | None = None):
    """Draw flexures, rigid links, the ground, body labels, target point and load arrows on
    ``ax`` (the undeformed mechanism; lengths in mm)."""
    mech = scene.mechanism
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    for f in mech.flexures:
        s = np.linspace(0.0, f.shape.length, 200)
        p = f.shape.point(s)
        ax.add_patch(
            Polygon(flexure_outline(f), closed=True, facecolor="tab:blue", alpha=0.35, lw=0)
        )
        ax.plot(p[:, 0], p[:, 1], color="tab:blue", lw=1)
        mid = f.shape.point(0.5 * f.shape.length)
        ax.annotate(f.name, mid, color="tab:blue", fontsize=9, ha="center", va="bottom")
    for p in draw_ground(ax, mech):
        ax.plot(*np.atleast_2d(p).T, alpha=0.0)  # keep the ground inside the axes
    draw_links(ax, mech)
    draw_pins(ax, mech)
    draw_target(ax, mech)
    cases = [scene.load_case(load_case)] if load_case else scene.load_cases
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"][1:]
    for k, lc in enumerate(cases):
        for p in draw_load(ax, mech, lc, colour=colors[k % len(colors)], offset=k):
            ax.plot(*p, alpha=0.0)  # keep the symbols inside the axes
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"{scene.name}: undeformed mechanism")
    ax.grid(alpha=0.3)
    return ax


def plot_mechanism(scene: Scene, path: str | Path) -> None:
    """Write the undeformed mechanism picture to ``path`` (PNG)."""
    fig, ax = plt.subplots(figsize=(7, 7))
    draw_mechanism(scene, ax)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)
