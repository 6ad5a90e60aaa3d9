"""Tables whose columns line up, and numbers with a fixed count of significant digits.

Every table a ``flexval`` command prints goes through here: a column is as
wide as its widest cell or title, so a long model id such as
``continuum:1[law=neo-hookean,plane=strain]`` widens its column instead of
shifting the rest of the row. :func:`text_table` sizes the columns from all
rows; a table printed row by row while its runs finish (``flexval run``)
fixes each column's width first (:class:`Column` ``width``) and formats each
row with :func:`text_row`. :func:`markdown_table` writes the same padded
layout as a Markdown pipe table, for the files that commands also print.

Only the standard library is imported: ``flexval info`` and ``flexval
models`` load no numerical package.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace

GAP = " "
"""Space between two columns of a plain-text table."""

SIG_WIDTH = 10
"""Widest text :func:`sig` gives with 4 significant digits: ``-0.0005000``, ``-1.234e-05``
(only an exponent beyond 99 is wider)."""


@dataclass(frozen=True)
class Column:
    """One column of a table.

    Parameters
    ----------
    title : str
        Header text (with the unit, e.g. ``dx mm``).
    align : {'>', '<'}
        ``>`` right-aligned (numbers), ``<`` left-aligned (names, text).
    width : int
        Least width in characters; :func:`fit` widens it to the cells.
    """

    title: str
    align: str = ">"
    width: int = 0

    def __post_init__(self) -> None:
        if self.align not in ("<", ">"):
            raise ValueError(f"column {self.title!r}: align must be '<' or '>', got {self.align!r}")

    @property
    def size(self) -> int:
        """Width of the column: its least width or its title, whichever is wider."""
        return max(self.width, len(self.title))


def sig(value: float | None, digits: int = 4) -> str:
    """``value`` with ``digits`` significant digits, trailing zeros kept.

    ``3.0`` -> ``3.000``, ``0.012`` -> ``0.01200``, ``123456.0`` -> ``1.235e+05``
    (with 4 digits); ``1234.0`` -> ``1234`` (no trailing point). None is ``-``,
    and a value that is not finite prints as ``nan``, ``inf`` or ``-inf``.
    """
    if value is None:
        return "-"
    x = float(value)
    if not math.isfinite(x):
        return str(x)
    mantissa, e, exponent = format(x, f"#.{digits}g").partition("e")
    return mantissa.rstrip(".") + e + exponent


def fit(columns: Sequence[Column], rows: Iterable[Sequence[str]]) -> list[Column]:
    """``columns`` widened so that every cell of ``rows`` fits."""
    widths = [c.size for c in columns]
    for row in rows:
        if len(row) != len(columns):
            raise ValueError(f"a row of {len(row)} cells in a table of {len(columns)} columns")
        widths = [max(w, len(cell)) for w, cell in zip(widths, row)]
    return [replace(c, width=w) for c, w in zip(columns, widths)]


def _cell(column: Column, text: str) -> str:
    return text.ljust(column.size) if column.align == "<" else text.rjust(column.size)


def text_row(columns: Sequence[Column], cells: Sequence[str], indent: str = "") -> str:
    """One line of a plain-text table: each cell padded to its column's width.

    A cell wider than its column (a streamed table's width was too small)
    widens that line only; :func:`text_table` never lets that happen.
    """
    if len(cells) != len(columns):
        raise ValueError(f"{len(cells)} cells in a table of {len(columns)} columns")
    return (indent + GAP.join(_cell(c, t) for c, t in zip(columns, cells))).rstrip()


def header(columns: Sequence[Column], indent: str = "") -> str:
    """The title line of a plain-text table."""
    return text_row(columns, [c.title for c in columns], indent)


def text_table(
    columns: Sequence[Column], rows: Sequence[Sequence[str]], indent: str = ""
) -> list[str]:
    """Title line and rows of a plain-text table, every column as wide as its widest cell."""
    cols = fit(columns, rows)
    return [header(cols, indent)] + [text_row(cols, row, indent) for row in rows]


def markdown_table(columns: Sequence[Column], rows: Sequence[Sequence[str]]) -> list[str]:
    """A Markdown pipe table, padded so that its columns also line up as plain text.

    ``|`` inside a cell is written as ``/`` (it would end the cell).
    """
    rows = [[cell.replace("|", "/") for cell in row] for row in rows]
    # a delimiter cell of at least three characters, as every Markdown reader accepts
    cols = fit([replace(c, width=max(c.width, 3)) for c in columns], rows)
    rule = ["-" * (c.size - 1) + ":" if c.align == ">" else "-" * c.size for c in cols]

    def line(cells: Sequence[str]) -> str:
        return "| " + " | ".join(cells) + " |"

    return [
        line([_cell(c, c.title) for c in cols]),
        line(rule),
        *(line([_cell(c, t) for c, t in zip(cols, row)]) for row in rows),
    ]
