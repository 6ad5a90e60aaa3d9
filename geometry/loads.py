"""Load cases: dead moments and forces on bodies, ramped proportionally from zero.

A load case is a set of components all scaled by one load factor
lambda in [0, 1]; the requested load levels are ``levels`` equally spaced
values of lambda from 0 to 1 (default 11). Forces keep their direction
(dead loads). Units: N, N mm, mm, rad.
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

LOAD_KINDS = ("moment", "force")
LOAD_VALUE_LIMIT = 1e9
"""Largest magnitude of a load's value (N or N mm) a scene may give."""

LOAD_FIELDS = (
    Field("kind", "choice", "what the load is", choices=LOAD_KINDS),
    Field(
        "value",
        "number",
        "full value at load factor 1: N mm for a moment (counterclockwise positive), "
        "N for a force (may be negative)",
        unit="N or N mm",
        limit=LOAD_VALUE_LIMIT,
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
        "point of application in the undeformed configuration (force only); it moves with the body",
        unit="mm",
        default=ABSENT,
        default_text="the target point",
    ),
    Field(
        "angle_deg",
        "number",
        "direction of a force, from the x axis, counterclockwise (force only; "
        "required for a force); the force keeps it (dead load)",
        unit="deg",
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
class LoadCase:
    """A named proportional load case.

    Attributes
    ----------
    name : str
    components : tuple of Moment | Force
        Loads at full value (load factor 1).
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
    def magnitude(self) -> float:
        """Signed full value of the first component (N or N mm), for tables and plots."""
        return float(self.components[0].value)

    @property
    def unit(self) -> str:
        """Unit of ``magnitude``: 'N' for a force, 'N mm' for a moment."""
        return "N" if isinstance(self.components[0], Force) else "N mm"

    def transformed(self, angle: float, shift: np.ndarray) -> LoadCase:
        """The load case for a rigidly moved mechanism."""
        return LoadCase(
            self.name,
            tuple(c.transformed(angle, shift) for c in self.components),
            self.levels,
            self.time_law,
        )
