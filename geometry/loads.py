"""Load cases: dead moments and forces on bodies, and prescribed motions, ramped from zero.

A load case is a set of components all scaled by one load factor
lambda in [0, 1]; the requested load levels are ``levels`` equally spaced
values of lambda from 0 to 1 (default 11). Forces keep their direction
(dead loads). A :class:`Displacement` prescribes a body point's motion
(displacement control): its components are reached at lambda = 1, and the
force and moment that hold them are the output. Units: N, N mm, mm, rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .fields import ABSENT, Field
from .kinematics import rotation
from .timelaw import TimeLaw

DEFAULT_LEVELS = 11
MAX_LOAD_SUBSTEPS = 20_000
"""The solver's cap on load sub-steps of one load path (``SolverSettings.max_substeps``).

Each of a load case's ``levels - 1`` increments takes at least one sub-step, so a load
case may have at most this many levels; more would run long and then stop at the cap."""

LOAD_KINDS = ("moment", "force", "displacement")
LOAD_VALUE_LIMIT = 1e9
"""Largest magnitude of a load's value (N or N mm) a scene may give."""
DISPLACEMENT_LIMIT = 1e6
"""Largest prescribed displacement (mm) a scene may give."""
ROTATION_LIMIT_DEG = 3600.0
"""Largest prescribed rotation (deg, ten turns) a scene may give."""

LOAD_FIELDS = (
    Field("kind", "choice", "what the load is", choices=LOAD_KINDS),
    Field(
        "value",
        "number",
        "full value at load factor 1: N mm for a moment (counterclockwise positive), "
        "N for a force (may be negative); not for a displacement",
        unit="N or N mm",
        limit=LOAD_VALUE_LIMIT,
        default=ABSENT,
        default_text="required for a moment or a force",
    ),
    Field(
        "body",
        "name",
        "the loaded body",
        default=ABSENT,
        default_text="the target body",
    ),
    Field(
        "point",
        "point",
        "point of application in the undeformed configuration (force or displacement); "
        "it moves with the body",
        unit="mm",
        default=ABSENT,
        default_text="the target point",
    ),
    Field(
        "angle_deg",
        "number",
        "direction of a force, from the x axis, counterclockwise (required for a force); "
        "the force keeps it (dead load). For a displacement: the direction of its dx "
        "(default 0, the x axis)",
        unit="deg",
        default=ABSENT,
    ),
    Field(
        "dx",
        "number",
        "displacement only: the point's prescribed motion along x (or along angle_deg) at "
        "full load; left out: free",
        unit="mm",
        limit=DISPLACEMENT_LIMIT,
        default=ABSENT,
    ),
    Field(
        "dy",
        "number",
        "displacement only: the point's prescribed motion along y (or normal to angle_deg, "
        "counterclockwise) at full load; left out: free",
        unit="mm",
        limit=DISPLACEMENT_LIMIT,
        default=ABSENT,
    ),
    Field(
        "rotation_deg",
        "number",
        "displacement only: the body's prescribed rotation at full load, counterclockwise; "
        "left out: free",
        unit="deg",
        limit=ROTATION_LIMIT_DEG,
        default=ABSENT,
    ),
)
"""Fields of one load: a ``[[load_cases]]`` entry of a single load, or an element of its
``loads`` array."""

LEVELS_FIELD = Field(
    "levels",
    "integer",
    "number of equally spaced load levels from 0 to full load (each of the levels - 1 "
    "increments takes at least one solver sub-step)",
    default=DEFAULT_LEVELS,
    minimum=2,
    maximum=MAX_LOAD_SUBSTEPS,
)


@dataclass(frozen=True)
class Moment:
    """A moment ``value`` (N mm, counterclockwise positive) on ``body``."""

    body: str
    value: float

    def transformed(self, angle: float, shift: np.ndarray) -> Moment:
        """The same moment for a rigidly moved mechanism (unchanged)."""
        return self


@dataclass(frozen=True)
class Force:
    """A dead force of magnitude ``value`` (N, may be negative) along ``angle`` (rad).

    It acts at ``point`` (mm, in the undeformed configuration) of ``body`` and
    follows that material point as the body moves.
    """

    body: str
    point: np.ndarray
    angle: float
    value: float

    @property
    def vector(self) -> np.ndarray:
        """Force vector (N) at full load."""
        return self.value * np.array([np.cos(self.angle), np.sin(self.angle)])

    def transformed(self, angle: float, shift: np.ndarray) -> Force:
        """The same force for a mechanism rotated by ``angle`` (rad) and shifted (mm)."""
        p = rotation(angle) @ np.asarray(self.point, float) + shift
        return Force(self.body, p, self.angle + angle, self.value)


