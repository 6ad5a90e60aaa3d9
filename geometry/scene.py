"""Scene files (TOML): a mechanism, its load cases and what is requested.

A scene is the one input of every flexval command. ``load_scene`` accepts a
built-in name (:data:`BUILTIN_SCENES`: the paper's ``open_chain`` and
``closed_chain``, the flexure scenes ``notch_fourbar``, ``filleted_stage``,
``tapered_leaf``, ``spline_flexure`` and the canonical mechanisms
``parallel_guide``, ``folded_guide``, ``cross_pivot``, ``cartwheel_hinge``,
``trapezoid_pivot``, ``bistable_truss``, ``bistable_arch``, ``bridge_amplifier``) or a
path. Every value is
checked; a bad one raises :class:`SceneError` naming the file, the field and
the value. Angles are degrees in the file and radians in memory; lengths mm,
moduli MPa, forces N, moments N mm.

Every table's fields (``[material]``, ``[section]``, ``[ground]``, ``[target]``,
``[[flexures]]`` of every shape, ``[[bodies]]``, ``[[pins]]``, the mass data,
``[[load_cases]]``, ``[request]``, ``[[measurements]]``) are declared once in
:mod:`flexval.geometry.scenefields` (kind, unit, default, allowed values); the parser
takes its known fields, defaults and range checks from there, and the scene file
reference of the documentation is generated from the same declarations
(:func:`field_reference`).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import tomllib
import unicodedata
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .errors import COMMAND_LINE, SceneError, did_you_mean
from .fields import Table
from .flexurefields import check_thickness_fits, read_notch, read_spline, read_thickness, section_of
from .inertia import MassData, parse_body_mass, parse_density, parse_gravity
from .loads import LOAD_KINDS, Displacement, Force, LoadCase, Moment
from .measured import Measurement, read_measurement
from .mechanism import FlexureSpec, Material, Mechanism, PinSpec, Section, assemble
from .scenefields import (
    BODIES,
    FLEXURE_SHAPES,
    FLEXURES,
    GROUND,
    LOAD_CASES,
    LOAD_COMPONENTS,
    MATERIAL,
    MAX_NAME_LENGTH,
    MEASUREMENTS,
    OUTPUTS,
    PINS,
    REQUEST,
    SCENE,
    SECTION,
    TARGET,
    field_reference,
)
from .shapes import Arc, Segment
from .tablereader import TableReader, read_utf8
from .timelaw import parse_time_law

NO_DATA = (
    "this scene keeps no scene data (a sweep's point: change the sweep's base or axes instead; "
    "load_scene and parse_scene give scenes that keep it)"
)

PAPER_SCENES = ("open_chain", "closed_chain")
"""The reference paper's two case studies (Sorgonà et al. 2024, Sect. 4)."""
FLEXURE_SCENES = ("notch_fourbar", "filleted_stage", "tapered_leaf", "spline_flexure")
"""Mechanisms of varying-section and free-form flexures: circular notch hinges,
corner-filleted notch hinges, tapered leaves and an S-shaped spline."""
MECHANISM_SCENES = (
    "parallel_guide",
    "folded_guide",
    "cross_pivot",
    "cartwheel_hinge",
    "trapezoid_pivot",
    "bistable_truss",
    "bistable_arch",
    "bridge_amplifier",
)
"""Canonical mechanisms designers build, each with an independent anchor in the tests: a
parallel leaf guide, a folded guide, a cross-axis pivot, a cartwheel hinge, a
leaf-type isosceles-trapezoidal pivot, a bistable truss, a fully compliant bistable arch
and a notch-hinge bridge-type displacement amplifier."""
BUILTIN_SCENES = PAPER_SCENES + FLEXURE_SCENES + MECHANISM_SCENES
"""Every scene ``load_scene`` knows by name (files in ``flexval/geometry/scenes``)."""

__all__ = [
    "BUILTIN_SCENES",
    "FLEXURE_SCENES",
    "MECHANISM_SCENES",
    "PAPER_SCENES",
    "MAX_NAME_LENGTH",
    "OUTPUTS",
    "Scene",
    "field_reference",
    "load_scene",
    "parse_scene",
    "read_scene_data",
]


