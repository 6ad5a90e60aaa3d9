"""Measured load–displacement files (a test rig's CSV), read and checked against a load case.

A measurement file is CSV text (UTF-8, comma-separated) whose first row names
the columns:

``load``
    the load, in the load case's unit: N for a force case, N mm for a moment
    case; for a combined case the value of its first load (as ``flexval run``
    reports it). It has the sign of the case's full load (zero allowed) and is
    strictly monotonic down the file (increasing or decreasing).
``dx``, ``dy``
    the target point's displacement, mm (either or both).
``rotation``
    the target body's rotation, degrees, counterclockwise positive.
``<column>_std``
    the standard uncertainty of ``dx``, ``dy`` or ``rotation``, in its unit (> 0).

A header cell may carry its unit in brackets, ``load [N]``, ``dx [mm]``,
``rotation [deg]``: the unit is then checked against the case (a moment case
measured in N is refused); without one the units above are assumed. Blank
lines and lines whose first cell starts with ``#`` are skipped. Every bad cell
is refused with a :class:`~flexval.geometry.errors.SceneError` naming the
file, the line and the column. Inside, rotations are radians.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

from .errors import SceneError, did_you_mean
from .loads import MAX_LOAD_SUBSTEPS, LoadCase
from .magnitudes import SMALLEST_NORMAL

MEASURED = ("dx", "dy", "rotation")
"""The measured columns, in the order they are reported."""
COLUMNS = ("load", *MEASURED, *(f"{c}_std" for c in MEASURED))
"""Every column a measurement file may have."""
VALUE_LIMIT = 1e12
"""Largest magnitude of a number in a measurement file (as in a scene file)."""
MAX_ROWS = MAX_LOAD_SUBSTEPS - 1
"""Most data rows: each measured load is a requested level of the traced path (with the
rest state), and a path has at most :data:`~flexval.geometry.loads.MAX_LOAD_SUBSTEPS`."""

MAX_BYTES = 64 * 2**20
"""Largest measurement file read (bytes): :data:`MAX_ROWS` rows of a dozen columns of
full-precision numbers take a few MiB, so a larger file cannot be a measurement; the bound
keeps the reader's memory bounded whatever it is given."""

_UNITS = {
    "mm": ("mm", {"mm"}),
    "deg": ("deg", {"deg", "degree", "degrees", "°"}),
    "N": ("N", {"n"}),
    "N mm": ("N mm", {"nmm"}),
}
"""Unit of the file -> (how messages write it, the spellings accepted, squeezed, lower case)."""
_HEADER = re.compile(r"^(?P<name>[^\[\]]*?)\s*(?:\[(?P<unit>[^\[\]]*)\])?$")


@dataclass(frozen=True)
class Measurement:
    """A measured load–displacement record of one load case.

    Attributes
    ----------
    source : str
        The file it was read from.
    load_case : str
        The load case it measures.
    unit : str
        Unit of ``load``: ``N`` or ``N mm`` (the case's).
    load : tuple of float
        Measured loads in file order (N or N mm), strictly monotonic.
    lines : tuple of int
        The file line of each row (for messages).
    dx, dy : tuple of float or None
        Target point displacement (mm); None where the file has no such column.
    rotation : tuple of float or None
        Target body rotation (rad).
    dx_std, dy_std, rotation_std : tuple of float or None
        Standard uncertainties (mm, mm, rad); None where not given.
    """

    source: str
    load_case: str
    unit: str
    load: tuple[float, ...]
    lines: tuple[int, ...]
    dx: tuple[float, ...] | None = None
    dy: tuple[float, ...] | None = None
    rotation: tuple[float, ...] | None = None
    dx_std: tuple[float, ...] | None = None
    dy_std: tuple[float, ...] | None = None
    rotation_std: tuple[float, ...] | None = None

    @property
    def columns(self) -> tuple[str, ...]:
        """The measured columns the file has (some of :data:`MEASURED`)."""
        return tuple(c for c in MEASURED if getattr(self, c) is not None)

    def std(self, column: str) -> tuple[float, ...] | None:
        """The standard uncertainties of ``column`` (its unit, radians for the rotation)."""
        return getattr(self, f"{column}_std")


