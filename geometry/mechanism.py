"""What a planar compliant mechanism is: bodies, flexures, section, material.

A mechanism is a graph: rigid bodies (one of them the ground) joined by
flexures and, optionally, pins (revolute joints). Each flexure end is
attached to one of the two bodies it joins.
Which end belongs to which body is derived from the geometry (coincidence
of end points with the points a body is known to have, else the end nearest
to the body's points already placed), or given explicitly with
``start_body``. Rigid links are then the sets of flexure end points and pin
points on each body. Nothing here knows about any solver.

Units: mm, MPa (N/mm^2), N, rad.
"""

from __future__ import annotations

import dataclasses
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .errors import SceneError
from .overlap import check_overlaps
from .shapes import FlexureShape


@dataclass(frozen=True)
class Material:
    """Linear elastic constants: Young's modulus E (MPa) and Poisson's ratio nu."""

    youngs_modulus: float
    poisson_ratio: float

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + nu)), MPa."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))


@dataclass(frozen=True)
class Section:
    """Rectangular flexure cross-section.

    Parameters
    ----------
    depth : float
        b, out-of-plane depth, mm.
    thickness : float
        h, in-plane thickness, mm.
    """

    depth: float
    thickness: float

    @property
    def area(self) -> float:
        """A = b h, mm^2."""
        return self.depth * self.thickness

    @property
    def inertia(self) -> float:
        """Second moment of area I = b h^3 / 12, mm^4 (in-plane bending)."""
        return self.depth * self.thickness**3 / 12.0


@dataclass(frozen=True)
class Flexure:
    """A flexure joining two bodies.

    Attributes
    ----------
    name : str
    shape : Arc or Segment
        Centre line, parametrised from its start to its end point.
    bodies : (str, str)
        The bodies it joins, as written in the scene (e_ij joins i to j; i is
        the leading body for DCMM's displaced frame).
    start_body : str
        Which of ``bodies`` the shape's start point is attached to.
    section : Section
    """

    name: str
    shape: FlexureShape
    bodies: tuple[str, str]
    start_body: str
    section: Section

    @property
    def end_body(self) -> str:
        """The body the shape's end point is attached to."""
        return self.bodies[1] if self.start_body == self.bodies[0] else self.bodies[0]

    def end_point_of(self, body: str) -> np.ndarray:
        """The end point (mm) attached to ``body``."""
        p = self.shape.end_points
        return p[0] if body == self.start_body else p[1]

    def bending_stiffness(self, material: Material) -> float:
        """EI, N mm^2."""
        return material.youngs_modulus * self.section.inertia

    def axial_stiffness(self, material: Material) -> float:
        """EA, N."""
        return material.youngs_modulus * self.section.area


@dataclass(frozen=True)
class Pin:
    """A revolute joint: the material points of two bodies at ``point`` stay together.

    Attributes
    ----------
    name : str
    bodies : (str, str)
        The two bodies it joins (either may be the ground).
    point : ndarray, shape (2,)
        The joint's position in the undeformed configuration, mm. The
        relative rotation of the two bodies about it is free.
    """

    name: str
    bodies: tuple[str, str]
    point: np.ndarray


@dataclass(frozen=True)
class Body:
    """A rigid body: its name and the points (mm) where flexures and pins attach.

    ``reference`` is the origin of the body frame (its pose (x, y, theta)
    is the position of that point and the body's rotation); it is the
    first attachment point (flexure ends come before pin points).
    """

    name: str
    points: np.ndarray
    is_ground: bool = False

    @property
    def reference(self) -> np.ndarray:
        """Origin of the body frame, mm."""
        return self.points[0]