@dataclass(frozen=True)
class Scene:
    """A mechanism with its load cases and the requested models and outputs.

    ``models`` are the model ids of ``request.models`` as written: geometry
    knows no model; :func:`flexval.reducedmodels.catalogue.parse_model` reads them
    (with source ``source`` and field ``request.models``) when they are used.
    ``measurements`` are the ``[[measurements]]`` files, read and checked against their
    load cases (:mod:`flexval.geometry.measured`).
    """

    name: str
    description: str
    mechanism: Mechanism
    load_cases: tuple[LoadCase, ...]
    models: tuple[str, ...]
    outputs: frozenset[str]
    source: str
    measurements: tuple[Measurement, ...] = ()
    data: dict | None = field(default=None, compare=False, repr=False)
    """The scene file's parsed TOML it was built from (read, never edited: :meth:`with_changes`
    edits a copy); None for a scene built otherwise."""

    def with_changes(self, changes: Mapping[str, float]) -> Scene:
        """The scene with numeric fields changed, each named by its path as a sweep axis names
        it (:mod:`flexval.geometry.scenepaths`), e.g. ``{"section.thickness": 0.2,
        "flexures.e34.width_deg": 200}`` (units as in a scene file: mm, MPa, N, degrees),
        checked as a scene file is.

        Raises
        ------
        SceneError
            Naming the path where it addresses no numeric field, or the field whose new
            value the scene refuses (the value with it).
        """
        from .scenepaths import field_slot

        if self.data is None:
            raise SceneError(self.source, "with_changes", dict(changes), NO_DATA)
        data = copy.deepcopy(self.data)
        for path, value in changes.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise SceneError(self.source, path, value, "must be a number")
            node, key = field_slot(data, str(path), self.source, str(path))
            node[key] = value
        changed = parse_scene(data, f"{self.source} with {dict(changes)}", default_name=self.name)
        names = [c.name for c in self.load_cases]
        if [c.name for c in changed.load_cases] != names:  # a filtered scene stays filtered
            changed = changed.with_load_cases(names)
        return changed

    def with_load_cases(self, names: Sequence[str], field: str = "--load-case") -> Scene:
        """The scene with only the load cases ``names``, in that order (and their
        measurements): a command's ``--load-case`` filter.

        Raises
        ------
        SceneError
            Naming ``field`` and a name the scene has no load case of.
        """
        chosen = []
        for name in names:
            if name not in {lc.name for lc in self.load_cases}:
                raise SceneError(
                    COMMAND_LINE,
                    field,
                    name,
                    f"scene {self.name} has no such load case; it has "
                    f"{[lc.name for lc in self.load_cases]}",
                )
            if name not in chosen:
                chosen.append(name)
        return dataclasses.replace(
            self,
            load_cases=tuple(self.load_case(n) for n in chosen),
            measurements=tuple(m for m in self.measurements if m.load_case in chosen),
        )

    def load_case(self, name: str) -> LoadCase:
        """The load case called ``name``."""
        for lc in self.load_cases:
            if lc.name == name:
                return lc
        raise SceneError(
            self.source,
            "load_case",
            name,
            f"unknown load case; the scene has {[lc.name for lc in self.load_cases]}",
        )


def _shapes_text(shapes) -> str:
    """``a segment or a notch``: the shapes (``shape`` values) in words."""
    words = [f"{'an' if s[0] in 'aeiou' else 'a'} {s}" for s in shapes]
    return " or ".join([", ".join(words[:-1]), words[-1]] if len(words) > 1 else words)


def _refuse_fields_of_other_shapes(rd: TableReader, f: dict, where: str, kind: str) -> None:
    """Refuse a field that belongs to another shape than ``kind`` (its declared variants).

    Without ``shape`` the flexure is an arc: fields of another shape there mean the
    ``shape`` is missing, and the error names it and the shapes they belong to.
    """
    foreign = [k for k in f if k in FLEXURES and k not in FLEXURES.keys(kind)]
    if not foreign:
        return
    owners = [s for s in FLEXURE_SHAPES if all(k in FLEXURES.keys(s) for k in foreign)]
    fields = " and ".join(f"{k!r}" for k in foreign)
    verb = "belong" if len(foreign) > 1 else "belongs"
    arc_fields = ("center", "radius", "axis_deg", "width_deg")
    if "shape" not in f and not all(k in f for k in arc_fields):
        shapes = owners or [s for s in FLEXURE_SHAPES if s != kind]
        choices = " or ".join(f'shape = "{s}"' for s in shapes)
        rd.fail(
            f"{where}shape",
            None,
            f"missing: {fields} {verb} to {_shapes_text(shapes)}, but without shape the "
            f"flexure is an arc (center, radius, axis_deg, width_deg): give {choices}",
        )
    key = foreign[0]
    shapes = FLEXURES[key].variants
    given = "" if "shape" in f else " (the flexure gives no shape)"
    rd.fail(
        f"{where}{key}",
        f[key],
        f"{key!r} belongs to {_shapes_text(shapes)} ("
        + " or ".join(f'shape = "{s}"' for s in shapes)
        + f"), not to {_shapes_text([kind])}{given}: remove it or change the shape",
    )


