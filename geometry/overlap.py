"""Impossible geometry: flexures that cross each other or whose band closes on itself.

Centre lines are sampled as polylines (``SAMPLES`` segments per flexure);
pairs whose bounding boxes overlap (found by a sweep, so the check scales
about linearly with the number of flexures) are tested for proper segment
crossings, vectorised over the pairs of their segments that lie in the
overlap of the two boxes, a crossing at a vertex included. Crossings within
``tol`` of a point where both flexures meet the same body (a shared
attachment), or where an end of each meets (two bars pinned end to end), are
allowed; so are crossings of flexures declared to lie in other layers of the
depth (``crosses``). Outlines are compared too (:func:`_check_outlines`). An arc (or a
spline) whose two ends come closer than its thickness h would have
overlapping end faces as a solid. :func:`self_crossings` finds where one
polyline crosses itself (a spline's centre line). Lengths mm.
"""

from __future__ import annotations

import numpy as np

from .errors import SceneError

SAMPLES = 256


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _segments_meeting(
    line: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Start and end points of the segments of ``line`` whose bounding boxes meet
    [lo, hi], in order."""
    a, b = line[:-1], line[1:]
    keep = np.all((np.maximum(a, b) >= lo) & (np.minimum(a, b) <= hi), axis=1)
    return a[keep], b[keep]


def crossings(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Intersection points (k, 2) of polylines p (m+1, 2) and q (n+1, 2), a crossing at a
    vertex of either included (parallel overlapping segments are left to the outline check).

    Only segments inside the overlap of the two polylines' bounding boxes can
    cross, so the all-pairs test runs on those (for neighbours that share an
    end, a few segments near it).
    """
    lo, hi = np.maximum(p.min(axis=0), q.min(axis=0)), np.minimum(p.max(axis=0), q.max(axis=0))
    if np.any(lo > hi):
        return np.empty((0, 2))
    (a, b), (c, d) = _segments_meeting(p, lo, hi), _segments_meeting(q, lo, hi)
    a, b, c, d = a[:, None, :], b[:, None, :], c[None, :, :], d[None, :, :]
    r, s = b - a, d - c
    den = _cross(r, s)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(c - a, s) / den
        u = _cross(c - a, r) / den
    hit = (den != 0) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)  # a vertex too
    return (a + t[..., None] * r)[hit]


SELF_CHUNK = 32
"""Segments per chunk in :func:`self_crossings` (chunks far apart are tested by their boxes)."""


def _chunk_crossings(line: np.ndarray) -> np.ndarray:
    """Proper crossings (k, 2) of the non-adjacent segments of one short polyline."""
    a, r = line[:-1], np.diff(line, axis=0)
    i, j = np.triu_indices(len(a), k=2)
    den = _cross(r[i], r[j])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(a[j] - a[i], r[j]) / den
        u = _cross(a[j] - a[i], r[i]) / den
    hit = (den != 0) & (t > 0) & (t < 1) & (u > 0) & (u < 1)
    return a[i][hit] + t[hit, None] * r[i][hit]


def self_crossings(line: np.ndarray) -> np.ndarray:
    """Points (k, 2) where a polyline (m + 1, 2) crosses itself (proper crossings, mm).

    Cut into chunks of :data:`SELF_CHUNK` segments: every two neighbouring
    chunks are tested together segment by segment, chunks farther apart by
    :func:`crossings` where their bounding boxes overlap.
    """
    line = np.asarray(line, float)
    m = len(line) - 1
    starts = list(range(0, m, SELF_CHUNK))
    chunks = [line[k : k + SELF_CHUNK + 1] for k in starts]
    found = [_chunk_crossings(line[k : min(k + 2 * SELF_CHUNK, m) + 1]) for k in starts]
    found += [crossings(chunks[i], chunks[j]) for i, j in candidate_pairs(chunks) if j - i >= 2]
    return np.concatenate([np.empty((0, 2)), *found])


def candidate_pairs(
    lines: list[np.ndarray], margins: list[float] | None = None
) -> list[tuple[int, int]]:
    """Index pairs (i < j) of polylines whose bounding boxes overlap, sorted (each box grown
    by its ``margins`` entry, mm: a band's half thickness, for outlines).

    Sweep and prune: boxes sorted by their lower x; each is compared only with
    the boxes that start before it ends in x, then filtered in y. Two
    polylines can cross only if their boxes overlap, so this prunes nothing
    that matters, and for mechanisms whose flexures are spread in the plane
    (chains, lattices) it costs about n log n instead of n^2.
    """
    grow = np.zeros(len(lines)) if margins is None else np.asarray(margins, float)
    lo = np.array([line.min(axis=0) for line in lines]).reshape(-1, 2) - grow[:, None]
    hi = np.array([line.max(axis=0) for line in lines]).reshape(-1, 2) + grow[:, None]
    order = np.argsort(lo[:, 0], kind="stable")
    lo, hi = lo[order], hi[order]
    pairs = []
    for k in range(len(order)):
        end = int(np.searchsorted(lo[:, 0], hi[k, 0], side="right"))
        others = np.arange(k + 1, end)
        others = others[(lo[others, 1] <= hi[k, 1]) & (hi[others, 1] >= lo[k, 1])]
        pairs += [tuple(sorted((int(order[k]), int(order[c])))) for c in others]
    return sorted(pairs)


