"""A sweep's rows as columns: the rows a run knows to be current are those hashing every
point finds, and the columns of the dataset read as the dicts of the same rows do."""

import textwrap

import numpy as np
import pyarrow.parquet as pq
import pytest
from builders import in_process_client

from flexval.validation.sweep import current_keys, load_sweep, results_store, run_sweep, sweep_rows
from flexval.validation.sweep.columns import FEW, Columns
from flexval.validation.sweep.summary import format_summary, format_timings, point_metrics

SWEEP = """
name = "tol"
base = "open_chain"
models = ["dcmm:1"]
reference = "ee"
load_cases = ["f+", "m+"]
outputs = ["peak_stress"]
{sample}
{extra}

[[axes]]
path = "section.thickness"
sample = "uniform"
low = 0.05
high = {high}
count = {count}
seed = 1
"""


@pytest.fixture(scope="module")
def client():
    with in_process_client() as c:
        yield c


def _sweep(tmp_path, high=0.15, count=16, sample="reference_sample = 6", extra=""):
    path = tmp_path / "sw.toml"
    text = SWEEP.format(high=high, count=count, sample=sample, extra=extra)
    path.write_text(textwrap.dedent(text), "utf-8")
    return load_sweep(path)


def _keys(part) -> list[bytes]:
    """The keys of one part file."""
    return [k.encode() for k in pq.read_table(part, columns=["key"]).column("key").to_pylist()]


def _known(sweep, store) -> set[bytes]:
    """The stored keys that hashing every point gives (the independent answer)."""
    return {k.encode() for k in current_keys(sweep)} & set(store.key_array().tolist())


@pytest.mark.parametrize(
    "high, extra",
    [(0.15, ""), (8.0, ""), (8.0, "linear_rotation = 0.1")],
    ids=["valid", "with invalid draws", "checked"],  # the last: points checked at loading
)
def test_a_run_knows_its_current_rows_as_hashing_every_point_finds_them(
    tmp_path, client, high, extra
):
    """A fresh run, a rerun with nothing to do, a run beside rows of an earlier code version
    and of the reference off its sample, and a resumed run with a part lost: the keys each
    run reports are the stored keys that :func:`current_keys` (every point hashed) finds,
    and the rows read by them are the same."""
    out = tmp_path / "o"
    sweep = _sweep(tmp_path, high, extra=extra)
    store = results_store(sweep, out)
    stats = run_sweep(sweep, out, client, use_cache=False)
    assert set(stats.current_keys().tolist()) == _known(sweep, store)
    assert stats.current_keys().size == stats.rows_written
    # the reference on every point: its rows off the sample are stored, and not current
    everywhere = run_sweep(
        _sweep(tmp_path, high, sample="", extra=extra), out, client, use_cache=False
    )
    assert everywhere.rows_written > 0
    # a rerun writes nothing and knows every row
    again = run_sweep(_sweep(tmp_path, high, extra=extra), out, client, use_cache=False)
    assert again.rows_written == 0 and set(again.current_keys().tolist()) == _known(sweep, store)
    # rows of an earlier code version (other keys) stay out
    rows = store.rows()
    store.append([r | {"key": "old-" + r["key"][4:]} for r in rows])
    # a lost part of current rows: they run again, the rest are found
    known = _known(sweep, store)
    next(p for p in store.parts() if known & set(_keys(p))).unlink()
    fresh = _sweep(tmp_path, high, extra=extra)
    resumed = run_sweep(fresh, out, client, use_cache=False)
    assert resumed.rows_written > 0
    assert set(resumed.current_keys().tolist()) == _known(fresh, store)
    assert sweep_rows(fresh, out, resumed) == sweep_rows(_sweep(tmp_path, high, extra=extra), out)
    assert len(sweep_rows(fresh, out, resumed)) == len(_known(fresh, store)) < len(rows)


def test_the_columns_of_the_dataset_read_as_its_rows_do(tmp_path, client):
    """Every accessor of :class:`Columns` gives the same from the Arrow table as from the
    same rows as dicts, and so do the summary and the timings written from each."""
    out = tmp_path / "o"
    sweep = _sweep(tmp_path, 8.0, count=60)
    run_sweep(sweep, out, client, use_cache=False)
    table = sweep_rows(sweep, out)
    dicts = Columns([dict(r) for r in results_store(sweep, out).rows()])
    assert table == dicts and len(table) > FEW  # both take paths below
    for name in ("end_rot", "peak_stress", "seconds", "point", "param_section.thickness"):
        np.testing.assert_array_equal(table.floats(name), dicts.floats(name))
    for name in ("model", "status", "reason", "valid", "peak_stress", "no such column"):
        assert table.column(name).tolist() == dicts.column(name).tolist()
        assert table.present(name).tolist() == dicts.present(name).tolist()
    assert table.ok().tolist() == dicts.ok().tolist() and not table.ok().all()
    for model in ("ee", "dcmm:1", "-", "beam:20"):
        for case in ("f+", "m+", "-"):
            assert table.rows_of(model, case).tolist() == dicts.rows_of(model, case).tolist()
    assert table.units(["m+", "f+"]) == dicts.units(["m+", "f+"]) == {"f+": "N", "m+": "N mm"}
    for some in ([], [3, 0], list(range(0, len(table), 2))):
        assert table.take(np.array(some, dtype=np.int64)) == [dicts[k] for k in some]
    assert point_metrics(sweep, table) == point_metrics(sweep, dicts)
    assert format_summary(sweep, table) == format_summary(sweep, list(dicts))
    assert format_timings(sweep, table, 1.0) == format_timings(sweep, list(dicts), 1.0)


def test_the_point_metric_is_the_largest_over_the_cases_and_none_if_one_has_none():
    """Rows written by hand: the metric of a point is max(0, its cases' values), None if a
    case has none; a model's points come in the order of their first rows."""

    class Spec:
        def __init__(self, id):
            self.id = id

    class Sweep:
        models = (Spec("a"),)
        metric = "end_rot"

    rows = [
        {"model": "a", "point": 2, "end_rot": 0.5},
        {"model": "a", "point": 1, "end_rot": -1.0},
        {"model": "a", "point": 2, "end_rot": 1.5},
        {"model": "a", "point": 3, "end_rot": 0.25},
        {"model": "a", "point": 3, "end_rot": None},
        {"model": "b", "point": 1, "end_rot": 9.0},
    ]
    assert point_metrics(Sweep, rows) == {"a": {2: 1.5, 1: 0.0, 3: None}}
    assert list(point_metrics(Sweep, rows)["a"]) == [2, 1, 3]