def _unit_of(column: str, case: LoadCase) -> str:
    """The unit a column is in: the case's for ``load``, mm or deg for the others."""
    if column == "load":
        return case.unit
    return "deg" if column.startswith("rotation") else "mm"


def _header(row: list[str], source: str, line: int, case: LoadCase) -> list[str]:
    """The column names of the header ``row``, each known, once, in a unit that fits."""

    def fail(column: str, value: str, reason: str) -> None:
        raise SceneError(source, f"line {line}, column {column}", value, reason)

    if len(row) == 1 and any(sep in row[0] for sep in ";\t"):
        fail("1", row[0], "expected comma-separated columns, e.g. load,dx,dy,rotation")
    names = []
    for k, cell in enumerate(row, 1):
        match = _HEADER.match(cell.strip())
        name = match["name"] if match else ""
        if name not in COLUMNS:
            fail(
                str(k),
                cell,
                f"unknown column{did_you_mean(name, COLUMNS)}; expected some of "
                f"{', '.join(COLUMNS)}",
            )
        if name in names:
            fail(name, cell, "the column is given twice")
        unit = match["unit"]
        if unit is not None:
            expected = _unit_of(name, case)
            shown, spellings = _UNITS[expected]
            squeezed = re.sub(r"[\s·*.⋅]", "", unit).lower()
            if squeezed not in spellings:
                what = f"load case {case.name!r} is a {'force' if case.unit == 'N' else 'moment'}"
                fail(
                    name,
                    cell,
                    f"unit [{unit}] does not fit: {name} is in {shown}"
                    + (f" ({what})" if name == "load" else ""),
                )
        names.append(name)
    if "load" not in names:
        fail("load", ",".join(row), "missing column 'load'")
    for name in names:
        if name.endswith("_std") and name[: -len("_std")] not in names:
            fail(name, name, f"an uncertainty without its column {name[: -len('_std')]!r}")
    if not any(c in names for c in MEASURED):
        raise SceneError(
            source,
            f"line {line} (header)",
            ",".join(row),
            "no measured column: give dx, dy (mm) or rotation (deg), or several",
        )
    return names


def _number(text: str, source: str, line: int, column: str) -> float:
    """The finite number of one cell (SceneError naming the line and column)."""
    cell = text.strip()

    def fail(reason: str) -> None:
        raise SceneError(source, f"line {line}, column {column}", text, reason)

    if not cell:
        fail("empty cell")
    try:
        value = float(cell)
    except ValueError:
        fail("not a number")
    if not math.isfinite(value):
        fail("must be finite")
    if abs(value) > VALUE_LIMIT:
        fail(f"absurd magnitude (|value| > {VALUE_LIMIT:g})")
    if value != 0.0 and abs(value) < SMALLEST_NORMAL:
        fail(f"is subnormal (|value| < {SMALLEST_NORMAL:.3g}): too small to compute with")
    if column.endswith("_std") and value <= 0.0:
        fail("a standard uncertainty must be positive")
    return value


def _rows(text: str, source: str) -> list[tuple[int, list[str]]]:
    """(line, cells) of every row that is neither blank nor a comment: the header and at most
    :data:`MAX_ROWS` + 1 data rows (one more than a measurement may have, for the check that
    refuses it, so that a long file is not parsed to its end)."""
    reader = csv.reader(io.StringIO(text))
    rows = []
    try:
        for cells in reader:
            if not any(c.strip() for c in cells) or cells[0].lstrip().startswith("#"):
                continue
            rows.append((reader.line_num, cells))
            if len(rows) > MAX_ROWS + 1:
                break
    except csv.Error as exc:
        raise SceneError(source, f"line {reader.line_num}", None, f"malformed CSV: {exc}") from None
    return rows