def _flexure_spec(rd: TableReader, f: dict, k: int, default_section: Section) -> FlexureSpec:
    if not isinstance(f, dict):
        rd.fail(f"flexures[{k}]", f, "must be a table")
    name = rd.value(f, FLEXURES["name"], f"flexures[{k}].")
    where = f"flexures.{name}."
    rd.known_keys(f, FLEXURES, where)
    bodies = rd.body_pair(f, where, "flexure")
    depth = rd.value(f, FLEXURES["depth"], where, default=default_section.depth)
    kind = rd.value(f, FLEXURES["shape"], where)
    _refuse_fields_of_other_shapes(rd, f, where, kind)
    if kind == "notch":
        shape, section = read_notch(rd, f, where, depth, default_section.thickness)
    else:
        thickness = read_thickness(rd, f, where, default_section.thickness)
        if kind == "arc":
            center = rd.value(f, FLEXURES["center"], where)
            radius = rd.value(f, FLEXURES["radius"], where)
            axis = rd.value(f, FLEXURES["axis_deg"], where)
            width = rd.value(f, FLEXURES["width_deg"], where)
            shape = Arc(
                (float(center[0]), float(center[1])),
                radius,
                math.radians(axis),
                math.radians(width),
            )
        elif kind == "segment":
            a, b = rd.value(f, FLEXURES["start"], where), rd.value(f, FLEXURES["end"], where)
            if np.hypot(*(b - a)) <= 0.0:
                rd.fail(f"{where}end", list(b), "segment has zero length")
            shape = Segment(tuple(map(float, a)), tuple(map(float, b)))
        else:
            shape = read_spline(rd, f, where)
        section = section_of(depth, thickness, shape)
        value = list(thickness) if isinstance(thickness, tuple) else thickness
        check_thickness_fits(rd, where, value, shape, section)
    start_body = rd.value(f, FLEXURES["start_body"], where)
    crosses = f.get("crosses", [])
    if not isinstance(crosses, list) or not all(isinstance(c, str | int) for c in crosses):
        rd.fail(f"{where}crosses", crosses, "must be an array of flexure names")
    return FlexureSpec(
        name, shape, tuple(bodies), section, start_body, tuple(str(c) for c in crosses)
    )


def _pin_spec(rd: TableReader, p: dict, k: int) -> PinSpec:
    """One ``[[pins]]`` table: a revolute joint between two different bodies at a point."""
    if not isinstance(p, dict):
        rd.fail(f"pins[{k}]", p, "must be a table")
    name = rd.value(p, PINS["name"], f"pins[{k}].")
    where = f"pins.{name}."
    rd.known_keys(p, PINS, where)
    bodies = rd.body_pair(p, where, "pin")
    point = rd.value(p, PINS["point"], where)
    return PinSpec(name, tuple(bodies), (float(point[0]), float(point[1])))


