"""The continuum reference's picture: the deformed mechanism, its flexures coloured by stress.

One figure of one state (Matplotlib, Agg):

* the whole mechanism deformed, at true scale: the rigid links at their poses
  (:func:`flexval.validation.report.drawing.draw_links`), the hatched ground, pins, the target
  point and the load (an arrow at its point, or a moment symbol round its body);
* the undeformed mechanism faint underneath (grey flexure outlines, dashed links);
* every flexure as its filled mesh at true thickness, coloured by a nodal stress (MPa):
  the signed Cauchy normal stress along the fibres (tension positive) or von Mises;
* beside it a zoom on the most stressed section, where the thin flexure can be read
  across its thickness, marked on the mechanism by a box;
* a colour scale clipped to a robust range (:func:`robust_range`): the largest stress
  outside the boundary layers at each clamped end face, where the continuum's stress is
  singular; where the end layers' values exceed it they saturate, and the colour bar's
  label and the caption say what the range leaves out and the largest value it holds.

Everything is computed from plain arrays of each flexure (:class:`FlexureField`: its
reference and current node positions, quad9 elements, centre-line nodes, nodal stresses
and which nodes lie outside the end layers), never from a flexure's shape parameters, so
any meshed flexure is drawn the same way. Units: mm, MPa, rad.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from ..outputs import use_file_backend

use_file_backend()
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.colors import Normalize  # noqa: E402
from matplotlib.patches import Polygon, Rectangle  # noqa: E402
from matplotlib.ticker import FormatStrFormatter  # noqa: E402
from matplotlib.tri import Triangulation  # noqa: E402

from flexval.geometry import LoadCase, Mechanism  # noqa: E402

from ..report.drawing import (  # noqa: E402
    FAINT_COLOUR,
    Poses,
    draw_ground,
    draw_links,
    draw_load,
    draw_pins,
    draw_target,
    link_points,
    load_label,
)
from .polar import nearest  # noqa: E402


@dataclass(frozen=True)
class Quantity:
    """A stress the flexures can be coloured by."""

    label: str
    """What it is, for the colour bar (unit MPa)."""
    symbol: str
    signed: bool
    """True: a symmetric range about zero (tension positive); False: from zero."""
    cmap: str


QUANTITIES = {
    "fibre_stress": Quantity(
        "fibre stress along the flexure (tension +)", r"$\sigma_{tt}$", True, "coolwarm"
    ),
    "von_mises": Quantity("von Mises stress", r"$\sigma_{vM}$", False, "viridis"),
}
"""The stresses a picture can show, by the key of :attr:`FlexureField.stress`."""

ROUND_OFF_STRAIN = 1e-9
"""A stress below this strain times Young's modulus is round-off: the smallest colour range."""


@dataclass(frozen=True)
class FlexureField:
    """One meshed flexure at one state, as plain arrays.

    Attributes
    ----------
    name : str
    reference : ndarray (n, 2)
        Undeformed node positions, mm.
    position : ndarray (n, 2)
        Current node positions, mm.
    elements : ndarray (m, 9)
        Quad9 connectivity (corners counterclockwise, mid-edge nodes, centre).
    centre_line : ndarray
        Nodes on the centre line, first end to second.
    stress : mapping of str to ndarray (n,)
        Nodal stresses, MPa, by the keys of :data:`QUANTITIES`.
    interior : ndarray (n,) of bool
        Nodes outside the boundary layers at the end faces.
    arc_fraction : ndarray (n,)
        Each node's arc-length fraction (0..1) from the first end.
    layer : float
        Width of each end layer along the centre line, mm.
    thickness : float
        The flexure's (smallest) in-plane thickness, mm.
    """

    name: str
    reference: np.ndarray
    position: np.ndarray
    elements: np.ndarray
    centre_line: np.ndarray
    stress: Mapping[str, np.ndarray]
    interior: np.ndarray
    arc_fraction: np.ndarray
    layer: float
    thickness: float


@dataclass(frozen=True)
class StressRange:
    """The colour range of a picture and where its peak is.

    Attributes
    ----------
    low, high : float
        Colour range, MPa (``-high .. high`` for a signed stress).
    peak : float
        Stress at the most stressed kept node (signed), MPa.
    flexure, node : int
        Index of that flexure (in the sequence given) and of the node in it.
    excluded_peak : float
        Largest magnitude among the nodes left out of the range, MPa (0 when none).
    by_percentile : bool
        True when no node lay outside the end layers and the range is a percentile of all
        nodes instead.
    percentile : float
        That percentile.
    """

    low: float
    high: float
    peak: float
    flexure: int
    node: int
    excluded_peak: float
    by_percentile: bool = False
    percentile: float = 99.0


