"""Reading a scene file: its text as UTF-8, and typed, checked access to its TOML tables.

Every error names the file, the field and the value
(:class:`flexval.geometry.errors.SceneError`): a missing table, a value of
the wrong type or outside its range, an unknown key.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from .errors import SceneError, did_you_mean
from .fields import REQUIRED, Field, Table
from .magnitudes import SMALLEST_NORMAL
from .scenefields import (
    COORDINATE_LIMIT,
    NUMBER_LIMIT,
)

_UNIT_WORDS = {"deg": "degrees"}
"""How a range check's message names a unit, where not by its symbol."""
_UNSET: Any = object()


class TableReader:
    """Typed, checked access to a TOML table; every error names the field."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, field: str, value: Any, reason: str) -> None:
        raise SceneError(self.source, field, value, reason)

    def table(self, data: dict, key: str, where: str, required: bool = True) -> dict:
        if key not in data:
            if required:
                self.fail(f"{where}{key}", None, "missing table")
            return {}
        if not isinstance(data[key], dict):
            self.fail(f"{where}{key}", data[key], "must be a table")
        return data[key]

    def number(
        self,
        data: dict,
        key: str,
        where: str,
        *,
        default: float | None = None,
        positive: bool = False,
        limit: float = NUMBER_LIMIT,
    ) -> float:
        field = f"{where}{key}"
        if key not in data:
            if default is None:
                self.fail(field, None, "missing value")
            return default
        v = data[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(field, v, "must be a number")
        v = float(v)
        if not math.isfinite(v):
            self.fail(field, v, "must be finite")
        if abs(v) > limit:
            self.fail(field, v, f"absurd magnitude (|value| > {limit:g})")
        if positive and v <= 0.0:
            self.fail(field, v, "must be positive")
        if v != 0.0 and abs(v) < SMALLEST_NORMAL:
            self.fail(
                field,
                v,
                f"is subnormal (|value| < {SMALLEST_NORMAL:.3g}): too small to compute with",
            )
        return v

    def point(self, data: dict, key: str, where: str) -> np.ndarray:
        field = f"{where}{key}"
        if key not in data:
            self.fail(field, None, "missing point [x, y]")
        v = data[key]
        if not (isinstance(v, list) and len(v) == 2):
            self.fail(field, v, "must be a point [x, y] in mm")
        return np.array(
            [
                self.number({f"{key}[{i}]": c}, f"{key}[{i}]", where, limit=COORDINATE_LIMIT)
                for i, c in enumerate(v)
            ]
        )

    def name(self, data: dict, key: str, where: str) -> str:
        field = f"{where}{key}"
        if key not in data:
            self.fail(field, None, "missing name")
        v = data[key]
        if isinstance(v, bool) or not isinstance(v, (str, int)) or str(v).strip() == "":
            self.fail(field, v, "must be a non-empty name (string or integer)")
        return str(v)

    def array(self, data: dict, key: str, where: str, what: str) -> list:
        """``data[key]`` if it is an array (missing: empty), else a SceneError."""
        v = data.get(key, [])
        if not isinstance(v, list):
            self.fail(f"{where}{key}", v, f"must be an array of {what}")
        return v

    def item_table(self, item: Any, field: str) -> dict:
        """An array element that must be a table."""
        if not isinstance(item, dict):
            self.fail(field, item, "must be a table")
        return item

    def body_pair(self, data: dict, where: str, what: str) -> list[str]:
        """The two distinct body names of a flexure or pin."""
        bodies = data.get("bodies")
        if not (isinstance(bodies, list) and len(bodies) == 2):
            self.fail(f"{where}bodies", bodies, "must list the two bodies it joins, e.g. [1, 2]")
        bodies = [self.name({"b": b}, "b", f"{where}bodies.") for b in bodies]
        if bodies[0] == bodies[1]:
            self.fail(f"{where}bodies", bodies, f"a {what} must join two different bodies")
        return bodies

    def known_keys(
        self, data: dict, table: Table | set[str], where: str, variant: str | None = None
    ) -> None:
        """Refuse a field of ``data`` that ``table`` (of ``variant``) does not declare."""
        allowed = table.keys(variant) if isinstance(table, Table) else table
        for k in data:
            if k not in allowed:
                self.fail(
                    f"{where}{k}",
                    data[k],
                    f"unknown field{did_you_mean(k, allowed)}; expected one of {sorted(allowed)}",
                )

    def value(self, data: dict, field: Field, where: str, default: Any = _UNSET) -> Any:
        """``data``'s value of the declared ``field``, read and checked as declared.

        ``default`` overrides the declared default (a default the parser computes,
        such as a flexure's section). Fields of kind number, point, name and choice
        are read here; a field of another kind is read by its table's own code.
        """
        d = field.default if default is _UNSET else default
        if field.name not in data and d is not REQUIRED:
            return d
        kind = field.kind
        if kind == "number":
            v = self.number(
                data,
                field.name,
                where,
                positive=field.positive,
                limit=NUMBER_LIMIT if field.limit is None else field.limit,
            )
            self.in_range(field, v, where)
            return v
        if kind == "point":
            return self.point(data, field.name, where)
        if kind == "name":
            return self.name(data, field.name, where)
        if kind == "choice":
            v = data.get(field.name)
            if v not in field.choices:
                words = [repr(c) for c in field.choices]
                text = " or ".join([", ".join(words[:-1]), words[-1]] if len(words) > 1 else words)
                self.fail(
                    f"{where}{field.name}", v, f"must be {text}{did_you_mean(v, field.choices)}"
                )
            return v
        raise TypeError(f"field {field.name!r} ({kind}) is read by its table's own code")

    def in_range(self, field: Field, v: float, where: str) -> None:
        """Refuse a number outside ``field``'s declared interval or bounds."""
        unit = _UNIT_WORDS.get(field.unit, field.unit)
        unit = f" {unit}" if unit else ""
        if field.interval is not None:
            lo, hi = field.interval
            if not lo < v < hi:
                self.fail(f"{where}{field.name}", v, f"must be in ({lo:g}, {hi:g}){unit}")
        lo = -math.inf if field.minimum is None else field.minimum
        hi = math.inf if field.maximum is None else field.maximum
        if not lo <= v <= hi:
            self.fail(f"{where}{field.name}", v, f"must be from {lo:g} to {hi:g}{unit}")


_BYTE_ORDER_MARKS = {
    b"\xff\xfe": "UTF-16",
    b"\xfe\xff": "UTF-16",
    b"\xff\xfe\x00\x00": "UTF-32",
    b"\x00\x00\xfe\xff": "UTF-32",
}


def read_utf8(path: Path) -> str:
    """The file's text: UTF-8 as TOML requires (a leading UTF-8 byte-order mark is skipped)."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise SceneError(str(path), "scene", str(path), f"cannot be read: {exc.strerror}") from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        found = next(
            (
                enc
                for bom, enc in sorted(_BYTE_ORDER_MARKS.items(), reverse=True)
                if raw.startswith(bom)
            ),
            None,
        )
        what = (
            f"it looks like {found}"
            if found
            else f"byte 0x{raw[exc.start]:02x} at offset {exc.start} is not UTF-8 (Latin-1?)"
        )
        raise SceneError(
            str(path),
            "encoding",
            None,
            f"a scene file must be UTF-8 text: {what}; save it as UTF-8",
        ) from None