def _check_loads(load: list[float], lines: list[int], source: str, case: LoadCase) -> None:
    """Loads strictly monotonic, of the case's sign, at least two of them."""
    if len(load) < 2:
        raise SceneError(
            source,
            f"line {lines[0] if lines else 1}",
            None,
            "at least two rows of measurements are needed",
        )
    if len(load) > MAX_ROWS:
        raise SceneError(
            source,
            f"line {lines[MAX_ROWS]}",
            None,
            f"more than {MAX_ROWS} rows (each measured load is a level of the traced path)",
        )
    rising = load[1] > load[0]
    for k in range(1, len(load)):
        if (load[k] > load[k - 1]) != rising or load[k] == load[k - 1]:
            raise SceneError(
                source,
                f"line {lines[k]}, column load",
                load[k],
                f"loads must be strictly {'increasing' if rising else 'decreasing'} down "
                f"the file (line {lines[k - 1]}: {load[k - 1]:g})",
            )
    for value, line in zip(load, lines):
        if value * case.magnitude < 0.0:
            raise SceneError(
                source,
                f"line {line}, column load",
                value,
                f"has the opposite sign of the full load of load case {case.name!r} "
                f"({case.magnitude:g} {case.unit})",
            )


def _bounded_bytes(path: Path, source: str) -> bytes:
    """The file's bytes, read only if it is a regular file of at most :data:`MAX_BYTES`
    (a device or a pipe, or a larger file, is refused before it is read whole)."""
    try:
        if not path.is_file():
            if not path.exists():
                raise SceneError(source, "file", source, "no such file")
            raise SceneError(
                source, "file", source, "is not a regular file (a device, pipe or folder)"
            )
        with open(path, "rb") as stream:
            raw = stream.read(MAX_BYTES + 1)
    except OSError as exc:
        raise SceneError(source, "file", source, f"cannot be read: {exc.strerror}") from None
    if len(raw) > MAX_BYTES:
        raise SceneError(
            source,
            "file",
            source,
            f"larger than {MAX_BYTES // 2**20} MiB: a measurement has at most {MAX_ROWS} rows",
        )
    return raw


def read_measurement(path: str | Path, case: LoadCase) -> Measurement:
    """Read and check the measurement file ``path`` of load case ``case``.

    Raises
    ------
    SceneError
        Naming the file, the line and the column of the first bad cell: a
        missing ``load`` column, an unknown or repeated column, no measured
        column, a unit that does not fit the case, an empty, non-numeric or
        non-finite cell, a row of another length than the header, loads not
        strictly monotonic or of the other sign than the case; or naming the
        file if it is missing or not UTF-8 text, or the case if its full load is zero.
    """
    source = str(path)
    if case.magnitude == 0.0:
        raise SceneError(
            source,
            "load_case",
            case.name,
            "the load case's full load is zero: a measured load is no load factor of it",
        )
    raw = _bounded_bytes(Path(path), source)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError(
            source, "file", source, f"not UTF-8 text (byte {exc.start} of the file)"
        ) from None
    rows = _rows(text, source)
    if not rows:
        raise SceneError(source, "line 1", "", "no header row: expected e.g. load,dx,dy,rotation")
    (head_line, head), data = rows[0], rows[1:]
    names = _header(head, source, head_line, case)
    columns: dict[str, list[float]] = {n: [] for n in names}
    lines = []
    for line, cells in data:
        if len(cells) != len(names):
            raise SceneError(
                source,
                f"line {line}",
                ",".join(cells),
                f"{len(cells)} cells, the header has {len(names)} ({','.join(names)})",
            )
        for name, cell in zip(names, cells):
            columns[name].append(_number(cell, source, line, name))
        lines.append(line)
    _check_loads(columns["load"], lines, source, case)
    to_rad = {c: math.pi / 180.0 if c.startswith("rotation") else 1.0 for c in names}
    return Measurement(
        source,
        case.name,
        case.unit,
        tuple(columns.pop("load")),
        tuple(lines),
        **{n: tuple(v * to_rad[n] for v in values) for n, values in columns.items()},
    )