def interior_nodes(
    nodes: np.ndarray,
    centre_line: np.ndarray,
    layer: float,
    along: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Nodes farther than ``layer`` (mm, along the centre line) from both end faces.

    A node's arc length is that of its section's centre-line node: ``along`` gives its
    position in ``centre_line`` (the mesh's logical coordinate along the flexure, as the
    reported peak fibre stress reads it, see
    :func:`flexval.validation.continuum.fibre.fibre_stress_peak`); without it, the nearest
    centre-line node's.

    Parameters
    ----------
    nodes : ndarray (n, 2)
        Undeformed node positions, mm.
    centre_line : ndarray
        Indices of the centre-line nodes, first end to second.
    layer : float
        Width of each end layer, mm.
    along : ndarray (n,), optional
        Each node's index into ``centre_line`` (whole numbers).

    Returns
    -------
    interior : ndarray (n,) of bool
    arc_fraction : ndarray (n,)
        Each node's arc-length fraction from the first end.
    """
    nodes = np.asarray(nodes, float)
    line = nodes[np.asarray(centre_line)]
    seg = np.hypot(*np.diff(line, axis=0).T)
    s_line = np.concatenate([[0.0], np.cumsum(seg)])
    length = float(s_line[-1])
    k = nearest(nodes, line) if along is None else np.rint(along).astype(np.int64)
    s = s_line[k]
    return (s >= layer) & (length - s >= layer), s / length


def robust_range(
    values: Sequence[np.ndarray],
    interior: Sequence[np.ndarray],
    signed: bool = True,
    percentile: float = 99.0,
    floor: float = 0.0,
) -> StressRange:
    """The colour range of nodal stresses that leaves out the end faces' boundary layers.

    The range reaches the largest magnitude among the ``interior`` nodes of all
    flexures (``-m .. m`` for a signed stress, ``0 .. m`` otherwise), so a clamped end
    face's singular corners do not wash out the rest; their values saturate the colours.
    When no node is interior (flexures shorter than their two end layers), the range is
    the ``percentile`` of all nodes' magnitudes instead.

    Parameters
    ----------
    values : sequence of ndarray (n_k,)
        Each flexure's nodal stress, MPa.
    interior : sequence of ndarray (n_k,) of bool
        Each flexure's nodes outside the end layers (see :func:`interior_nodes`).
    signed : bool
        A signed stress (the range is symmetric about zero).
    percentile : float
        The fallback percentile (0..100).
    floor : float
        The smallest range, MPa: a state without stress (round-off only) is drawn on
        ``floor`` (1 MPa when 0).

    Returns
    -------
    StressRange
    """
    mags = [np.abs(np.asarray(v, float)) if signed else np.asarray(v, float) for v in values]
    kept = [np.where(np.asarray(m_in, bool), m, -np.inf) for m, m_in in zip(mags, interior)]
    left = [np.where(np.asarray(m_in, bool), -np.inf, m) for m, m_in in zip(mags, interior)]
    excluded = max((float(x.max()) for x in left if x.size), default=-np.inf)
    best = [float(k.max()) if k.size else -np.inf for k in kept]
    by_percentile = not np.isfinite(max(best, default=-np.inf))
    if by_percentile:
        every = np.concatenate(mags)
        high = float(np.percentile(every, percentile))
        best = [float(m.max()) if m.size else -np.inf for m in mags]
        flexure = int(np.argmax(best))
        node = int(np.argmax(mags[flexure]))
        excluded = float(every[every > high].max()) if np.any(every > high) else 0.0
    else:
        flexure = int(np.argmax(best))
        node = int(np.argmax(kept[flexure]))
        high = best[flexure]
    if not high > floor:  # an unloaded state: round-off is not a stress
        high = floor if floor > 0.0 else 1.0
    return StressRange(
        low=-high if signed else 0.0,
        high=high,
        peak=float(np.asarray(values[flexure], float)[node]),
        flexure=flexure,
        node=node,
        excluded_peak=max(excluded, 0.0),
        by_percentile=by_percentile,
        percentile=percentile,
    )


# quad9 node order: corners 0-3 counterclockwise, mid-edge nodes 4 (0-1), 5 (1-2),
# 6 (2-3), 7 (3-0), centre 8
_SUB_TRIANGLES = np.array(
    [[0, 4, 8], [0, 8, 7], [4, 1, 5], [4, 5, 8], [8, 5, 2], [8, 2, 6], [7, 8, 6], [7, 6, 3]]
)
_EDGES = np.array([[0, 4, 1], [1, 5, 2], [2, 6, 3], [3, 7, 0]])


def quad9_triangles(elements: np.ndarray) -> np.ndarray:
    """Eight triangles (m * 8, 3) per quad9 element over its nine nodes (for Gouraud fills)."""
    return np.asarray(elements)[:, _SUB_TRIANGLES].reshape(-1, 3)


def boundary_loops(elements: np.ndarray) -> list[np.ndarray]:
    """The mesh's outline: closed node loops (corner and mid-edge nodes, in order).

    An element edge that no other element shares lies on the boundary; the elements
    are counterclockwise, so the edges chain head to tail.
    """
    edges = np.asarray(elements)[:, _EDGES].reshape(-1, 3)
    key = np.sort(edges[:, [0, 2]], axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    outer = edges[counts[inverse.ravel()] == 1]
    following = {int(a): (int(m), int(b)) for a, m, b in outer}
    loops = []
    while following:
        start = next(iter(following))
        loop, node = [start], start
        while True:
            mid, node = following.pop(node)
            loop += [mid, node]
            if node == start or node not in following:
                break
        loops.append(np.asarray(loop))
    return loops


def _draw_flexure(ax, field: FlexureField, values: np.ndarray, cmap, norm, outline_lw: float):
    """The filled, coloured mesh of one flexure at its current positions."""
    x = field.position
    tri = Triangulation(x[:, 0], x[:, 1], quad9_triangles(field.elements))
    art = ax.tripcolor(tri, values, shading="gouraud", cmap=cmap, norm=norm, zorder=4)
    if outline_lw > 0.0:
        for loop in boundary_loops(field.elements):
            ax.plot(x[loop, 0], x[loop, 1], color="0.1", lw=outline_lw, zorder=4.5)
    return art


def _draw_undeformed(ax, field: FlexureField) -> None:
    """The flexure's undeformed outline, faint."""
    for loop in boundary_loops(field.elements):
        ax.add_patch(
            Polygon(
                field.reference[loop],
                closed=True,
                fc=FAINT_COLOUR,
                ec=FAINT_COLOUR,
                lw=0.5,
                alpha=0.6,
                zorder=1,
            )
        )


def _layer_ticks(ax, field: FlexureField, lw: float) -> list[np.ndarray]:
    """Short bars across the deformed flexure where its end layers stop; their ends (mm)."""
    line = field.position[field.centre_line]
    ref_line = field.reference[field.centre_line]
    s_ref = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ref_line, axis=0).T))])
    ends = []
    for s in (field.layer, s_ref[-1] - field.layer):
        if not 0.0 < s < s_ref[-1]:
            continue
        k = int(np.clip(np.searchsorted(s_ref, s), 1, len(s_ref) - 1))
        w = (s - s_ref[k - 1]) / (s_ref[k] - s_ref[k - 1])
        p = (1 - w) * line[k - 1] + w * line[k]
        t = line[k] - line[k - 1]
        t /= np.hypot(*t)
        half = (1 - w) * _half_width(field, k - 1) + w * _half_width(field, k)
        n = np.array([-t[1], t[0]]) * (half + 0.5 * field.thickness)
        ax.plot(*np.array([p - n, p + n]).T, color="k", lw=lw, zorder=5, solid_capstyle="butt")
        ends.append(p + n)
    return ends