@dataclass(frozen=True)
class Mechanism:
    """A planar compliant mechanism.

    Attributes
    ----------
    bodies : dict[str, Body]
        All bodies, ground included, in a stable order (ground first).
    flexures : tuple[Flexure, ...]
    ground : str
    material : Material
    target_body : str
    target_point : ndarray, shape (2,)
        The tracing point (mm), attached to ``target_body``.
    pins : tuple[Pin, ...]
        Revolute joints between bodies (none by default).
    """

    bodies: dict[str, Body]
    flexures: tuple[Flexure, ...]
    ground: str
    material: Material
    target_body: str
    target_point: np.ndarray
    source: str = field(default="<scene>", compare=False)
    pins: tuple[Pin, ...] = ()

    @property
    def moving_bodies(self) -> list[str]:
        """Names of the non-ground bodies, in order."""
        return [n for n in self.bodies if n != self.ground]

    def size(self) -> float:
        """Largest distance between flexure end points, pin points and the target, mm.

        A length scale that does not change when the mechanism is moved rigidly.
        """
        pts = np.vstack([f.shape.end_points for f in self.flexures]
                        + [np.asarray(p.point, float)[None] for p in self.pins]
                        + [self.target_point[None]])
        d = pts[:, None, :] - pts[None, :, :]
        return float(np.sqrt((d**2).sum(axis=-1)).max())

    def transformed(self, angle: float, shift: np.ndarray) -> "Mechanism":
        """The same mechanism rotated by ``angle`` (rad) about the origin, then shifted (mm)."""
        from .transform import transform_mechanism, transform_point

        shift = np.asarray(shift, dtype=float)
        pins = tuple(dataclasses.replace(p, point=transform_point(p.point, angle, shift))
                     for p in self.pins)
        return dataclasses.replace(transform_mechanism(self, angle, shift), pins=pins)


