"""Reading a ``[[flexures]]`` entry's thickness law, notch hinge or spline centre line.

The parser of :mod:`flexval.geometry.scene` reads the arc and segment fields
itself and hands these readers the rest (fields declared in
:data:`flexval.geometry.scenefields.FLEXURES`):

- ``thickness = h`` or ``thickness = [h_start, h_end]``: a uniform section or
  a linear taper in arc length from the centre line's first end
  (:class:`flexval.geometry.profiles.LinearTaper`);
- ``shape = "notch"``: a straight axis ``start`` -> ``end`` with a
  :class:`flexval.geometry.profiles.NotchProfile` (``contour``, smallest
  thickness ``thickness`` = t, ``height`` = H, ``fillet_radius``, ``exponent``);
- ``shape = "spline"``: :class:`flexval.geometry.shapes.Spline` through ``points``.

Every refusal is a :class:`SceneError` naming the field and the value. The
reader ``rd`` is the scene parser's (``value``, ``number``, ``point``,
``fail``). Units: mm.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from .mechanism import Section
from .overlap import self_crossings
from .profiles import FLAT_ROUND_OFF, SEMICIRCLE_ROUND_OFF, LinearTaper, NotchProfile
from .scenefields import FLEXURES
from .shapes import Segment, Shape, Spline, largest_along

SPLINE_SAMPLES = 32
"""Polyline segments per spline interval for the self-crossing and thickness checks."""

REPEATED_POINT = 1e-9
"""Spline points closer than this fraction of the points' extent are the same point."""

FILLET_HEIGHT_TOLERANCE = 1e-9

MAX_TAPER_RATIO = 1e4
"""Largest ratio of a taper's end thicknesses: EI spans its cube, 10^12. A moment on a
column tapered 10^4 : 1 from its clamp turns it within 4e-5 of M int ds / EI (ee); at
10^5 : 1, 2e-3 (tests/test_hostile_surfaces.py): the mechanism's stiffnesses then lie
further apart than its linear solves resolve."""
"""A corner-filleted notch's given H may differ from t + 2 r by this fraction (rounding)."""


def read_thickness(rd, f: dict, where: str, default: float) -> float | tuple[float, float]:
    """``thickness``: a number (mm) or a taper's two end thicknesses (mm)."""
    field = FLEXURES["thickness"]
    value = f.get("thickness")
    if isinstance(value, list):
        if len(value) != 2:
            rd.fail(f"{where}thickness", value, "must be a number or [h_start, h_end] in mm")
        ends = tuple(
            rd.number({f"thickness[{i}]": h}, f"thickness[{i}]", where) for i, h in enumerate(value)
        )
        if min(ends) <= 0.0:
            rd.fail(
                f"{where}thickness",
                value,
                "a taper's end thicknesses must both be positive (it would taper to zero "
                "or a negative thickness)",
            )
        if max(ends) > MAX_TAPER_RATIO * min(ends):
            rd.fail(
                f"{where}thickness",
                value,
                f"a taper's ends may differ by a factor of at most {MAX_TAPER_RATIO:g} (its "
                "stiffness EI by the cube of it): a steeper one puts stiffnesses more than "
                "10^12 apart into one mechanism, beyond what its linear solves resolve",
            )
        return ends
    return rd.value(f, dataclasses.replace(field, kind="number"), where, default=default)


def section_of(depth: float, thickness: float | tuple[float, float], shape: Shape) -> Section:
    """The section of a uniform thickness or of a taper [h_start, h_end] along ``shape`` (mm).

    A taper with equal ends is a uniform section.
    """
    if not isinstance(thickness, tuple):
        return Section(depth, thickness)
    start, end = thickness
    if start == end:
        return Section(depth, start)
    return Section(depth, min(start, end), LinearTaper(start, end, shape.length))


def check_thickness_fits(rd, where: str, value: Any, shape: Shape, section: Section) -> None:
    """Refuse a thickness of at least twice the radius of curvature somewhere (no inner edge).

    An arc's radius is constant (h < 2 r, the largest thickness of a taper);
    a spline's curvature is sampled along it.
    """
    if shape.kind == "arc":
        if section.max_thickness >= 2.0 * shape.radius:
            rd.fail(
                f"{where}thickness",
                value,
                f"thickness h must be smaller than 2 r = {2 * shape.radius:g} mm",
            )
        return
    if shape.kind != "spline":
        return
    at, excess = largest_along(
        lambda s: section.thickness_at(s) * np.abs(shape.curvature_at(s)),
        shape.length,
        SPLINE_SAMPLES * (len(shape.points) - 1),
    )
    if excess >= 2.0:
        radius = 1.0 / abs(float(shape.curvature_at(at)))
        rd.fail(
            f"{where}thickness",
            value,
            f"{at:.4g} mm along the spline its radius of curvature is {radius:.4g} mm: a "
            f"thickness of {float(section.thickness_at(at)):.4g} mm, at least twice it, "
            "has no inner edge",
        )