def _half_width(field: FlexureField, k: int) -> float:
    """Half the flexure's width (mm, undeformed) at its ``k``-th centre-line node: the
    farthest node of the same arc length."""
    centre = field.centre_line[k]
    section = field.arc_fraction == field.arc_fraction[centre]
    return float(np.max(np.hypot(*(field.reference[section] - field.reference[centre]).T)))


def _element_edges(ax, field: FlexureField, lo: np.ndarray, hi: np.ndarray) -> None:
    """The element edges (light) of the elements with a node inside the box lo..hi (mm)."""
    x = field.position
    near = np.all((x >= lo) & (x <= hi), axis=1)[field.elements].any(axis=1)
    loops = x[field.elements[near][:, [0, 4, 1, 5, 2, 6, 3, 7, 0]]]
    ax.add_collection(LineCollection(loops, colors="k", linewidths=0.3, alpha=0.35, zorder=4.6))


def _bounds(points: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    pts = np.vstack([np.atleast_2d(p) for p in points])
    return pts.min(axis=0), pts.max(axis=0)


def continuum_figure(
    mechanism: Mechanism,
    case: LoadCase,
    fields: Sequence[FlexureField],
    poses: Poses,
    title: str = "",
    quantity: str = "fibre_stress",
    load_factor: float = 1.0,
):
    """The picture of the deformed mechanism with its flexures coloured by stress.

    Parameters
    ----------
    mechanism : Mechanism
    case : LoadCase
        The load drawn (its full value, times ``load_factor``)
    fields : sequence of FlexureField
        Every meshed flexure at the state drawn (mm, MPa).
    poses : mapping
        Each body's pose (x mm, y mm, theta rad) at that state.
    title : str
    quantity : {'fibre_stress', 'von_mises'}
        The stress the flexures are coloured by (MPa).
    load_factor : float
        The load factor of the state drawn (1: full load), for the captions.

    Returns
    -------
    matplotlib.figure.Figure
        The mechanism on the left, the zoom on its most stressed section on the right
        above the colour bar, a caption underneath.
    """
    q = QUANTITIES[quantity]
    values = [f.stress[quantity] for f in fields]
    rng = robust_range(
        values,
        [f.interior for f in fields],
        signed=q.signed,
        floor=ROUND_OFF_STRAIN * mechanism.material.youngs_modulus,
    )
    cmap = plt.get_cmap(q.cmap)
    norm = Normalize(rng.low, rng.high)
    peak_field = fields[rng.flexure]
    peak_at = peak_field.position[rng.node]

    fig = plt.figure(figsize=(13.0, 7.8))
    ax = fig.add_axes((0.055, 0.2, 0.56, 0.7))
    zoom = fig.add_axes((0.665, 0.40, 0.31, 0.50))
    cax = fig.add_axes((0.675, 0.285, 0.29, 0.025))

    # the undeformed mechanism, faint, then the deformed one
    for f in fields:
        _draw_undeformed(ax, f)
    draw_links(ax, mechanism, faint=True, zorder=1.5)
    ground = draw_ground(ax, mechanism)
    mappable = None
    for f, v in zip(fields, values):
        mappable = _draw_flexure(ax, f, v, cmap, norm, outline_lw=0.2)
        _layer_ticks(ax, f, lw=0.8)
    draw_links(ax, mechanism, poses)
    draw_pins(ax, mechanism, poses)
    draw_target(ax, mechanism, poses)
    reach = draw_load(ax, mechanism, case, poses, colour="darkorange", values=True)
    for f in fields:
        mid = np.argmin(np.abs(f.arc_fraction[f.centre_line] - 0.5))
        ax.annotate(
            f.name,
            f.position[f.centre_line[mid]],
            xytext=(5, 5),
            textcoords="offset points",
            color="tab:blue",
            fontsize=10,
            weight="bold",
            zorder=8,
        )
    lo, hi = _bounds(
        [f.reference for f in fields]
        + [f.position for f in fields]
        + [link_points(mechanism, b) for b in mechanism.bodies]
        + [link_points(mechanism, b, poses) for b in mechanism.bodies]
        + reach
        + ground
    )
    pad = 0.06 * float(np.max(hi - lo))
    ax.update_datalim([lo - [pad, 1.6 * pad], hi + pad])
    ax.margins(0.0)
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.grid(alpha=0.25)
    at = "full load" if load_factor == 1.0 else f"load factor {load_factor:g}"
    ax.set_title(f"deformed at {at}, true scale (undeformed in grey)", fontsize=11)

    # the zoom on the most stressed section
    half = min(4.0 * peak_field.thickness, 0.25 * float(np.max(hi - lo)))
    window = (peak_at - half, peak_at + half)
    draw_ground(zoom, mechanism, label=False)
    for f, v in zip(fields, values):
        _draw_flexure(zoom, f, v, cmap, norm, outline_lw=1.0)
        _element_edges(zoom, f, window[0] - half, window[1] + half)
        for end in _layer_ticks(zoom, f, lw=1.5):
            if np.all((end > window[0]) & (end < window[1])):
                zoom.annotate(
                    f"end layer of {f.name}\n({f.layer:g} mm) stops here",
                    end,
                    xytext=(4, 2),
                    textcoords="offset points",
                    fontsize=8,
                    zorder=9,
                    bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="none", alpha=0.8),
                )
    draw_links(zoom, mechanism, poses, labels=False)
    zoom.plot(*peak_at, marker="o", ms=11, mfc="none", mec="k", mew=1.8, zorder=9)
    zoom.set_xlim(window[0][0], window[1][0])
    zoom.set_ylim(window[0][1], window[1][1])
    zoom.set_aspect("equal", adjustable="box")
    zoom.tick_params(labelsize=8)
    zoom.grid(alpha=0.25)
    where = f"{peak_field.name}, {100 * peak_field.arc_fraction[rng.node]:.0f} % of its length"
    zoom.set_title(
        f"zoom on the most stressed section ({where})\n"
        f"peak {q.symbol} = {rng.peak:.4g} MPa (circled), "
        f"thickness {peak_field.thickness:g} mm",
        fontsize=10,
    )
    ax.add_patch(Rectangle(window[0], 2 * half, 2 * half, fill=False, ec="k", lw=1.2, zorder=10))
    rightwards = peak_at[0] < 0.5 * (lo[0] + hi[0])  # the label runs towards the centre
    ax.annotate(
        f"zoom: peak {q.symbol} {rng.peak:.3g} MPa",
        window[0] + [0.0 if rightwards else 2 * half, 0.0],
        xytext=(0, -4),
        textcoords="offset points",
        fontsize=8.5,
        ha="left" if rightwards else "right",
        va="top",
        zorder=10,
        bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="none", alpha=0.8),
    )

    # the colour scale and what it leaves out
    magnitude = "|" + q.symbol + "|" if q.signed else q.symbol
    span = f"\u00b1{rng.high:.3g}" if q.signed else f"0 .. {rng.high:.3g}"
    if rng.high <= ROUND_OFF_STRAIN * mechanism.material.youngs_modulus:
        rule = f"range {span} MPa: no stress above round-off"
        left_out = f"largest {magnitude} {max(abs(rng.peak), rng.excluded_peak):.3g} MPa"
    elif rng.by_percentile:
        rule = f"range {span} MPa: the {rng.percentile:g}th percentile\nof {magnitude} at all nodes"
        left_out = f"excluded: the nodes above it (up to {rng.excluded_peak:.3g} MPa)"
    else:
        ratios = sorted({round(f.layer / f.thickness, 6) for f in fields})
        n_t = " or ".join(f"{r:g}" for r in ratios)
        rule = f"range {span} MPa: largest {magnitude} beyond {n_t} thicknesses\nof each end face"
        left_out = (
            "excluded: the end layers (singular clamp corners),\n"
            f"which reach {rng.excluded_peak:.3g} MPa"
        )
    cb = fig.colorbar(
        mappable,
        cax=cax,
        orientation="horizontal",
        extend="both" if q.signed else "max",
    )
    cb.set_label(f"{q.label}, {q.symbol} (MPa)\n{rule}; {left_out}", fontsize=9.5)
    cb.ax.tick_params(labelsize=8)
    cb.ax.xaxis.set_major_formatter(FormatStrFormatter("%.3g"))

    lines = [
        f"Flexures at true thickness, coloured by the nodal {q.label} "
        "(MPa, recovered at the nodes from the quadrature points); grey: the undeformed mechanism; "
        "the box marks the zoom on the right.",
        "Black ticks across each flexure: the ends of the boundary layers at its end faces "
        + ", ".join(f"({f.name}: {f.layer:g} mm)" for f in fields)
        + (
            f"; their stress stays inside the range (up to {rng.excluded_peak:.3g} MPa)."
            if rng.excluded_peak <= rng.high
            else f"; their stress, up to {rng.excluded_peak:.3g} MPa, saturates the colours."
        ),
        f"Load {', '.join(load_label(case, c) for c in case.components)} "
        + ("at full value " if load_factor == 1.0 else f"times the load factor {load_factor:g} ")
        + "(dead load: it keeps its direction and moves with its point).",
    ]
    fig.text(0.055, 0.025, "\n".join(lines), fontsize=9, va="bottom", ha="left", wrap=True)
    fig.suptitle(
        f"{title or case.name}: stress in the deformed mechanism", fontsize=13, weight="bold"
    )
    return fig
