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
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .errors import SceneError
from .inertia import MassData
from .loads import Displacement, LoadCase
from .magnitudes import check_magnitudes
from .mobility import check_structure
from .overlap import check_overlaps
from .profiles import ThicknessProfile
from .shapes import Shape


@dataclass(frozen=True)
class Material:
    """Linear elastic constants: Young's modulus E (MPa) and Poisson's ratio nu; optional
    strengths (MPa) against which a model's peak stress is judged.

    The strengths decide no load path: they are left out of the comparison (and so
    of the result cache's key, :func:`flexval.validation.cache.exact`), and every
    model runs the same with or without them.

    Attributes
    ----------
    youngs_modulus : float
        E, MPa.
    poisson_ratio : float
        nu.
    yield_strength : float or None
        sigma_y, MPa: the outer-fibre stress at which the flexure first yields
        (:mod:`flexval.validation.studies.yieldpoint`); None: not given.
    fatigue_strength : float or None
        sigma_f, MPa, below ``yield_strength``: the stress amplitude the
        flexure endures without fatigue failure; None: not given.
    shear_flexible : bool
        The reduced models add the section's transverse shear compliance
        ∫ ds/(k G A) (Timoshenko) to its bending: set on a notch hinge's
        calibrated material (:mod:`flexval.reducedmodels.notchcorrection`),
        never by a scene file.
    """

    youngs_modulus: float
    poisson_ratio: float
    yield_strength: float | None = field(default=None, compare=False)
    fatigue_strength: float | None = field(default=None, compare=False)
    shear_flexible: bool = False

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + nu)), MPa."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    def plane_strain(self) -> Material:
        """The constants of a wide flexure (plate) in bending, MPa: E / (1 - nu^2) and
        nu / (1 - nu), the plane-strain pair, with the same shear modulus G.

        A beam of width b much larger than sqrt(R h) cannot curl sideways
        (anticlastic curvature suppressed), so its bending and axial stiffness
        per unit strain are E / (1 - nu^2), not E; the continuum's
        ``plane=strain`` is the same idealisation in 2D.
        """
        nu = self.poisson_ratio
        wide = self.youngs_modulus / (1.0 - nu * nu)
        return dataclasses.replace(self, youngs_modulus=wide, poisson_ratio=nu / (1.0 - nu))


