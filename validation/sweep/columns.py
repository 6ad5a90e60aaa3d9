"""A sweep's result rows read as columns: what the summary, the figures and the tolerance
study take over every row.

A 100,000-point sweep has a few hundred thousand rows. Made into Python dicts (Arrow's
``to_pylist``) and read back row by row for each table and figure, they cost the driver a
serial tail after the workers are done, which a fast sweep on many workers waits for
(``benchmarks/bench_sweep.py --tolerance`` times reading the rows back). :class:`Columns`
holds the rows as an Arrow table (as the dataset is read) or as dicts (rows made in
memory), gives each column once as a numpy array, and makes dicts only of the rows a
consumer lists one by one (failures, limit points), or of all of them for a consumer that
iterates (it is a sequence of dicts).

Units: those of each column (see :mod:`flexval.validation.sweep.store`).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any, TypeAlias

import numpy as np
import pyarrow as pa

Rows: TypeAlias = "Columns | Sequence[dict]"
"""A sweep's rows: as dicts, or as :class:`Columns` (what every consumer of rows takes)."""

FEW = 64
"""Most rows :meth:`Columns.take` slices one by one: a take gathers every column of a table
read from many parts (tens of ms), a slice is a view."""


class Columns(Sequence):
    """The rows of a sweep (a sequence of dicts), and each column as a numpy array.

    Parameters
    ----------
    rows : pyarrow.Table or sequence of dict
        The rows: an Arrow table (a column the table lacks reads as all None) or dicts (a
        key a row lacks reads as None).
    """

    def __init__(self, rows: pa.Table | Sequence[dict]):
        self._table = rows if isinstance(rows, pa.Table) else None
        self._dicts: list[dict] | None = None if self._table is not None else list(rows)
        self._columns: dict[str, np.ndarray] = {}
        self._floats: dict[str, np.ndarray] = {}
        self._ok: np.ndarray | None = None
        self._groups: dict[tuple[Any, Any], np.ndarray] | None = None

    @classmethod
    def of(cls, rows: Rows | pa.Table) -> Columns:
        """``rows`` as Columns (the same object if it is one already)."""
        return rows if isinstance(rows, Columns) else cls(rows)

    def __len__(self) -> int:
        return self._table.num_rows if self._table is not None else len(self._dicts)

    def _rows(self) -> list[dict]:
        """Every row as a dict (made once)."""
        if self._dicts is None:
            self._dicts = self._table.to_pylist()
        return self._dicts

    def __getitem__(self, index):
        return self._rows()[index]

    def __iter__(self) -> Iterator[dict]:
        return iter(self._rows())

    def __eq__(self, other: object) -> bool:
        """Rows equal row by row (to Columns or to a list of dicts)."""
        if not isinstance(other, (Columns, list, tuple)):
            return NotImplemented
        return len(self) == len(other) and all(a == b for a, b in zip(self, other))

    __hash__ = None  # type: ignore[assignment]  (mutable caches; compared by content)

    def take(self, indices: np.ndarray) -> list[dict]:
        """The rows at ``indices`` as dicts, in that order (only they are made)."""
        if self._dicts is not None:
            return [self._dicts[int(k)] for k in indices]
        if len(indices) <= FEW:
            return [self._table.slice(int(k), 1).to_pylist()[0] for k in indices]
        return self._table.take(pa.array(np.asarray(indices, dtype=np.int64))).to_pylist()

    def column(self, name: str) -> np.ndarray:
        """The column as an array of Python objects (None where a row has no value)."""
        if name not in self._columns:
            values = np.empty(len(self), dtype=object)
            if self._dicts is not None:
                values[:] = [r.get(name) for r in self._dicts]
            elif name in self._table.column_names:
                chunked = self._table.column(name)
                values[:] = chunked.to_numpy(zero_copy_only=False)
                values[chunked.is_null().to_numpy(zero_copy_only=False)] = None
            self._columns[name] = values
        return self._columns[name]

    def floats(self, name: str) -> np.ndarray:
        """The column as floats, NaN where a row has no finite value."""
        if name not in self._floats:
            if self._table is not None and name in self._table.column_names:
                values = self._table.column(name).to_numpy(zero_copy_only=False)
                values = np.array(values, dtype=float)  # nulls: NaN
            else:
                column = self.column(name)
                values = np.full(len(self), np.nan)
                present = np.not_equal(column, None)
                values[present] = column[present].astype(float)
            values[~np.isfinite(values)] = np.nan
            self._floats[name] = values
        return self._floats[name]

    def present(self, name: str) -> np.ndarray:
        """Whether each row has a value (not None) in the column."""
        return np.not_equal(self.column(name), None)

    def ok(self) -> np.ndarray:
        """Whether each row's run reached full load (status ``ok``)."""
        if self._ok is None:
            self._ok = np.equal(self.column("status"), "ok")
        return self._ok

    def units(self, cases: Sequence[str]) -> dict[str, str]:
        """The load unit (``load_unit``: N or N mm) of each of ``cases`` some row gives (the
        first such row's), in the order of those rows."""
        unit, case = self.column("load_unit"), self.column("load_case")
        given = np.not_equal(unit, None) & np.not_equal(unit, "")
        first = {}
        for c in cases:
            hits = np.flatnonzero(given & np.equal(case, c))
            if hits.size:
                first[c] = int(hits[0])
        return {c: unit[k] for c, k in sorted(first.items(), key=lambda item: item[1])}

    def rows_of(self, model: str, case: str) -> np.ndarray:
        """The indices of the rows of ``model`` under ``case``, in row order."""
        if self._groups is None:
            pairs = [self.column("model"), self.column("load_case")]
            codes = [np.unique(c.astype(str), return_inverse=True) for c in pairs]
            (models, of_model), (cases, of_case) = codes
            group = of_model.ravel() * len(cases) + of_case.ravel()
            order = np.argsort(group, kind="stable")  # row order within a group
            starts = np.searchsorted(group[order], np.arange(len(models) * len(cases) + 1))
            self._groups = {
                (m, c): order[starts[i * len(cases) + j] : starts[i * len(cases) + j + 1]]
                for i, m in enumerate(models.tolist())
                for j, c in enumerate(cases.tolist())
            }
        return self._groups.get((model, case), np.zeros(0, dtype=np.int64))

    def of_model(self, model: str) -> np.ndarray:
        """Whether each row is of ``model``."""
        return np.equal(self.column("model"), model)