def assemble(
    flexure_specs: list[dict],
    ground: str,
    ground_points: np.ndarray,
    material: Material,
    target_body: str,
    target_point: np.ndarray,
    source: str = "<scene>",
    body_points: dict[str, np.ndarray] | None = None,
    tolerance: float | None = None,
    pin_specs: list[dict] | None = None,
) -> Mechanism:
    """Build a Mechanism, attaching every flexure end to one of its bodies.

    Parameters
    ----------
    flexure_specs : list of dict
        Each with keys ``name``, ``shape``, ``bodies`` (two names),
        ``section`` and optionally ``start_body``.
    ground, ground_points
        Name of the ground and the points (mm) where it holds flexures.
    body_points : dict, optional
        Known points of other bodies (mm); flexure ends are matched to them by
        coincidence like the ground's.
    tolerance : float, optional
        Coincidence tolerance, mm. Default: 1e-3 of the mechanism's size.
    pin_specs : list of dict, optional
        Revolute joints, each with keys ``name``, ``bodies`` (two different
        names) and ``point`` (mm). A pin point is a known point of both its
        bodies (flexure ends there attach to them) and a pin connects its
        bodies like a flexure for the reachability check.

    Raises
    ------
    SceneError
        If a flexure end meets no body, a body is unreachable from the ground,
        the target body is unknown, or a name is duplicated.
    """
    pin_specs = list(pin_specs or [])
    known: dict[str, list[np.ndarray]] = {ground: [np.asarray(p, float) for p in ground_points]}
    for name, pts in (body_points or {}).items():
        known.setdefault(name, []).extend(np.asarray(p, float) for p in pts)
    for pin in pin_specs:
        for b in pin["bodies"]:
            known.setdefault(b, []).append(np.asarray(pin["point"], float))
    all_ends = np.vstack([spec["shape"].end_points for spec in flexure_specs])
    scale = float(np.hypot(*(all_ends.max(axis=0) - all_ends.min(axis=0)))) or 1.0
    tol = tolerance if tolerance is not None else 1e-3 * scale

    names = [spec["name"] for spec in flexure_specs]
    body_names: list[str] = [ground]
    for spec in [*flexure_specs, *pin_specs]:
        for b in spec["bodies"]:
            if b not in body_names:
                body_names.append(b)
    if ground not in {b for spec in [*flexure_specs, *pin_specs] for b in spec["bodies"]}:
        raise SceneError(source, "ground", ground, "no flexure or pin is attached to the ground")

    start_body: dict[str, str] = {}
    # explicit assignments and coincidences first
    for spec in flexure_specs:
        ends = spec["shape"].end_points
        if spec.get("start_body") is not None:
            sb = spec["start_body"]
            if sb not in spec["bodies"]:
                raise SceneError(
                    source, f"flexures.{spec['name']}.start_body", sb,
                    f"must be one of the flexure's bodies {list(spec['bodies'])}",
                )
            start_body[spec["name"]] = sb
            continue
        for b in spec["bodies"]:
            pts = known.get(b)
            if not pts:
                continue
            d = [min(np.hypot(*(e - p)) for p in pts) for e in ends]
            if min(d) <= tol:
                k = int(np.argmin(d))
                other = spec["bodies"][1] if b == spec["bodies"][0] else spec["bodies"][0]
                start_body[spec["name"]] = b if k == 0 else other
                break
        else:
            if ground in spec["bodies"]:
                d = min(np.hypot(*(e - p)) for e in ends for p in known[ground])
                raise SceneError(
                    source, f"flexures.{spec['name']}", spec["name"],
                    f"no end point meets a ground point within {tol:.3g} mm "
                    f"(nearest is {d:.3g} mm away)",
                )

    # propagate from the ground along the flexure graph: an end goes to the
    # body whose already placed points are nearest (the shortest rigid link)
    placed: dict[str, list[np.ndarray]] = {b: list(p) for b, p in known.items()}

    def place(spec: dict) -> None:
        sb = start_body[spec["name"]]
        other = spec["bodies"][1] if sb == spec["bodies"][0] else spec["bodies"][0]
        ends = spec["shape"].end_points
        placed.setdefault(sb, []).append(ends[0])
        placed.setdefault(other, []).append(ends[1])

    for spec in flexure_specs:
        if spec["name"] in start_body:
            place(spec)
    queue = deque([ground])
    visited = {ground}
    while queue:
        body = queue.popleft()
        for pin in pin_specs:
            if body in pin["bodies"]:
                other = pin["bodies"][1] if body == pin["bodies"][0] else pin["bodies"][0]
                if other not in visited:
                    visited.add(other)
                    queue.append(other)
        for spec in flexure_specs:
            if body not in spec["bodies"]:
                continue
            other = spec["bodies"][1] if body == spec["bodies"][0] else spec["bodies"][0]
            if spec["name"] not in start_body:
                ends = spec["shape"].end_points
                d = [min(np.hypot(*(e - p)) for p in placed[body]) for e in ends]
                start_body[spec["name"]] = body if d[0] <= d[1] else other
                place(spec)
            if other not in visited:
                visited.add(other)
                queue.append(other)

    unreached = [b for b in body_names if b not in visited]
    if unreached:
        raise SceneError(source, "flexures", unreached[0],
                         f"body {unreached[0]!r} is not connected to the ground")
    if target_body not in body_names:
        raise SceneError(source, "target.body", target_body,
                         f"unknown body; bodies are {body_names}")
    if target_body == ground:
        raise SceneError(source, "target.body", target_body, "the target cannot be the ground")
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise SceneError(source, "flexures.name", dup, "duplicate flexure name")
    pin_names = [pin["name"] for pin in pin_specs]
    for k, name in enumerate(pin_names):
        if name in names or name in pin_names[:k]:
            raise SceneError(source, "pins.name", name,
                             "duplicate name (pins and flexures share one namespace)")

    flexures = tuple(
        Flexure(spec["name"], spec["shape"], tuple(spec["bodies"]), start_body[spec["name"]],
                spec["section"])
        for spec in flexure_specs
    )
    check_overlaps(flexures, source, tol)
    pins = tuple(Pin(p["name"], tuple(p["bodies"]), np.asarray(p["point"], dtype=float))
                 for p in pin_specs)
    bodies: dict[str, Body] = {}
    for name in body_names:
        pts = ([f.end_point_of(name) for f in flexures if name in f.bodies]
               + [p.point for p in pins if name in p.bodies])
        bodies[name] = Body(name, np.array(pts, dtype=float), is_ground=(name == ground))
    return Mechanism(
        bodies=bodies,
        flexures=flexures,
        ground=ground,
        material=material,
        target_body=target_body,
        target_point=np.asarray(target_point, dtype=float),
        source=source,
        pins=pins,
    )