def _load_component(
    rd: TableReader,
    c: dict,
    where: str,
    target_body: str,
    target_point: np.ndarray,
    table: Table,
    variant: str | None = None,
) -> Moment | Force | Displacement:
    """One load: the fields of ``table`` (of ``variant``) in ``c``."""
    rd.known_keys(c, table, where, variant)
    kind = c.get("kind")
    if kind not in LOAD_KINDS:
        hint = did_you_mean(kind, LOAD_KINDS)
        if kind is None:
            force = [k for k in ("point", "angle_deg") if k in c]
            hint = f" ({' and '.join(force)} belong to a force)" if force else ""
        rd.fail(f"{where}kind", kind, f"must be 'moment', 'force' or 'displacement'{hint}")
    body = rd.value(c, table["body"], where, default=target_body)
    if kind == "displacement":
        return _displacement(rd, c, where, body, target_body, target_point, table)
    for key in _DRIVE_KEYS:
        if key in c:
            rd.fail(f"{where}{key}", c[key], f"belongs to kind = 'displacement', not a {kind}")
    if "value" not in c:
        rd.fail(f"{where}value", None, f"missing: a {kind} needs its full value")
    value = rd.value(c, table["value"], where)
    if kind == "moment":
        for key in ("point", "angle_deg"):
            if key in c:
                rd.fail(
                    f"{where}{key}",
                    c[key],
                    "a moment has no point of application or "
                    "direction (it acts on the whole body): remove it or use kind = 'force'",
                )
        return Moment(body, value)
    point = _point_of(rd, c, where, body, target_body, target_point, table, "a force")
    if "angle_deg" not in c:
        rd.fail(
            f"{where}angle_deg",
            None,
            "missing: a force needs its direction in degrees from the x axis, "
            "counterclockwise (a pure couple is kind = 'moment')",
        )
    angle = rd.value(c, table["angle_deg"], where)
    return Force(body, point, math.radians(angle), value)


_DRIVE_KEYS = ("dx", "dy", "rotation_deg")
"""The fields of a prescribed motion (kind = 'displacement')."""


def _point_of(
    rd: TableReader,
    c: dict,
    where: str,
    body: str,
    target_body: str,
    target_point: np.ndarray,
    table: Table,
    what: str,
) -> np.ndarray:
    """The ``point`` of a force or a drive; the target point only on the target body."""
    if "point" not in c and body != target_body:
        rd.fail(
            f"{where}point",
            None,
            f"missing: {what} on body {body!r} needs its point of application [x, y] in mm "
            f"(the default, the target point, is on the target body {target_body!r})",
        )
    return rd.value(c, table["point"], where, default=target_point)


def _displacement(
    rd: TableReader,
    c: dict,
    where: str,
    body: str,
    target_body: str,
    target_point: np.ndarray,
    table: Table,
) -> Displacement:
    """A prescribed motion: dx, dy (mm) and rotation_deg (deg) of a body point, at least one."""
    if "value" in c:
        rd.fail(
            f"{where}value",
            c["value"],
            "a displacement has no value: give its dx, dy (mm) and/or rotation_deg",
        )
    if not any(key in c for key in _DRIVE_KEYS):
        rd.fail(
            f"{where}dx",
            None,
            "missing: a displacement prescribes at least one of dx, dy (mm) and rotation_deg",
        )
    point = _point_of(rd, c, where, body, target_body, target_point, table, "a displacement")
    dx, dy, turn = (rd.value(c, table[key], where) for key in _DRIVE_KEYS)
    angle = rd.value(c, table["angle_deg"], where, default=0.0)
    return Displacement(
        body,
        point,
        dx,
        dy,
        None if turn is None else math.radians(turn),
        math.radians(angle),
    )


_UNSAFE_NAME_CHARACTERS = set('/\\<>:"|?*')
"""Characters that are path separators or not allowed in file names on common systems."""


def _scene_name(rd: TableReader, value: Any) -> str:
    """The scene's name, which other commands use as a file-name stem: it must be safe as one."""
    if not isinstance(value, str) or not value.strip():
        rd.fail("name", value, "must be a non-empty string")
    bad = sorted(
        {
            ch
            for ch in value
            if ch in _UNSAFE_NAME_CHARACTERS or unicodedata.category(ch) in ("Cc", "Cf", "Zl", "Zp")
        }
    )
    if bad:
        rd.fail(
            "name",
            value,
            f"must be usable as a file name: it contains {bad} (path "
            "separators, characters file systems forbid, or control characters)",
        )
    if value.strip(" .") == "":
        rd.fail("name", value, "must be usable as a file name, not a path like '.' or '..'")
    if len(value) > MAX_NAME_LENGTH:
        rd.fail("name", value, f"is longer than {MAX_NAME_LENGTH} characters")
    return value