@dataclass(frozen=True)
class Displacement:
    """A prescribed motion of the material point ``point`` of ``body`` (displacement control).

    At load factor lambda the point has moved by lambda ``dx`` along the
    frame direction ``angle`` and lambda ``dy`` normal to it (mm), and the body
    has turned by lambda ``rotation`` (rad); a component given as None is
    free. The force and moment that impose the motion are the load path's
    output (:attr:`flexval.reducedmodels.LoadPath.drive_reactions`).

    Attributes
    ----------
    body : str
    point : array (2,)
        The driven point in the undeformed configuration, mm.
    dx, dy : float or None
        Prescribed motion at full load along the frame's axes, mm.
    rotation : float or None
        Prescribed rotation at full load, rad.
    angle : float
        The frame's direction (its dx axis) from the x axis, rad.
    """

    body: str
    point: np.ndarray
    dx: float | None = None
    dy: float | None = None
    rotation: float | None = None
    angle: float = 0.0

    @property
    def prescribed(self) -> tuple[tuple[int, float], ...]:
        """(component, value at full load) of the prescribed components: 0 dx, 1 dy (mm),
        2 rotation (rad)."""
        values = (self.dx, self.dy, self.rotation)
        return tuple((k, float(v)) for k, v in enumerate(values) if v is not None)

    @property
    def axis(self) -> tuple[int, float]:
        """(component, value at full load) of the load factor's axis: the first prescribed
        component that moves (a component held at 0 moves nothing), or the first one if
        every component is held."""
        prescribed = self.prescribed
        return next(((k, v) for k, v in prescribed if v != 0.0), prescribed[0])

    @property
    def value(self) -> float:
        """The drive's value at full load along its :attr:`axis` (mm, or rad for a
        rotation)."""
        return self.axis[1]

    @property
    def unit(self) -> str:
        """Unit of :attr:`value`: 'mm', or 'rad' when the axis is the rotation."""
        return "rad" if self.axis[0] == 2 else "mm"

    def transformed(self, angle: float, shift: np.ndarray) -> Displacement:
        """The same drive for a mechanism rotated by ``angle`` (rad) and shifted (mm)."""
        p = rotation(angle) @ np.asarray(self.point, float) + shift
        return Displacement(self.body, p, self.dx, self.dy, self.rotation, self.angle + angle)


@dataclass(frozen=True)
class LoadCase:
    """A named proportional load case.

    Attributes
    ----------
    name : str
    components : tuple of Moment | Force | Displacement
        Loads at full value (load factor 1); at most one :class:`Displacement`.
    levels : int
        Number of equally spaced load levels from 0 to full load (>= 2).
    time_law : TimeLaw or None
        How the load grows in time in a dynamic run (:mod:`flexval.geometry.timelaw`);
        None: the run's command-line default.
    """

    name: str
    components: tuple
    levels: int = DEFAULT_LEVELS
    time_law: TimeLaw | None = None

    def factors(self, levels: int | None = None) -> np.ndarray:
        """Load factors 0 .. 1 of the requested levels."""
        return np.linspace(0.0, 1.0, levels or self.levels)

    @property
    def drive(self) -> Displacement | None:
        """The prescribed motion of a displacement-controlled case, or None."""
        return next((c for c in self.components if isinstance(c, Displacement)), None)

    @property
    def magnitude(self) -> float:
        """Signed full value of the load factor's axis (N, N mm, mm or rad), for tables and
        plots: the drive's :attr:`~Displacement.axis` where the case prescribes a motion,
        else the first load's value."""
        drive = self.drive
        return float(drive.value if drive is not None else self.components[0].value)

    @property
    def unit(self) -> str:
        """Unit of ``magnitude``: 'N' for a force, 'N mm' for a moment, 'mm' or 'rad' for a
        prescribed motion."""
        drive = self.drive
        if drive is not None:
            return drive.unit
        return "N" if isinstance(self.components[0], Force) else "N mm"

    def transformed(self, angle: float, shift: np.ndarray) -> LoadCase:
        """The load case for a rigidly moved mechanism."""
        return LoadCase(
            self.name,
            tuple(c.transformed(angle, shift) for c in self.components),
            self.levels,
            self.time_law,
        )
