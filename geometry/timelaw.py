"""Time laws of load cases for dynamic runs: the paper's Eq. 15 ramp, or a linear one.

A load case may say how its load factor lambda (0..1) grows in time
(seconds)::

    [[load_cases]]
    name = "f-"
    ...
    ramp = "eq15"        # or "linear"
    t0 = 0.0             # s: lambda = 0 until t0
    t1 = 2.0             # s: lambda = 1 from t1 on
    end_time = 3.0       # s: default duration of a dynamic run (default 1.25 t1)

Static runs ignore these fields.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .fields import ABSENT, Field

TIME_LIMIT = 1e9
"""Largest time (s) a time law may name."""


def eq15_ramp(t: float, t0: float, t1: float) -> float:
    """The paper's Eq. 15 smooth step, 0 for t <= t0 and 1 for t >= t1 (times in s).

    lambda = s^3 (10 - 15 s + 6 s^2) with s = (t - t0)/(t1 - t0): its first and
    second derivatives vanish at both ends, so the load starts and stops
    without a jerk.
    """
    if t <= t0:
        return 0.0
    if t >= t1:
        return 1.0
    s = (t - t0) / (t1 - t0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s * s)


def linear_ramp(t: float, t0: float, t1: float) -> float:
    """Load factor rising linearly from 0 at t0 to 1 at t1 (s), constant outside."""
    return min(1.0, max(0.0, (t - t0) / (t1 - t0)))


RAMPS = {"eq15": eq15_ramp, "linear": linear_ramp}

TIME_LAW_FIELDS = (
    Field(
        "ramp",
        "choice",
        "how the load factor grows in a dynamic run: the paper's Eq. 15 smooth step or a "
        "straight line (static runs ignore the time law)",
        default="eq15",
        choices=tuple(RAMPS),
    ),
    Field(
        "t0",
        "number",
        "load factor 0 until this time",
        unit="s",
        default=0.0,
        minimum=0.0,
        maximum=TIME_LIMIT,
    ),
    Field(
        "t1",
        "number",
        "load factor 1 from this time on; required once any time-law field is given; > t0",
        unit="s",
        default=ABSENT,
        minimum=0.0,
        maximum=TIME_LIMIT,
    ),
    Field(
        "end_time",
        "number",
        "default duration of a dynamic run",
        unit="s",
        default=ABSENT,
        default_text="1.25 t1",
        minimum=0.0,
        maximum=TIME_LIMIT,
    ),
)
"""Fields of a ``[[load_cases]]`` table that set its time law."""

TIME_LAW_KEYS = frozenset(f.name for f in TIME_LAW_FIELDS)
"""Names of :data:`TIME_LAW_FIELDS`."""


@dataclass(frozen=True)
class TimeLaw:
    """lambda(t): ``ramp`` ('eq15' or 'linear') from t0 to t1 (s); ``end_time`` (s) or None."""

    ramp: str = "eq15"
    t0: float = 0.0
    t1: float = 1.0
    end_time: float | None = None

    def __call__(self, t: float) -> float:
        return RAMPS[self.ramp](t, self.t0, self.t1)

    @property
    def duration(self) -> float:
        """The run's default end time, s: ``end_time``, else 1.25 t1 (a quarter to settle)."""
        return self.end_time if self.end_time is not None else 1.25 * self.t1


def parse_time_law(case: dict, where: str, fail: Callable[[str, Any, str], None]) -> TimeLaw | None:
    """The time law of one ``[[load_cases]]`` table (``where`` is its field prefix), or None."""
    if not TIME_LAW_KEYS & set(case):
        return None
    ramp = case.get("ramp", TIME_LAW_FIELDS[0].default)
    if ramp not in RAMPS:
        fail(f"{where}ramp", ramp, f"must be one of {sorted(RAMPS)}")
    values = {}
    for f in TIME_LAW_FIELDS[1:]:
        key = f.name
        v = case.get(key, f.default)
        if v is None:
            if key == "t1":
                fail(f"{where}t1", None, "a ramp needs its end time t1 (s)")
            values[key] = None
            continue
        if (
            isinstance(v, bool)
            or not isinstance(v, (int, float))
            or not math.isfinite(v)
            or v < f.minimum
            or v > f.maximum
        ):
            fail(f"{where}{key}", v, "must be a time in s, from 0 to 1e9")
        values[key] = float(v)
    if values["t1"] <= values["t0"]:
        fail(f"{where}t1", values["t1"], f"must be later than t0 = {values['t0']:g} s")
    if values["end_time"] is not None and values["end_time"] <= 0.0:
        fail(f"{where}end_time", values["end_time"], "must be positive")
    return TimeLaw(ramp, values["t0"], values["t1"], values["end_time"])