def _material(rd: TableReader, data: dict) -> tuple[Material, dict]:
    """``[material]``: E (MPa), nu, the optional yield and fatigue strengths (MPa, the
    fatigue strength below the yield strength), and the raw table (its density is read
    later)."""
    mat = rd.table(data, "material", "")
    rd.known_keys(mat, MATERIAL, "material.")
    E = rd.value(mat, MATERIAL["youngs_modulus"], "material.")
    nu = rd.value(mat, MATERIAL["poisson_ratio"], "material.")
    yield_strength = rd.value(mat, MATERIAL["yield_strength"], "material.")
    fatigue = rd.value(mat, MATERIAL["fatigue_strength"], "material.")
    if fatigue is not None and yield_strength is None:
        rd.fail("material.fatigue_strength", fatigue, "needs material.yield_strength")
    if fatigue is not None and fatigue >= yield_strength:
        rd.fail(
            "material.fatigue_strength",
            fatigue,
            f"must be below material.yield_strength ({yield_strength:g} MPa)",
        )
    return Material(E, nu, yield_strength, fatigue), mat


def _section(rd: TableReader, data: dict) -> Section:
    """``[section]``: the default depth b and thickness h of every flexure, mm."""
    sec = rd.table(data, "section", "")
    rd.known_keys(sec, SECTION, "section.")
    return Section(
        rd.value(sec, SECTION["depth"], "section."),
        rd.value(sec, SECTION["thickness"], "section."),
    )


def _ground(rd: TableReader, data: dict) -> tuple[str, np.ndarray]:
    """``[ground]``: its name and the points (mm) where it holds flexures."""
    ground_t = rd.table(data, "ground", "")
    rd.known_keys(ground_t, GROUND, "ground.")
    ground = rd.value(ground_t, GROUND["name"], "ground.")
    gpts = ground_t.get("points")
    if not (isinstance(gpts, list) and gpts):
        rd.fail(
            "ground.points",
            gpts,
            "must list at least one point [x, y] where the ground holds a flexure",
        )
    return ground, np.array([rd.point({"p": p}, "p", "ground.points.") for p in gpts])


def _target(rd: TableReader, data: dict) -> tuple[str, np.ndarray]:
    """``[target]``: the target body and its tracing point, mm."""
    target_t = rd.table(data, "target", "")
    rd.known_keys(target_t, TARGET, "target.")
    return rd.value(target_t, TARGET["body"], "target."), rd.value(
        target_t, TARGET["point"], "target."
    )


def _bodies(
    rd: TableReader, data: dict, density: float | None, depth: float
) -> tuple[dict[str, np.ndarray], dict]:
    """``[[bodies]]``: known points of links (mm) and their mass data, by body name."""
    body_points, body_masses = {}, {}
    for k, b in enumerate(rd.array(data, "bodies", "", "tables [[bodies]]")):
        b = rd.item_table(b, f"bodies[{k}]")
        bname = rd.value(b, BODIES["name"], f"bodies[{k}].")
        rd.known_keys(b, BODIES, f"bodies.{bname}.")
        if bname in body_points:
            rd.fail("bodies.name", bname, "duplicate [[bodies]] entry: list a body's points once")
        rigid_mass = parse_body_mass(b, f"bodies.{bname}.", density, depth, rd.fail)
        if rigid_mass is not None:
            body_masses[bname] = rigid_mass
        body_points[bname] = np.array(
            [
                rd.point({"p": p}, "p", f"bodies.{bname}.points.")
                for p in rd.array(b, "points", f"bodies.{bname}.", "points [x, y]")
            ]
        )
    return body_points, body_masses


def _mechanism(rd: TableReader, data: dict, source: str) -> Mechanism:
    """The mechanism of a scene: material, flexures, bodies, pins, masses and gravity."""
    material, mat = _material(rd, data)
    section = _section(rd, data)
    ground, ground_points = _ground(rd, data)
    target_body, target_point = _target(rd, data)
    flex = data.get("flexures")
    if not (isinstance(flex, list) and flex):
        rd.fail("flexures", flex, "must be a non-empty array of tables [[flexures]]")
    specs = [_flexure_spec(rd, f, k, section) for k, f in enumerate(flex)]
    density = parse_density(mat, rd.fail)
    body_points, body_masses = _bodies(rd, data, density, section.depth)
    raw_pins = data.get("pins", [])
    if not isinstance(raw_pins, list):
        rd.fail("pins", raw_pins, "must be an array of tables [[pins]]")
    pins = [_pin_spec(rd, p, k) for k, p in enumerate(raw_pins)]
    mech = assemble(
        specs,
        ground,
        ground_points,
        material,
        target_body,
        target_point,
        source=source,
        body_points=body_points,
        pin_specs=pins,
    )
    for bname in body_masses:
        if bname not in mech.bodies or bname == mech.ground:
            rd.fail(
                f"bodies.{bname}.mass",
                bname,
                "mass data for the ground or for a body no "
                f"flexure or pin holds; moving bodies are {mech.moving_bodies}",
            )
    return dataclasses.replace(
        mech, inertia=MassData(density, parse_gravity(data, rd.fail), body_masses)
    )


