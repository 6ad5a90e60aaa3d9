"""Mass data of a scene: material density, rigid-body inertia, gravity.

Units (the mm-N-s system): density in t/mm^3 (PLA: about 1.24e-9), masses
in t (1 t = 1000 kg), inertias in t mm^2, gravity in mm/s^2 (Earth:
9810 mm/s^2), so that mass x acceleration is in N.

Scene fields read here (all optional; a scene without them is massless and
weightless, and static results are unchanged)::

    [material]  density = 1.24e-9                 # flexures' mass, t/mm^3
    [gravity]   acceleration = [0.0, -9810.0]     # mm/s^2
    [[bodies]]  name = "4"
                mass = 2.0e-6                     # t, and
                inertia = 1.0e-4                  # t mm^2 about the centre of mass, and
                center_of_mass = [20.0, 15.0]     # mm
             or outline = [[x, y], ...]           # polygon (mm); needs material.density
                depth = 5.0                       # out-of-plane, mm (default: section depth)

A body without mass data is massless: static runs do not need its mass,
dynamic runs and modal analyses refuse it by name.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import did_you_mean
from .fields import ABSENT, Field, Table
from .magnitudes import SMALLEST_NORMAL

PLA_DENSITY = 1.24e-9
"""Density of PLA, t/mm^3 (1240 kg/m^3): the default of studies on scenes without mass data."""
MIN_DENSITY = 1e-13
"""Smallest flexure density accepted, t/mm^3 (0.1 kg/m^3): below the lightest aerogels
(about 1e-12), and far above the 1e-300 that makes natural frequencies of 1e148 Hz."""
MAX_DENSITY = 1e-3
"""Largest accepted density, t/mm^3: a value in kg/m^3 or g/cm^3 by mistake is above it."""
MASS_LIMIT = 1e12
"""Largest accepted mass (t), inertia (t mm^2) or outline depth (mm)."""
GRAVITY_LIMIT = 1e9
"""Largest accepted gravity component, mm/s^2."""

DENSITY_FIELD = Field(
    "density",
    "number",
    "density of the flexures' material (PLA: about 1.24e-9, steel 7.85e-9); "
    "needed by body outlines",
    unit="t/mm³",
    default=ABSENT,
    positive=True,
    minimum=MIN_DENSITY,
    maximum=MAX_DENSITY,
)
"""``material.density``: optional; without it the flexures are massless."""

MASS_FIELDS = (
    Field(
        "mass",
        "number",
        "mass of the body; give mass, inertia and center_of_mass together",
        unit="t",
        default=ABSENT,
        positive=True,
        limit=MASS_LIMIT,
    ),
    Field(
        "inertia",
        "number",
        "polar moment of inertia about the centre of mass (≥ 0)",
        unit="t mm²",
        default=ABSENT,
        limit=MASS_LIMIT,
    ),
    Field(
        "center_of_mass",
        "point",
        "centre of mass in the undeformed configuration",
        unit="mm",
        default=ABSENT,
    ),
    Field(
        "outline",
        "points",
        "the body as a simple polygon of at least 3 points, of material.density: "
        "instead of mass, inertia and center_of_mass",
        unit="mm",
        default=ABSENT,
    ),
    Field(
        "depth",
        "number",
        "out-of-plane depth of an outline",
        unit="mm",
        default=ABSENT,
        default_text="[section] depth",
        positive=True,
        limit=MASS_LIMIT,
    ),
)
"""Fields of a ``[[bodies]]`` table that describe its mass."""

MASS_KEYS = frozenset(f.name for f in MASS_FIELDS)
"""Names of :data:`MASS_FIELDS`."""

GRAVITY = Table(
    "gravity",
    "Optional: a uniform gravity field. Without it the mechanism is weightless.",
    (
        Field(
            "acceleration",
            "point",
            "gravitational acceleration [gx, gy] (Earth, downwards: [0.0, -9810.0])",
            unit="mm/s²",
            limit=GRAVITY_LIMIT,
        ),
    ),
)
"""The ``[gravity]`` table."""

GRAVITY_KEYS = GRAVITY.keys()
"""Fields of the ``[gravity]`` table."""


@dataclass(frozen=True)
class RigidMass:
    """Mass properties of one rigid body.

    Attributes
    ----------
    mass : float
        m, t.
    inertia : float
        Polar moment of inertia about the centre of mass, t mm^2.
    center_of_mass : ndarray, shape (2,)
        Position of the centre of mass in the undeformed configuration, mm.
    """

    mass: float
    inertia: float
    center_of_mass: np.ndarray


@dataclass(frozen=True)
class MassData:
    """All mass data of a scene (empty: massless and weightless).

    Attributes
    ----------
    density : float or None
        Flexure material density, t/mm^3 (None: massless flexures).
    gravity : ndarray (2,) or None
        Gravitational acceleration, mm/s^2 (None: no weight).
    bodies : dict of str -> RigidMass
        Rigid bodies with mass data; the others are massless.
    """

    density: float | None = None
    gravity: np.ndarray | None = None
    bodies: dict[str, RigidMass] = field(default_factory=dict)

    @property
    def declared(self) -> bool:
        """True if the scene gives any mass or gravity data."""
        return self.density is not None or self.gravity is not None or bool(self.bodies)

    def massless_bodies(self, moving_bodies: list[str]) -> list[str]:
        """The moving bodies without mass data, in order."""
        return [b for b in moving_bodies if b not in self.bodies]

    def transformed(self, angle: float, shift: np.ndarray) -> MassData:
        """The same data for the mechanism rotated by ``angle`` (rad) about the origin and
        shifted by ``shift`` (mm): centres of mass move with it, gravity turns with it."""
        c, s = math.cos(angle), math.sin(angle)
        rot = np.array([[c, -s], [s, c]])
        bodies = {
            n: RigidMass(b.mass, b.inertia, rot @ b.center_of_mass + shift)
            for n, b in self.bodies.items()
        }
        gravity = None if self.gravity is None else rot @ self.gravity
        return MassData(self.density, gravity, bodies)


def polygon_properties(outline: np.ndarray) -> tuple[float, np.ndarray, float]:
    """Area (mm^2), centroid (mm) and polar second moment about the centroid (mm^4).

    Green's theorem on the closed polygon ``outline`` (m, 2); either
    orientation. The polygon must be simple (the formulas then hold
    exactly). Raises ValueError if its area is zero.
    """
    x, y = outline[:, 0], outline[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = 0.5 * cross.sum()
    if abs(area) <= 1e-12 * float(np.ptp(outline, axis=0).max()) ** 2:
        raise ValueError("polygon has zero area")
    cx = ((x + xn) * cross).sum() / (6.0 * area)
    cy = ((y + yn) * cross).sum() / (6.0 * area)
    polar_origin = ((x * x + x * xn + xn * xn + y * y + y * yn + yn * yn) * cross).sum() / 12.0
    polar = polar_origin / math.copysign(1.0, area) - abs(area) * (cx * cx + cy * cy)
    return abs(area), np.array([cx, cy]), polar


Fail = Callable[[str, Any, str], None]


def _positive(fail: Fail, field_name: str, value: Any, allow_zero: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        fail(field_name, value, "must be a finite number")
    if value < 0.0 or (value == 0.0 and not allow_zero):
        fail(field_name, value, "must be positive" if not allow_zero else "must not be negative")
    if value != 0.0 and value < SMALLEST_NORMAL:
        fail(
            field_name,
            value,
            f"is below the smallest normal double ({SMALLEST_NORMAL:g}): "
            "masses and frequencies computed from it lose all precision or vanish",
        )
    if value > MASS_LIMIT:
        fail(field_name, value, f"absurd magnitude (> {MASS_LIMIT:g})")
    return float(value)


def _point(fail: Fail, field_name: str, value: Any) -> np.ndarray:
    if not (
        isinstance(value, list)
        and len(value) == 2
        and all(
            not isinstance(c, bool) and isinstance(c, (int, float)) and math.isfinite(c)
            for c in value
        )
    ):
        fail(field_name, value, "must be a point [x, y] in mm")
    return np.array(value, float)


def parse_density(material: dict, fail: Fail) -> float | None:
    """``material.density`` (t/mm^3) if given; it must be between 1e-13 and 1e-3
    (a value in kg/m^3 or g/cm^3 by mistake is caught by this bound: steel is 7.85e-9)."""
    if "density" not in material:
        return None
    value = _positive(fail, "material.density", material["density"])
    if value < DENSITY_FIELD.minimum:
        fail(
            "material.density",
            value,
            f"below {MIN_DENSITY:g} t/mm^3 (0.1 kg/m^3, under the lightest aerogels'): no "
            "solid flexure is that light; is this in another unit?",
        )
    if value > DENSITY_FIELD.maximum:
        fail(
            "material.density",
            value,
            "t/mm^3 expected (PLA is about 1.24e-9); is this in kg/m^3 or g/cm^3?",
        )
    return value


def parse_gravity(data: dict, fail: Fail) -> np.ndarray | None:
    """``[gravity] acceleration = [gx, gy]`` (mm/s^2) if the table is given."""
    if "gravity" not in data:
        return None
    table = data["gravity"]
    if not isinstance(table, dict):
        fail("gravity", table, "must be a table with acceleration = [gx, gy] in mm/s^2")
    for key in table:
        if key not in GRAVITY_KEYS:
            fail(
                f"gravity.{key}",
                table[key],
                f"unknown field{did_you_mean(key, GRAVITY_KEYS)}; expected one of "
                f"{sorted(GRAVITY_KEYS)}",
            )
    if "acceleration" not in table:
        fail("gravity.acceleration", None, "missing value [gx, gy] in mm/s^2")
    g = _point(fail, "gravity.acceleration", table["acceleration"])
    if np.abs(g).max() > GRAVITY_LIMIT:
        fail(
            "gravity.acceleration",
            table["acceleration"],
            f"absurd magnitude (> {GRAVITY_LIMIT:g} mm/s^2)",
        )
    return g


def parse_body_mass(
    body: dict, where: str, density: float | None, default_depth: float, fail: Fail
) -> RigidMass | None:
    """The mass of one ``[[bodies]]`` table, or None if it gives none.

    Either ``mass``, ``inertia`` and ``center_of_mass`` together, or an
    ``outline`` polygon (with ``depth``, default ``default_depth``) of the
    scene's ``material.density``; ``where`` is the field prefix
    (``bodies.NAME.``).
    """
    explicit = [k for k in ("mass", "inertia", "center_of_mass") if k in body]
    if "outline" in body:
        if explicit:
            fail(
                f"{where}{explicit[0]}",
                body[explicit[0]],
                "give either outline (+ depth) or mass, inertia and center_of_mass, not both",
            )
        if density is None:
            fail(
                f"{where}outline",
                body["outline"],
                "an outline needs material.density (t/mm^3) to give a mass",
            )
        raw = body["outline"]
        if not (isinstance(raw, list) and len(raw) >= 3):
            fail(f"{where}outline", raw, "must be a polygon of at least 3 points [x, y] in mm")
        outline = np.array([_point(fail, f"{where}outline[{i}]", p) for i, p in enumerate(raw)])
        depth = (
            _positive(fail, f"{where}depth", body["depth"]) if "depth" in body else default_depth
        )
        try:
            area, centroid, polar = polygon_properties(outline)
        except ValueError as exc:
            fail(f"{where}outline", raw, str(exc))
        return RigidMass(density * depth * area, density * depth * polar, centroid)
    if "depth" in body:
        fail(f"{where}depth", body["depth"], "depth is only used with an outline")
    if not explicit:
        return None
    if len(explicit) < 3:
        missing = [k for k in ("mass", "inertia", "center_of_mass") if k not in body]
        fail(
            f"{where}{missing[0]}",
            None,
            "mass, inertia (about the centre of mass) and center_of_mass go together",
        )
    return RigidMass(
        _positive(fail, f"{where}mass", body["mass"]),
        _positive(fail, f"{where}inertia", body["inertia"], allow_zero=True),
        _point(fail, f"{where}center_of_mass", body["center_of_mass"]),
    )
