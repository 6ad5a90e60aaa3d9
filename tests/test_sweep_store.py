"""The sweep's Parquet parts: non-finite floats stored as null, rows read back filtered by
key and sorted by point, model and load case as Python sorts them, and what an interrupted
run leaves unpublished removed."""

import math

import pyarrow.parquet as pq

from flexval.geometry.files import atomic_path
from flexval.validation.sweep.store import ResultStore


def _row(key: str, point: int, model: str, case: str, **values) -> dict:
    return {"key": key, "point": point, "model": model, "load_case": case, **values}


def test_a_part_holds_null_where_a_row_has_a_non_finite_float(tmp_path):
    store = ResultStore(tmp_path / "results", ["section.thickness"])
    rows = [
        _row("a", 0, "ee", "f+", end_rot=math.nan, seconds=1.5, **{"param:section.thickness": 0.1}),
        _row("b", 1, "ee", "f+", end_rot=math.inf, seconds=None, valid=True),
        _row("c", 2, "ee", "f+", end_rot=-math.inf, load_reached=0.5),
    ]
    table = pq.read_table(store.append(rows))
    assert table.column("end_rot").to_pylist() == [None, None, None]
    assert table.column("seconds").to_pylist() == [1.5, None, None]
    assert table.column("load_reached").to_pylist() == [None, None, 0.5]
    assert table.column("param:section.thickness").to_pylist() == [0.1, None, None]
    assert table.column("valid").to_pylist() == [None, True, None]


def test_rows_read_back_filtered_by_key_and_sorted_as_python_sorts_them(tmp_path):
    store = ResultStore(tmp_path / "results", [])
    rows = [
        _row("k0", 2, "ee", "m+", seconds=0.0),
        _row("k1", 1, "prbm", "f+", seconds=1.0),
        _row("k2", 1, "dcmm:1", "f-", seconds=2.0),
        _row("k3", 1, "dcmm:1", "f+", seconds=3.0),
        _row("k4", 0, "ß", "f+", seconds=4.0),  # a non-ASCII name: byte order is code point order
        _row("k5", 0, "z", "f+", seconds=5.0),
    ]
    store.append(rows[:3])
    store.append(rows[3:])
    want = sorted(rows, key=lambda r: (r["point"], r["model"], r["load_case"]))
    got = store.rows()
    assert [r["key"] for r in got] == [r["key"] for r in want]
    keep = {"k1", "k3", "k4"}
    assert [r["key"] for r in store.rows(keep)] == [r["key"] for r in want if r["key"] in keep]


def test_clear_staged_removes_unpublished_parts_and_a_write_cut_short(tmp_path):
    store = ResultStore(tmp_path / "results", [])
    published = store.append([_row("p", 0, "ee", "f+", seconds=0.0)])
    staged = store.stage([_row("s", 1, "ee", "f+", seconds=0.0)])
    # a worker stopped inside atomic_path leaves its temporary file, named as atomic_path names it
    cut = atomic_path(staged.with_name(staged.name.replace("part-", "part-cut")))
    temporary = cut.__enter__()
    temporary.write_bytes(b"PAR1")
    before = {p.name for p in store.folder.iterdir()}
    assert {published.name, staged.name, temporary.name} == before
    store.clear_staged()
    assert [p.name for p in store.folder.iterdir()] == [published.name]
    assert [r["key"] for r in store.rows()] == ["p"]