@dataclass(frozen=True)
class Section:
    """Rectangular flexure cross-section, uniform or varying along the flexure.

    Parameters
    ----------
    depth : float
        b, out-of-plane depth, mm.
    thickness : float
        h, in-plane thickness, mm; for a varying section its smallest value
        (the one that bounds the stress and the validity of thin-beam models).
    profile : ThicknessProfile or None
        h(s) along the flexure (:mod:`flexval.geometry.profiles`: a linear
        taper or a notch contour); None for a uniform section.
    """

    depth: float
    thickness: float
    profile: ThicknessProfile | None = None

    @property
    def is_uniform(self) -> bool:
        """True when the thickness is the same all along the flexure."""
        return self.profile is None

    def _uniform_only(self, what: str) -> None:
        if self.profile is not None:
            raise ValueError(
                f"the section varies along the flexure ({self.profile.kind}): "
                f"use {what}_at(s) for its {what} at arc length s"
            )

    @property
    def area(self) -> float:
        """A = b h, mm^2 (a uniform section's; see :meth:`area_at`)."""
        self._uniform_only("area")
        return self.depth * self.thickness

    @property
    def inertia(self) -> float:
        """I = b h^3 / 12, mm^4 (a uniform section's; see :meth:`inertia_at`)."""
        self._uniform_only("inertia")
        return self.depth * self.thickness**3 / 12.0

    def thickness_at(self, s: np.ndarray | float) -> np.ndarray:
        """h at arc length s (mm) from the flexure's first end, mm."""
        if self.profile is None:
            return np.full(np.shape(s), self.thickness)
        return self.profile.thickness(s)

    def area_at(self, s: np.ndarray | float) -> np.ndarray:
        """A(s) = b h(s), mm^2."""
        return self.depth * self.thickness_at(s)

    def inertia_at(self, s: np.ndarray | float) -> np.ndarray:
        """I(s) = b h(s)^3 / 12, mm^4."""
        return self.depth * self.thickness_at(s) ** 3 / 12.0

    @property
    def max_thickness(self) -> float:
        """The largest thickness along the flexure, mm."""
        return self.thickness if self.profile is None else self.profile.max_thickness

    def scaled(self, factor: float) -> Section:
        """The section with every length (depth, thickness, profile) multiplied by ``factor``."""
        profile = None if self.profile is None else self.profile.scaled(factor)
        return Section(self.depth * factor, self.thickness * factor, profile)


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
    crosses : tuple of str
        Flexures whose centre lines this one may cross: they lie in other layers of the
        depth (a cross-axis pivot's leaves), so the overlap check lets them cross.
    """

    name: str
    shape: Shape
    bodies: tuple[str, str]
    start_body: str
    section: Section
    crosses: tuple[str, ...] = ()

    @property
    def end_body(self) -> str:
        """The body the shape's end point is attached to."""
        return self.bodies[1] if self.start_body == self.bodies[0] else self.bodies[0]

    def end_point_of(self, body: str) -> np.ndarray:
        """The end point (mm) attached to ``body``."""
        p = self.shape.end_points
        return p[0] if body == self.start_body else p[1]

    def bending_stiffness(self, material: Material) -> float:
        """EI of a uniform flexure, N mm^2 (see :meth:`bending_stiffness_at`)."""
        return material.youngs_modulus * self.section.inertia

    def axial_stiffness(self, material: Material) -> float:
        """EA of a uniform flexure, N (see :meth:`axial_stiffness_at`)."""
        return material.youngs_modulus * self.section.area

    def bending_stiffness_at(self, material: Material, s: np.ndarray | float) -> np.ndarray:
        """EI(s) at arc length s (mm) from the first end, N mm^2."""
        return material.youngs_modulus * self.section.inertia_at(s)

    def axial_stiffness_at(self, material: Material, s: np.ndarray | float) -> np.ndarray:
        """EA(s) at arc length s (mm) from the first end, N."""
        return material.youngs_modulus * self.section.area_at(s)


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
    inertia : MassData
        Density, rigid-body masses and gravity (default: none, see
        :mod:`flexval.geometry.inertia`).
    drive : Displacement or None
        The prescribed motion of a displacement-controlled load case (see
        :meth:`driven_by`), joined to the ground by an exact constraint in
        every model; None (the default): no body is driven.
    """

    bodies: dict[str, Body]
    flexures: tuple[Flexure, ...]
    ground: str
    material: Material
    target_body: str
    target_point: np.ndarray
    source: str = field(default="<scene>", compare=False)
    pins: tuple[Pin, ...] = ()
    inertia: MassData = field(default_factory=MassData, compare=False)
    drive: Displacement | None = field(default=None, compare=False)

    def driven_by(self, case: LoadCase) -> Mechanism:
        """The mechanism as ``case`` loads it: with the case's prescribed motion as its
        :attr:`drive` (itself where the case prescribes none and none is set)."""
        drive = case.drive
        if drive is self.drive:
            return self
        return dataclasses.replace(self, drive=drive)

    @property
    def moving_bodies(self) -> list[str]:
        """Names of the non-ground bodies, in order."""
        return [n for n in self.bodies if n != self.ground]

    def size(self) -> float:
        """Largest distance between flexure end points, pin points and the target, mm.

        A length scale that does not change when the mechanism is moved rigidly.
        Computed once per (immutable) mechanism: the solvers ask for it on every
        path, and recomputing the arcs' end points cost about 10 % of a dcmm:1 path.
        """
        return self._size

    @cached_property
    def _size(self) -> float:
        pts = np.vstack(
            [f.shape.end_points for f in self.flexures]
            + [np.asarray(p.point, float)[None] for p in self.pins]
            + [self.target_point[None]]
        )
        # numpy, not scipy.spatial.distance.pdist: importing scipy.spatial costs a
        # command's start-up 0.1-0.2 s, and a mechanism has a few dozen points
        return float(np.linalg.norm(pts[:, None] - pts[None], axis=-1).max())

    def transformed(self, angle: float, shift: np.ndarray) -> Mechanism:
        """The same mechanism rotated by ``angle`` (rad) about the origin, then shifted (mm)."""
        from .transform import transform_mechanism, transform_point

        shift = np.asarray(shift, dtype=float)
        pins = tuple(
            dataclasses.replace(p, point=transform_point(p.point, angle, shift)) for p in self.pins
        )
        return dataclasses.replace(
            transform_mechanism(self, angle, shift),
            pins=pins,
            inertia=self.inertia.transformed(angle, shift),
            drive=None if self.drive is None else self.drive.transformed(angle, shift),
        )


@dataclass(frozen=True)
class FlexureSpec:
    """A flexure as written in a scene, before its ends are attached to bodies.

    Attributes
    ----------
    name : str
    shape : Arc or Segment
        Centre line (lengths mm, angles rad).
    bodies : (str, str)
        The two bodies it joins.
    section : Section
    start_body : str, optional
        Which of ``bodies`` holds the shape's start point; None: inferred
        from the geometry by :func:`assemble`.
    crosses : tuple of str
        Flexures it crosses out of plane (see :class:`Flexure`).
    """

    name: str
    shape: Shape
    bodies: tuple[str, str]
    section: Section
    start_body: str | None = None
    crosses: tuple[str, ...] = ()

    def other(self, body: str) -> str:
        """The body at the other end from ``body``."""
        return self.bodies[1] if body == self.bodies[0] else self.bodies[0]


@dataclass(frozen=True)
class PinSpec:
    """A revolute joint as written in a scene: ``name``, two ``bodies``, ``point`` (mm)."""

    name: str
    bodies: tuple[str, str]
    point: tuple[float, float]


def _check_crossings_named(specs: Sequence[FlexureSpec], source: str) -> None:
    """Each name in a flexure's ``crosses`` is another flexure of the mechanism."""
    names = {spec.name for spec in specs}
    for spec in specs:
        for other in spec.crosses:
            if other == spec.name or other not in names:
                why = "is the flexure itself" if other == spec.name else "names no flexure"
                raise SceneError(source, f"flexures.{spec.name}.crosses", other, why)


def assemble(
    flexure_specs: Sequence[FlexureSpec],
    ground: str,
    ground_points: np.ndarray,
    material: Material,
    target_body: str,
    target_point: np.ndarray,
    source: str = "<scene>",
    body_points: dict[str, np.ndarray] | None = None,
    tolerance: float | None = None,
    pin_specs: Sequence[PinSpec] = (),
) -> Mechanism:
    """Build a Mechanism, attaching every flexure end to one of its bodies.

    Four passes: check the names and the graph (every body reached from the
    ground), infer which end of each flexure belongs to which body, check
    that every given point is used, then build the bodies. The result is
    refused if it intersects itself, if a derived quantity (EI, EA,
    compliances, size) is degenerate, or if it is not a structure (mobile,
    or with redundant pins).

    Parameters
    ----------
    flexure_specs : sequence of FlexureSpec
    ground, ground_points
        Name of the ground and the points (mm) where it holds flexures.
    material : Material
    target_body, target_point
        The body and point (mm) whose motion is traced.
    source : str
        The scene file, for error messages.
    body_points : dict, optional
        Known points of other bodies (mm); flexure ends are matched to them by
        coincidence like the ground's.
    tolerance : float, optional
        Coincidence tolerance, mm. Default: 1e-3 of the extent of the
        flexure end points.
    pin_specs : sequence of PinSpec, optional
        Revolute joints. A pin point is a known point of both its bodies
        (flexure ends there attach to them).

    Raises
    ------
    SceneError
        If a name is duplicated, a flexure end or a given point meets
        nothing, a body is unreachable from the ground, the target body is
        unknown, or the mechanism is impossible (see above).
    """
    specs, pins = tuple(flexure_specs), tuple(pin_specs)
    all_ends = np.vstack([spec.shape.end_points for spec in specs])
    scale = float(np.hypot(*(all_ends.max(axis=0) - all_ends.min(axis=0)))) or 1.0
    tol = tolerance if tolerance is not None else 1e-3 * scale
    body_points = {
        name: np.asarray(pts, float).reshape(-1, 2) for name, pts in (body_points or {}).items()
    }
    ground_points = np.asarray(ground_points, float).reshape(-1, 2)

    body_names = _check_names_and_graph(specs, pins, ground, target_body, body_points, source)
    known = _known_points(ground, ground_points, body_points, pins)
    start_body = _attach_ends(specs, pins, ground, known, tol, source)
    _check_crossings_named(specs, source)
    flexures = tuple(
        Flexure(s.name, s.shape, tuple(s.bodies), start_body[s.name], s.section, s.crosses)
        for s in specs
    )
    pins_built = tuple(Pin(p.name, tuple(p.bodies), np.asarray(p.point, dtype=float)) for p in pins)
    _check_points_used(flexures, pins_built, ground, ground_points, body_points, tol, source)
    check_overlaps(flexures, source, tol)
    points: dict[str, list[np.ndarray]] = {name: [] for name in body_names}
    for f in flexures:  # flexure ends first, then pin points
        start, end = f.shape.end_points
        points[f.start_body].append(start)
        points[f.end_body].append(end)
    for pin in pins_built:
        for name in pin.bodies:
            points[name].append(pin.point)
    bodies = {
        name: Body(name, np.array(points[name], dtype=float), is_ground=(name == ground))
        for name in body_names
    }
    mechanism = Mechanism(
        bodies=bodies,
        flexures=flexures,
        ground=ground,
        material=material,
        target_body=target_body,
        target_point=np.asarray(target_point, dtype=float),
        source=source,
        pins=pins_built,
    )
    check_magnitudes(mechanism)
    check_structure(mechanism)
    return mechanism


def _check_names_and_graph(
    specs: tuple[FlexureSpec, ...],
    pins: tuple[PinSpec, ...],
    ground: str,
    target_body: str,
    body_points: dict[str, np.ndarray],
    source: str,
) -> list[str]:
    """The body names (ground first, then in order of appearance), after checking the graph.

    Names must be unique (pins and flexures share one namespace), the ground
    must hold something, every body must be reachable from the ground and
    the target must be a moving body.
    """
    names = [spec.name for spec in specs]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise SceneError(source, "flexures.name", dup, "duplicate flexure name")
    seen = set(names)
    for pin in pins:
        if pin.name in seen:
            raise SceneError(
                source,
                "pins.name",
                pin.name,
                "duplicate name (pins and flexures share one namespace)",
            )
        seen.add(pin.name)
    links = [*specs, *pins]
    body_names: list[str] = [ground]
    neighbours: dict[str, list[str]] = {ground: []}
    for link in links:
        a, b = link.bodies
        for name in (a, b):
            if name not in neighbours:
                body_names.append(name)
                neighbours[name] = []
        neighbours[a].append(b)
        neighbours[b].append(a)
    if not neighbours[ground]:
        raise SceneError(source, "ground", ground, "no flexure or pin is attached to the ground")
    visited, queue = {ground}, deque([ground])
    while queue:
        for other in neighbours[queue.popleft()]:
            if other not in visited:
                visited.add(other)
                queue.append(other)
    unreached = [b for b in body_names if b not in visited]
    if unreached:
        raise SceneError(
            source,
            "flexures",
            unreached[0],
            f"body {unreached[0]!r} is not connected to the ground",
        )
    if target_body not in neighbours:
        raise SceneError(
            source, "target.body", target_body, f"unknown body; bodies are {body_names}"
        )
    if target_body == ground:
        raise SceneError(source, "target.body", target_body, "the target cannot be the ground")
    for name in body_points:
        if name not in neighbours:
            raise SceneError(
                source,
                f"bodies.{name}",
                name,
                f"no flexure or pin joins this body; bodies are {body_names}",
            )
    return body_names


def _known_points(
    ground: str,
    ground_points: np.ndarray,
    body_points: dict[str, np.ndarray],
    pins: tuple[PinSpec, ...],
) -> dict[str, list[np.ndarray]]:
    """Points (mm) known to lie on each body before any flexure is attached."""
    known: dict[str, list[np.ndarray]] = {ground: list(ground_points)}
    for name, pts in body_points.items():
        known.setdefault(name, []).extend(pts)
    for pin in pins:
        for b in pin.bodies:
            known.setdefault(b, []).append(np.asarray(pin.point, float))
    return known


def _attach_ends(
    specs: tuple[FlexureSpec, ...],
    pins: tuple[PinSpec, ...],
    ground: str,
    known: dict[str, list[np.ndarray]],
    tol: float,
    source: str,
) -> dict[str, str]:
    """The body holding each flexure's start point, by flexure name.

    Explicit ``start_body`` first, then coincidence of an end with a known
    point of one of its bodies; the rest by a walk from the ground along the
    body graph, where an end goes to the body whose points already placed are
    nearest (the shortest rigid link). A flexure on the ground must have its
    ground end on a known ground point.
    """
    start_body: dict[str, str] = {}
    for spec in specs:
        if spec.start_body is not None:
            if spec.start_body not in spec.bodies:
                raise SceneError(
                    source,
                    f"flexures.{spec.name}.start_body",
                    spec.start_body,
                    f"must be one of the flexure's bodies {list(spec.bodies)}",
                )
            start_body[spec.name] = spec.start_body
            continue
        ends = spec.shape.end_points
        for b in spec.bodies:
            pts = known.get(b)
            if not pts:
                continue
            d = [min(np.hypot(*(e - p)) for p in pts) for e in ends]
            if min(d) <= tol:
                start_body[spec.name] = b if int(np.argmin(d)) == 0 else spec.other(b)
                break
    for spec in specs:
        if ground in spec.bodies:
            _check_ground_end(spec, start_body.get(spec.name), ground, known[ground], tol, source)

    placed: dict[str, list[np.ndarray]] = {b: list(p) for b, p in known.items()}

    def place(spec: FlexureSpec) -> None:
        sb = start_body[spec.name]
        ends = spec.shape.end_points
        placed.setdefault(sb, []).append(ends[0])
        placed.setdefault(spec.other(sb), []).append(ends[1])

    for spec in specs:
        if spec.name in start_body:
            place(spec)
    flexures_of: dict[str, list[FlexureSpec]] = {}
    pin_neighbours: dict[str, list[str]] = {}
    for spec in specs:
        for b in spec.bodies:
            flexures_of.setdefault(b, []).append(spec)
    for pin in pins:
        a, b = pin.bodies
        pin_neighbours.setdefault(a, []).append(b)
        pin_neighbours.setdefault(b, []).append(a)
    queue, visited = deque([ground]), {ground}
    while queue:
        body = queue.popleft()
        for other in pin_neighbours.get(body, []):
            if other not in visited:
                visited.add(other)
                queue.append(other)
        for spec in flexures_of.get(body, []):
            other = spec.other(body)
            if spec.name not in start_body:
                ends = spec.shape.end_points
                d = [min(np.hypot(*(e - p)) for p in placed[body]) for e in ends]
                start_body[spec.name] = body if d[0] <= d[1] else other
                place(spec)
            if other not in visited:
                visited.add(other)
                queue.append(other)
    return start_body


def _check_ground_end(
    spec: FlexureSpec,
    start_body: str | None,
    ground: str,
    ground_points: list[np.ndarray],
    tol: float,
    source: str,
) -> None:
    """Refuse a ground flexure whose ground end meets no ground point.

    While the ground end is not yet known, the flexure is refused when
    neither end meets one.
    """
    ends = spec.shape.end_points
    candidates = ends if start_body is None else [ends[0] if start_body == ground else ends[1]]
    gaps = [min(np.hypot(*(e - p)) for p in ground_points) for e in candidates]
    if min(gaps) <= tol:
        return
    if start_body is None:
        raise SceneError(
            source,
            f"flexures.{spec.name}",
            spec.name,
            f"no end point meets a ground point within {tol:.3g} mm "
            f"(nearest is {min(gaps):.3g} mm away)",
        )
    raise SceneError(
        source,
        f"flexures.{spec.name}.start_body",
        start_body,
        f"puts the flexure's ground end {gaps[0]:.3g} mm away from every ground "
        f"point (tolerance {tol:.3g} mm): the ground holds nothing there",
    )


def _check_points_used(
    flexures: tuple[Flexure, ...],
    pins: tuple[Pin, ...],
    ground: str,
    ground_points: np.ndarray,
    body_points: dict[str, np.ndarray],
    tol: float,
    source: str,
) -> None:
    """Refuse a given ground or body point that no flexure end or pin of that body meets."""
    given = [(ground, "ground.points", p) for p in ground_points] + [
        (name, f"bodies.{name}.points", p) for name, pts in body_points.items() for p in pts
    ]
    for body, field_name, p in given:
        attached = [f.end_point_of(body) for f in flexures if body in f.bodies] + [
            pin.point for pin in pins if body in pin.bodies
        ]
        if not any(np.hypot(*(p - q)) <= tol for q in attached):
            raise SceneError(
                source,
                field_name,
                [float(p[0]), float(p[1])],
                f"no flexure end or pin of body {body!r} meets this point "
                f"within {tol:.3g} mm: it would be ignored",
            )