def _load_case(rd: TableReader, c: Any, k: int, mech: Mechanism) -> LoadCase:
    """One ``[[load_cases]]`` entry (a single load, or ``loads`` combined) on ``mech``."""
    c = rd.item_table(c, f"load_cases[{k}]")
    lname = rd.value(c, LOAD_CASES["name"], f"load_cases[{k}].")
    where = f"load_cases.{lname}."
    spec = LOAD_CASES["levels"]
    levels = c.get("levels", spec.default)
    if (
        isinstance(levels, bool)
        or not isinstance(levels, int)
        or not spec.minimum <= levels <= spec.maximum
    ):
        rd.fail(
            f"{where}levels",
            levels,
            f"must be an integer from {spec.minimum} to {spec.maximum} (each of the "
            f"levels - 1 load increments takes at least one of the solver's "
            f"{spec.maximum} sub-steps)",
        )
    target_body, target_point = mech.target_body, mech.target_point
    if "loads" in c:
        rd.known_keys(c, LOAD_CASES, where, "combined")
        comps = tuple(
            _load_component(
                rd,
                rd.item_table(x, f"{where}loads[{i}]"),
                f"{where}loads[{i}].",
                target_body,
                target_point,
                LOAD_COMPONENTS,
            )
            for i, x in enumerate(rd.array(c, "loads", where, "load tables"))
        )
        if not comps:
            rd.fail(f"{where}loads", [], "must contain at least one load")
    else:
        comps = (
            _load_component(
                rd,
                c,
                where,
                target_body,
                target_point,
                LOAD_CASES,
                "single",
            ),
        )
    drives = [comp for comp in comps if isinstance(comp, Displacement)]
    if len(drives) > 1:
        rd.fail(
            f"{where}loads",
            len(drives),
            "a load case prescribes the motion of one point at most (one kind = 'displacement')",
        )
    for comp in comps:
        if comp.body not in mech.bodies:
            rd.fail(f"{where}body", comp.body, f"unknown body; bodies are {list(mech.bodies)}")
        if comp.body == mech.ground:
            rd.fail(f"{where}body", comp.body, "a load on the ground does nothing")
    return LoadCase(lname, comps, levels, parse_time_law(c, where, rd.fail))


def _load_cases(rd: TableReader, data: dict, mech: Mechanism) -> list[LoadCase]:
    """Every ``[[load_cases]]`` entry, names unique."""
    raw_cases = data.get("load_cases", [])
    if not isinstance(raw_cases, list) or not raw_cases:
        rd.fail("load_cases", raw_cases, "must be a non-empty array of tables [[load_cases]]")
    cases = []
    for k, c in enumerate(raw_cases):
        case = _load_case(rd, c, k, mech)
        if any(lc.name == case.name for lc in cases):
            rd.fail("load_cases.name", case.name, "duplicate load case name")
        cases.append(case)
    return cases


def _refuse_dangling_bodies(rd: TableReader, mech: Mechanism, cases: list[LoadCase]) -> None:
    """A body held by one flexure only, unloaded and not the target, does nothing."""
    loaded = {c.body for lc in cases for c in lc.components} | {mech.target_body}
    links = Counter(b for link in (*mech.flexures, *mech.pins) for b in link.bodies)
    for b in mech.moving_bodies:
        if links[b] == 1 and b not in loaded:
            rd.fail(
                "flexures",
                b,
                f"body {b!r} is dangling: held by one flexure, not loaded and not the target",
            )


def _request(rd: TableReader, data: dict) -> tuple[tuple, list]:
    """``[request]``: model ids (text, parsed by the model catalogue when used) and outputs."""
    req = rd.table(data, "request", "", required=False)
    rd.known_keys(req, REQUEST, "request.")
    models = tuple(rd.array(req, "models", "request.", "model names"))
    for m in models:
        if not isinstance(m, str):
            rd.fail("request.models", m, 'expected a model id string such as "beam:20"')
    outputs = rd.array(req, "outputs", "request.", "output names")
    for o in outputs:
        if not isinstance(o, str) or o not in OUTPUTS:
            rd.fail("request.outputs", o, f"unknown output; expected some of {sorted(OUTPUTS)}")
    return models, outputs