def closest_pair(points: np.ndarray) -> tuple[int, int, float]:
    """The two closest of ``points`` (n, 2), i < j, and their distance (mm): each point's
    nearest other by a k-d tree, O(n log n) time and O(n) memory (a spline may have tens of
    thousands of points)."""
    from scipy.spatial import cKDTree

    distances, neighbours = cKDTree(points).query(points, k=2)
    own = np.arange(len(points))
    other = np.where(neighbours[:, 0] == own, neighbours[:, 1], neighbours[:, 0])  # a twin
    gap = np.where(neighbours[:, 0] == own, distances[:, 1], distances[:, 0])  # may come first
    k = int(np.argmin(gap))
    i, j = sorted((k, int(other[k])))
    return i, j, float(gap[k])


def read_spline(rd, f: dict, where: str) -> Spline:
    """``points``: at least three different points (mm) whose spline does not cross itself."""
    value = f.get("points")
    if not isinstance(value, list) or len(value) < 3:
        rd.fail(
            f"{where}points",
            value,
            "a spline needs at least 3 points [x, y] in mm (the curve passes through them)",
        )
    points = np.array(
        [rd.point({f"points[{i}]": p}, f"points[{i}]", where) for i, p in enumerate(value)]
    )
    extent = float(np.hypot(*(points.max(axis=0) - points.min(axis=0))))
    i, j, gap = closest_pair(points)
    if gap <= REPEATED_POINT * extent:
        rd.fail(
            f"{where}points[{j}]",
            value[j],
            f"repeats point {i} of the spline: its points must all be different",
        )
    try:
        spline = Spline(tuple(map(tuple, points.tolist())))
        line = spline.point(np.linspace(0.0, spline.length, SPLINE_SAMPLES * (len(points) - 1) + 1))
    except ValueError as exc:
        rd.fail(f"{where}points", value, str(exc))
    crossing = self_crossings(line)
    if len(crossing):
        x, y = crossing[0]
        rd.fail(
            f"{where}points",
            value,
            f"the spline through these points crosses itself at ({x:.4g}, {y:.4g}) mm",
        )
    return spline


def read_notch(rd, f: dict, where: str, depth: float, default_t: float) -> tuple[Segment, Section]:
    """A notch hinge's axis and section from ``start``, ``end``, ``contour``, ``thickness``,
    ``height``, ``fillet_radius`` and ``exponent`` (mm)."""
    a, b = rd.value(f, FLEXURES["start"], where), rd.value(f, FLEXURES["end"], where)
    length = float(np.hypot(*(b - a)))
    if length <= 0.0:
        rd.fail(f"{where}end", list(b), "the notch's axis has zero length")
    contour = rd.value(f, FLEXURES["contour"], where)
    if isinstance(f.get("thickness"), list):
        rd.fail(
            f"{where}thickness",
            f["thickness"],
            "a notch's thickness is its smallest thickness t, at its middle: a number",
        )
    t = read_thickness(rd, f, where, default_t)
    height = rd.value(f, FLEXURES["height"], where)
    radius = rd.value(f, FLEXURES["fillet_radius"], where)
    exponent = rd.value(f, FLEXURES["exponent"], where)
    if contour == "corner-filleted":
        if radius is None:
            rd.fail(
                f"{where}fillet_radius", None, "a corner-filleted notch needs its fillet radius"
            )
        if radius > 0.5 * length * (1.0 + FLAT_ROUND_OFF):  # fillets meeting, to round-off
            rd.fail(
                f"{where}fillet_radius",
                radius,
                f"must be at most half the notch's length, L/2 = {0.5 * length:g} mm",
            )
        filleted = t + 2.0 * radius
        if height is not None and abs(height - filleted) > FILLET_HEIGHT_TOLERANCE * filleted:
            rd.fail(
                f"{where}height",
                height,
                f"a corner-filleted notch has H = t + 2 r = {filleted:g} mm (leave it out)",
            )
        height = filleted
    elif radius is not None:
        rd.fail(f"{where}fillet_radius", radius, f"a {contour} notch has no fillet radius")
    if contour == "power" and exponent is None:
        rd.fail(f"{where}exponent", None, "a power notch needs its exponent n")
    if contour != "power" and exponent is not None:
        rd.fail(f"{where}exponent", exponent, f"a {contour} notch has no exponent")
    if height is None:
        rd.fail(f"{where}height", None, "missing value: the notch's thickness H at its ends")
    if t >= height:
        rd.fail(
            f"{where}height",
            height,
            f"must be larger than the notch's smallest thickness t = {t:g} mm",
        )
    if contour == "circular" and height > (t + length) * (1.0 + SEMICIRCLE_ROUND_OFF):
        rd.fail(
            f"{where}height",
            height,
            f"a circular notch's cut-outs are arcs of at most half a circle, so H <= t + L = "
            f"{t + length:g} mm (a taller blank would need the cut-out to overhang its own "
            "ends); lengthen the notch or take an elliptical contour",
        )
    try:
        profile = NotchProfile(contour, t, height, length, radius, exponent)
    except ValueError as exc:
        rd.fail(f"{where}contour", contour, str(exc))
    return Segment(tuple(map(float, a)), tuple(map(float, b))), Section(depth, t, profile)