def check_overlaps(flexures, source: str, tol: float) -> None:
    """Raise SceneError if two flexures cross or an arc's ends nearly touch."""
    lines = [f.shape.point(np.linspace(0.0, f.shape.length, SAMPLES + 1)) for f in flexures]
    for f in flexures:
        if f.shape.closes_on_itself(f.section.max_thickness):
            gap = float(np.hypot(*(f.shape.end_points[0] - f.shape.end_points[1])))
            arc = f.shape.kind == "arc"
            raise SceneError(
                source,
                f"flexures.{f.name}.{'width_deg' if arc else 'points'}",
                f.shape.width * 180 / np.pi if arc else f.shape.parameters()["points"],
                f"the {f.shape.kind}'s ends are {gap:.3g} mm apart, less than its "
                f"thickness {f.section.max_thickness:g} mm: the solid closes on itself",
            )
    widths = [  # each flexure's thickness at its centre line's samples (mm)
        np.broadcast_to(
            f.section.thickness_at(np.linspace(0.0, f.shape.length, SAMPLES + 1)), SAMPLES + 1
        )
        for f in flexures
    ]
    for i, j in candidate_pairs(lines, [0.5 * float(h.max()) for h in widths]):
        f, g = flexures[i], flexures[j]
        if g.name in f.crosses or f.name in g.crosses:  # declared: in other layers of the depth
            continue
        shared = [f.end_point_of(b) for b in f.bodies if b in g.bodies] + [
            g.end_point_of(b) for b in g.bodies if b in f.bodies
        ]
        joints = [  # where an end of each meets: their bands join in the body there
            p
            for p in f.shape.end_points
            if any(np.hypot(*(p - q)) <= tol for q in g.shape.end_points)
        ]
        touching = [*shared, *joints]  # a shared attachment, or two ends that meet
        for x in crossings(lines[i], lines[j]):
            if not any(np.hypot(*(x - s)) <= tol for s in touching):
                raise SceneError(
                    source,
                    f"flexures.{g.name}",
                    g.name,
                    f"crosses flexure {f.name!r} at ({x[0]:.3g}, {x[1]:.3g}) mm: "
                    "the mechanism intersects itself (if they lie in different layers of "
                    f"the depth, as a cross-axis pivot's leaves, say so: crosses = "
                    f"[{f.name!r}])",
                )
        _check_outlines(f, g, (lines[i], widths[i]), (lines[j], widths[j]), joints, source)


JOINT_SHARE = 0.25
"""Most of a flexure's length, from a body point it shares with another, within which
their bands may meet in the body (a quarter: two flexures that leave the point side by
side and stay so, one on top of the other, overlap beyond it)."""


def _check_outlines(f, g, band_f, band_g, shared: list[np.ndarray], source: str) -> None:
    """Refuse two flexures whose outlines (the bands +-h(s)/2 about their centre lines)
    overlap away from where they meet a body together.

    ``band_f`` and ``band_g`` are each one's centre-line samples (``SAMPLES`` + 1 points,
    mm) and its thickness there (mm). Two bands overlap where their centre lines come
    closer than the sum of their half thicknesses there, less a sample's spacing (a
    notch on top of another, two notches side by side closer than their blanks allow).
    Where both attach to one body point they join in that body, and their bands meet
    within the larger of their thicknesses divided by the sine of the
    angle between them there (up to :data:`JOINT_SHARE` of the shorter one's length) from
    the point; those stretches are left out.
    """
    (p_f, h_f), (p_g, h_g) = band_f, band_g  # centre-line samples and thickness there
    keep_f, keep_g = np.ones(len(p_f), bool), np.ones(len(p_g), bool)
    for point in shared:
        t_f = _tangent_at(f, point)
        t_g = _tangent_at(g, point)
        sine = abs(float(t_f[0] * t_g[1] - t_f[1] * t_g[0]))
        thickest = max(float(h_f.max()), float(h_g.max()))
        shortest = min(f.shape.length, g.shape.length)
        reach = min(thickest / max(sine, 1e-12), JOINT_SHARE * shortest)
        keep_f &= np.hypot(*(p_f - point).T) > reach
        keep_g &= np.hypot(*(p_g - point).T) > reach
    reach = 0.5 * (float(h_f.max()) + float(h_g.max()))  # only samples near the other's box
    keep_f &= np.all((p_f >= p_g.min(axis=0) - reach) & (p_f <= p_g.max(axis=0) + reach), axis=1)
    keep_g &= np.all((p_g >= p_f.min(axis=0) - reach) & (p_g <= p_f.max(axis=0) + reach), axis=1)
    if not (keep_f.any() and keep_g.any()):
        return
    a, b = p_f[keep_f], p_g[keep_g]
    gaps = np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])
    nearest = np.argmin(gaps, axis=1)
    distance = gaps[np.arange(len(a)), nearest]
    room = 0.5 * (h_f[keep_f] + h_g[keep_g][nearest])
    spacing = max(f.shape.length, g.shape.length) / SAMPLES  # a sample's reach
    overlap = distance < room - spacing
    if overlap.any():
        k = int(np.argmax(room - distance))
        x = p_f[keep_f][k]
        raise SceneError(
            source,
            f"flexures.{g.name}",
            g.name,
            f"its outline overlaps flexure {f.name!r}'s near ({x[0]:.3g}, {x[1]:.3g}) mm: "
            f"their centre lines are {distance[k]:.3g} mm apart there, their half "
            f"thicknesses add up to {room[k]:.3g} mm (the material would be counted twice)",
        )


def _tangent_at(flexure, point: np.ndarray) -> np.ndarray:
    """The unit tangent of a flexure's centre line at its end nearest ``point``."""
    start, end = flexure.shape.end_points
    s = 0.0 if np.hypot(*(point - start)) <= np.hypot(*(point - end)) else flexure.shape.length
    angle = float(flexure.shape.tangent_angle(s))
    return np.array([np.cos(angle), np.sin(angle)])
