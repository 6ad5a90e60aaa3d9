"""Declared fields of flexval's input files: each table's fields are declared once.

A :class:`Table` lists its :class:`Field` s: name, kind of value, unit,
default, allowed values or range and a one-line description. The parsers
read those declarations for their known-field checks, defaults and range
checks, and :func:`markdown_table` renders the same declarations in the
file-format references, so the documentation cannot drift from the parser.

Units are those of the file: mm, MPa, N, N mm, s, t, degrees.

Declaring a field
-----------------
``Field("radius", "number", "arc radius r", unit="mm", positive=True,
variants=("arc",))`` declares a required positive number that belongs to
``shape = "arc"`` flexures. ``kind`` names the value's form (see
:data:`KINDS`); several forms are joined by ``" | "``, e.g.
``"number | pair"`` for a value given either as a number or as
``[start, end]``. A field whose kind the generic reader does not know is
read by its table's own code; its declaration still sets the known fields
and the reference.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

KINDS = {
    "number": "number",
    "integer": "integer",
    "pair": "[a, b]",
    "numbers": "array of numbers",
    "point": "[x, y]",
    "points": "array of [x, y]",
    "name": "name",
    "names": "[name, name]",
    "text": "string",
    "choice": "string",
    "choices": "array of strings",
    "texts": "array of strings",
    "table": "table",
    "tables": "array of tables",
    "any": "table or string",
}
"""The forms a value may take, with the words the reference uses for them.

A *name* is a non-empty string or an integer (body, flexure and case names).
"""


class _Required:
    """The default of a field that must be given."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()
"""``Field.default`` of a field that must be given."""
ABSENT: Any = None
"""``Field.default`` of an optional field that has no value when left out."""


@dataclass(frozen=True)
class Field:
    """One field of a table of an input file.

    Attributes
    ----------
    name : str
        The key in the file.
    kind : str
        Form of the value: a key of :data:`KINDS`, or several joined by
        ``" | "`` (e.g. ``"number | pair"``).
    description : str
        One line for the reference.
    unit : str
        Unit of the value in the file (``""``: none).
    default : object
        Value used when the field is left out; :data:`REQUIRED` if it must be
        given; :data:`ABSENT` (None) if it is optional without a value.
    default_text : str or None
        How the reference states a default that the parser computes (e.g.
        ``"[section] depth"``); None: the reference prints ``default``.
    positive : bool
        A number must be > 0.
    limit : float or None
        Largest accepted magnitude of a number (None: the reader's own).
    interval : tuple of float or None
        Open interval (low, high) a number must lie in.
    minimum, maximum : float or None
        Closed bounds of a number or integer.
    choices : tuple of str
        The accepted values of a ``choice`` or ``choices`` field.
    variants : tuple of str
        The variants of the table (e.g. the flexure ``shape`` values) that
        use this field; empty: every variant.
    """

    name: str
    kind: str
    description: str
    unit: str = ""
    default: Any = REQUIRED
    default_text: str | None = None
    positive: bool = False
    limit: float | None = None
    interval: tuple[float, float] | None = None
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple[str, ...] = ()
    variants: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        unknown = [k for k in self.kinds if k not in KINDS]
        if unknown:
            raise ValueError(f"field {self.name!r}: unknown kind {unknown}; known: {list(KINDS)}")

    @property
    def kinds(self) -> tuple[str, ...]:
        """The forms the value may take."""
        return tuple(k.strip() for k in self.kind.split("|"))

    @property
    def required(self) -> bool:
        """True if the field must be given."""
        return self.default is REQUIRED

    def range_text(self) -> str:
        """The allowed values in words (empty: any value of the kind)."""
        parts = []
        if self.choices:
            parts.append(", ".join(f'`"{c}"`' for c in self.choices))
        if self.positive:
            parts.append("> 0")
        if self.interval is not None:
            lo, hi = self.interval
            parts.append(f"({number_text(lo)}, {number_text(hi)})")
        if self.minimum is not None and self.maximum is not None:
            parts.append(f"[{number_text(self.minimum)}, {number_text(self.maximum)}]")
        elif self.minimum is not None:
            parts.append(f"≥ {number_text(self.minimum)}")
        elif self.maximum is not None:
            parts.append(f"≤ {number_text(self.maximum)}")
        if self.limit is not None:
            parts.append(f"magnitude ≤ {number_text(self.limit)}")
        return ", ".join(parts)

    def default_words(self) -> str:
        """The default as the reference prints it."""
        if self.default_text is not None:
            return self.default_text
        if self.required:
            return "required"
        if self.default is None:
            return "—"
        if isinstance(self.default, str):
            return f'`"{self.default}"`'
        if isinstance(self.default, float):
            return f"`{self.default:g}`"
        return f"`{self.default!r}`"


@dataclass(frozen=True)
class Table:
    """The fields of one table of an input file.

    Attributes
    ----------
    path : str
        Where the table sits, e.g. ``"material"``, ``"flexures"``,
        ``"load_cases.loads"``; ``""`` for the file's top level.
    description : str
        What the table holds (Markdown, may span lines).
    fields : tuple of Field
        Its fields in reference order.
    array : bool
        True for an array of tables (``[[flexures]]``).
    selector : str or None
        The field (or rule, in words) that picks the variant of an entry,
        e.g. ``"shape"``; None if the table has no variants.
    """

    path: str
    description: str
    fields: tuple[Field, ...]
    array: bool = False
    selector: str | None = None

    def __post_init__(self) -> None:
        names = [f.name for f in self.fields]
        if len(set(names)) != len(names):
            raise ValueError(f"table {self.path!r} declares a field twice: {names}")

    def __getitem__(self, name: str) -> Field:
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(f"table {self.path!r} declares no field {name!r}")

    def __contains__(self, name: object) -> bool:
        return any(f.name == name for f in self.fields)

    def keys(self, variant: str | None = None) -> frozenset[str]:
        """The accepted field names: of every variant, or of ``variant`` only."""
        return frozenset(
            f.name
            for f in self.fields
            if variant is None or not f.variants or variant in f.variants
        )

    def extended(self, *fields: Field) -> Table:
        """This table with ``fields`` appended."""
        return dataclasses.replace(self, fields=self.fields + tuple(fields))

    @property
    def heading(self) -> str:
        """The table as a TOML header: ``[material]``, ``[[flexures]]``, or ``top level``."""
        if not self.path:
            return "top level"
        return f"[[{self.path}]]" if self.array else f"[{self.path}]"


def number_text(x: float) -> str:
    """``x`` as the reference prints it: ``1e12``, ``0.5``, ``20000``, ``1000000``."""
    if float(x).is_integer() and abs(x) < 1e7:
        return str(int(x))
    return format(x, "g").replace("e+", "e")


def _cell(text: str) -> str:
    """``text`` safe inside a Markdown table cell."""
    return text.replace("|", "\\|").replace("\n", " ")


def markdown_table(table: Table) -> str:
    """The reference table of ``table``'s fields (Markdown).

    Columns: field, kind, unit, default, allowed values and, when the table
    has variants, the variants each field belongs to.
    """
    variants = table.selector is not None
    head = ["Field", "Kind", "Unit", "Default", "Allowed", "Description"]
    if variants:
        head.insert(5, f"Only for ({table.selector})")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for f in table.fields:
        kind = " or ".join(KINDS[k] for k in f.kinds)
        row = [
            f"`{f.name}`",
            _cell(kind),
            _cell(f.unit),
            _cell(f.default_words()),
            f.range_text(),
            _cell(f.description),
        ]
        if variants:
            row.insert(5, ", ".join(f"`{v}`" for v in f.variants) or "all")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"