def _measurements(rd: TableReader, data: dict, cases: list[LoadCase]) -> tuple[Measurement, ...]:
    """``[[measurements]]``: each file read (relative to the scene file's folder) and checked
    against its load case; a missing or bad file is refused naming the entry."""
    out = []
    for k, m in enumerate(rd.array(data, "measurements", "", "tables [[measurements]]")):
        where = f"measurements[{k}]."
        m = rd.item_table(m, f"measurements[{k}]")
        rd.known_keys(m, MEASUREMENTS, where)
        name = rd.value(m, MEASUREMENTS["load_case"], where)
        case = next((c for c in cases if c.name == name), None)
        if case is None:
            rd.fail(
                f"{where}load_case",
                name,
                f"unknown load case; the scene has {[c.name for c in cases]}",
            )
        file = m.get("file")
        if not isinstance(file, str) or not file.strip():
            rd.fail(f"{where}file", file, "must be the path of a CSV file")
        path = Path(rd.source).parent / file  # an absolute path stays as it is
        try:
            out.append(read_measurement(path, case))
        except SceneError as exc:
            where_in = "" if exc.field == "file" else f"{exc.field} = {exc.value!r}: "
            rd.fail(f"{where}file", file, f"{path}: {where_in}{exc.reason}")
    return tuple(out)


def parse_scene(
    data: dict, source: str, default_name: str = "scene", keep_data: bool = True
) -> Scene:
    """Build and check a Scene from parsed TOML ``data`` read from ``source``; with
    ``keep_data`` (default) the scene keeps ``data`` for :meth:`Scene.with_changes` (a
    sweep's points keep none: they change by the sweep's axes).

    In passes, each a function named after what it reads: the mechanism
    (material, section, ground, target, flexures, bodies, pins, masses), the
    load cases on it, the bodies they leave dangling, the request, the measurements. Every
    value is checked where it is read (:class:`SceneError` names the field).
    """
    rd = TableReader(source)
    rd.known_keys(data, SCENE, "")
    name = _scene_name(rd, data.get("name", default_name))
    mech = _mechanism(rd, data, source)
    cases = _load_cases(rd, data, mech)
    _refuse_dangling_bodies(rd, mech, cases)
    models, outputs = _request(rd, data)
    return Scene(
        name,
        str(data.get("description", "")),
        mech,
        tuple(cases),
        models,
        frozenset(outputs),
        source,
        _measurements(rd, data, cases),
        data if keep_data else None,
    )


def load_scene(name_or_path: str | Path) -> Scene:
    """Load a built-in scene by name, or a scene file by path.

    Raises
    ------
    SceneError
        If the file is missing, is not valid TOML, or has a bad field.
    """
    source, data, stem = read_scene_data(name_or_path)
    return parse_scene(data, source, default_name=stem)


def read_scene_data(name_or_path: str | Path) -> tuple[str, dict, str]:
    """(source label, parsed TOML, file stem) of a built-in scene or a scene file, unchecked.

    For callers that edit a scene's fields before :func:`parse_scene` checks
    them (``flexval sweep``). Raises SceneError for a missing, unreadable or
    malformed file.
    """
    text_id = str(name_or_path)
    if text_id in BUILTIN_SCENES:
        res = resources.files("flexval.geometry").joinpath("scenes", f"{text_id}.toml")
        source, text, stem = f"<builtin {text_id}>", res.read_text(encoding="utf-8"), text_id
    else:
        path = Path(text_id)
        if not path.is_file():
            raise SceneError(
                text_id,
                "scene",
                text_id,
                f"no such file, and not a built-in scene {list(BUILTIN_SCENES)}",
            )
        source, text, stem = str(path), read_utf8(path), path.stem
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(source, "toml", None, f"malformed TOML: {exc}") from None
    except RecursionError:
        raise SceneError(
            source,
            "toml",
            None,
            "arrays or tables nested too deeply to read (a scene needs at most 3 levels)",
        ) from None
    return source, data, stem
