"""Estimates before work: a command's memory and time from its scene and options.

Every command that runs models asks :func:`check_models` before it starts:
each model family that can be costly declares a
:attr:`~flexval.reducedmodels.catalogue.Family.cost` (the continuum: unknowns
and factor fill from the mesh level, :mod:`flexval.validation.continuum.cost`),
and a path whose estimated peak memory exceeds what the machine has is
refused as bad input (exit 2) naming the estimate, the machine's figure and
the highest resolution that fits. Work estimated to take longer than
:data:`LONG_SECONDS` (or the environment variable :data:`LONG_ENV`) prints its
estimate first, and shows its progress (the report's bar, the sweep's lines, and
``flexval run``'s line per converged load level).

The machine's figure is the memory available now (``MemAvailable``, via
psutil), lowered to the room left under a cgroup limit (a container's cap),
or the budget set in the environment variable :data:`MEMORY_ENV`.

Units: bytes, s.
"""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Iterable
from pathlib import Path

from flexval.geometry import SceneError

MEMORY_ENV = "FLEXVAL_MEMORY"
"""Memory budget overriding the machine's figure: bytes, or a number with K, M, G or T
(powers of 1024), e.g. ``FLEXVAL_MEMORY=4G``."""
HEADROOM = 1.25
"""A path fits when this many times its estimated peak memory fits: the estimate is 0.8 to
1.12 of the measured peak on the sizes it was fitted to and at least 20 % low beyond them
(open_chain at continuum:4)."""
LONG_SECONDS = 60.0
"""Work estimated to take longer than this (s) prints its estimate before it starts and
shows its progress."""
LONG_ENV = "FLEXVAL_LONG_SECONDS"
"""Overrides :data:`LONG_SECONDS` (s, a number >= 0; 0 shows every estimate and progress)."""
_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def long_seconds() -> float:
    """The threshold (s) above which work prints its estimate and shows progress:
    :data:`LONG_ENV` if set (SceneError if it is not a number >= 0), else :data:`LONG_SECONDS`."""
    text = os.environ.get(LONG_ENV)
    if text is None:
        return LONG_SECONDS
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not (value >= 0.0 and value != float("inf")):
        raise SceneError("<environment>", LONG_ENV, text, "expected a number of seconds >= 0")
    return value


def _parse_size(text: str) -> int:
    """Bytes of ``text`` (``123``, ``500M``, ``4G``, ``1.5T``; SceneError if malformed)."""
    match = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([KMGT]?)i?B?\s*", text, re.IGNORECASE)
    value = float(match.group(1)) * _UNITS[match.group(2).upper()] if match else 0.0
    if not value >= 1:
        raise SceneError(
            "<environment>", MEMORY_ENV, text, "expected a memory size such as 4G, 500M or bytes"
        )
    return int(value)


def _cgroup_room() -> int | None:
    """Bytes left under the cgroup v2 limit of this process (None: no limit, or unreadable)."""
    try:
        line = Path("/proc/self/cgroup").read_text().splitlines()[0]
        folder = Path("/sys/fs/cgroup") / line.split("::", 1)[1].lstrip("/")
        limit = (folder / "memory.max").read_text().strip()
        if limit == "max":
            return None
        return max(0, int(limit) - int((folder / "memory.current").read_text()))
    except (OSError, IndexError, ValueError):
        return None


def available_memory() -> tuple[int, str]:
    """(bytes, what they are) of the memory a command may use."""
    text = os.environ.get(MEMORY_ENV)
    if text:
        return _parse_size(text), f"the budget ${MEMORY_ENV}"
    try:
        import psutil

        free, what = int(psutil.virtual_memory().available), "the memory available"
    except ImportError:
        meminfo = Path("/proc/meminfo").read_text()
        free = int(re.search(r"MemAvailable:\s+(\d+) kB", meminfo).group(1)) * 1024
        what = "the memory available (MemAvailable)"
    room = _cgroup_room()
    if room is not None and room < free:
        return room, "the room under this process's cgroup memory limit"
    return free, what


def gigabytes(size: float) -> str:
    """``size`` bytes as text in GB (10^9 bytes), e.g. ``'2.0 GB'``, ``'3.5e+03 GB'``."""
    gb = size / 1e9
    return f"{gb:.2g} GB" if gb < 1e3 else f"{gb:.2e} GB"


def duration(seconds: float) -> str:
    """``seconds`` as text: ``'40 s'``, ``'12 min'``, ``'3.2 h'``, ``'5.1 days'``."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.3g} days"


def _fitting(mechanism, spec, levels: int | None, room: float, jobs: int):
    """The finest resolution of ``spec``'s family below its own whose path fits ``room``
    (the spec and its cost), or None."""
    family, res = spec.model_family, spec.model_family.resolution
    if res is None or spec.resolution is None:
        return None
    for r in range(spec.resolution - 1, res.low - 1, -1):
        lower = spec.with_resolution(r)
        cost = family.cost(mechanism, lower, levels)
        if HEADROOM * cost.bytes * jobs <= room:
            return lower, cost
    return None


def check_models(
    jobs_of: Iterable[tuple[object, object, int | None]],
    source: str,
    field: str,
    parallel: int = 1,
    quiet: bool = False,
) -> float:
    """Refuse a model whose load path would not fit in memory; the estimated total time.

    Parameters
    ----------
    jobs_of : iterable of (Mechanism, ModelSpec, levels or None)
        The load paths the command will trace (one per model and load case).
    source, field : str
        Where the models were asked for (the SceneError names them).
    parallel : int
        Paths traced at once (worker processes), each with its own memory.
    quiet : bool
        Do not print the time estimate.

    Returns
    -------
    float
        The estimated time of all the paths, s (0 for families without a cost).

    Raises
    ------
    SceneError
        For the first path whose peak memory (times ``parallel`` and
        :data:`HEADROOM`) exceeds :func:`available_memory`.
    """
    room = None
    total, worst = 0.0, None
    for mechanism, spec, levels in jobs_of:
        family = spec.model_family
        if family.cost is None:
            continue
        cost = family.cost(mechanism, spec, levels)
        total += cost.seconds
        if room is None:
            room, what = available_memory()
        if HEADROOM * cost.bytes * parallel > room:
            times = f" x {parallel} workers" if parallel > 1 else ""
            fit = _fitting(mechanism, spec, levels, room, parallel)
            res = family.resolution
            lower = (
                f"use a lower {res.name}: {fit[0].id} needs about {gigabytes(fit[1].bytes)}"
                if fit is not None
                else f"no {res.name} of {family.name} fits"
                if res is not None
                else ""
            )
            if parallel > 1:
                lower += ", or fewer workers"
            raise SceneError(
                source,
                field,
                spec.id,
                f"needs about {gigabytes(cost.bytes)}{times} of memory ({cost.size}) but "
                f"{what} is {gigabytes(room)}; {lower}",
            )
        if worst is None or cost.seconds > worst[1].seconds:
            worst = (spec, cost)
    if total > long_seconds() and not quiet:
        spec, cost = worst
        print(
            f"estimate: about {duration(total)} of model runs (the longest: {spec.id}, "
            f"{duration(cost.seconds)} a path, {cost.size}, peak {gigabytes(cost.bytes)})",
            file=sys.stderr,
            flush=True,
        )
    return total
