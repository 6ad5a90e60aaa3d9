"""Sweeps whose driver sends parameter blocks: the workers' scenes are the checked ones, task
sizes follow the measured cost, and the reference runs on a seeded sample of the points."""

import textwrap

import numpy as np
import pytest
from builders import in_process_client

from flexval.validation.cache import exact
from flexval.validation.sweep import load_sweep, run_sweep, sweep_rows
from flexval.validation.sweep.builtin import BUILTIN_SWEEPS
from flexval.validation.sweep.engine import (
    MAX_TASK_POINTS,
    TASK_SECONDS,
    TaskCost,
    reference_positions,
    task_info,
    task_points,
)
from flexval.validation.sweep.points import digest
from flexval.validation.sweep.tasks import PointBlock, SweepJob

TOLERANCE = """
name = "tol"
base = "open_chain"
models = ["dcmm:1"]
reference = "ee"
load_cases = ["f+"]
outputs = ["errors", "times"]
{extra}

[[axes]]
path = "section.thickness"
sample = "normal"
mean = 0.1
std = 0.002
count = {count}
seed = 1
"""


def _tolerance(tmp_path, count=12, extra=""):
    path = tmp_path / "tol.toml"
    path.write_text(textwrap.dedent(TOLERANCE.format(count=count, extra=extra)), "utf-8")
    return load_sweep(path)


def _worker_points(sweep, positions):
    """The points of ``positions`` as a worker builds them from a parameter block."""
    b = sweep.points.builder
    job = SweepJob(task_info(sweep), b.light(), tuple(a.path for a in sweep.axes), (), "")
    values = b.values(np.asarray(positions))
    digests = tuple(sweep.points.digest(k) for k in positions)
    return PointBlock(tuple(positions), values, digests, (True,) * len(positions)).points(job)


@pytest.mark.parametrize("name", BUILTIN_SWEEPS)
def test_a_worker_builds_the_checked_scene_of_every_builtin_point(name):
    """Every point of every built-in sweep: the scene a worker builds from the point's
    parameters equals the one the driver's check built (exact values of the mechanism and
    the load cases), and so does its digest, which keys its rows."""
    sweep = load_sweep(name)
    positions = list(range(len(sweep.points)))
    for k, got in zip(positions, _worker_points(sweep, positions)):
        want = sweep.points[k]
        assert got.digest == want.digest == sweep.points.digest(k)
        assert got.params == want.params
        assert exact(got.scene.mechanism) == exact(want.scene.mechanism)
        assert exact(got.scene.load_cases) == exact(want.scene.load_cases)


def test_a_random_sweep_is_keyed_without_building_its_points(tmp_path):
    """A random sweep is not checked point by point: its digests follow from the axis values
    alone, and equal the digest of each point's data written out and hashed."""
    sweep = _tolerance(tmp_path, 50)
    assert not sweep.points.checked
    for k in range(50):
        point = sweep.points[k]  # builds: deep copy, edit, load, hash the data
        assert point.digest == sweep.points.digest(k)
        data = sweep.points.builder.base | {}
        assert digest(data) != point.digest  # the axis value is in the digest
    got = _worker_points(sweep, [3, 7])
    assert [p.digest for p in got] == [sweep.points.digest(3), sweep.points.digest(7)]


def test_a_worker_refuses_a_point_whose_digest_differs(tmp_path):
    sweep = _tolerance(tmp_path)
    b = sweep.points.builder
    job = SweepJob(task_info(sweep), b.light(), ("section.thickness",), (), "")
    block = PointBlock((0,), b.values(np.array([1])), (sweep.points.digest(0),), (True,))
    with pytest.raises(RuntimeError, match="built differently"):
        block.points(job)


@pytest.mark.parametrize(
    "per_point, remaining, workers, want",
    [
        (None, 20_000, 2, 25),  # before any measurement: auto_batch
        (2.5e-3, 20_000, 2, 400),  # 1 s of work
        (2.5e-3, 1000, 2, 125),  # the tail: 4 tasks per worker still
        (1e-6, 10**6, 2, MAX_TASK_POINTS),  # the cap
        (30.0, 1000, 2, 1),  # a costly model: one point
    ],
)
def test_task_sizes_follow_the_measured_cost(per_point, remaining, workers, want):
    assert task_points(per_point, remaining, workers) == want
    assert task_points(per_point, remaining, workers, fixed=7) == 7
    if per_point is not None and want not in (1, MAX_TASK_POINTS):
        assert want * per_point <= TASK_SECONDS


@pytest.fixture(scope="module")
def client():
    with in_process_client() as c:
        yield c


def test_the_reference_runs_on_its_seeded_sample_only(tmp_path, client):
    """reference_sample = 5 of 40 points: the reference's rows and the models' errors exist
    on those 5 points only (drawn again alike from the axes' seeds), every point has the
    model's own outputs, and a rerun runs nothing."""
    sweep = _tolerance(tmp_path, 40, "reference_sample = 5")
    sample = reference_positions(sweep)
    assert len(sample) == 5 and np.array_equal(sample, reference_positions(sweep))
    stats = run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    rows = sweep_rows(sweep, tmp_path / "o")
    ref = [r for r in rows if r["model"] == "ee"]
    model = {r["point"]: r for r in rows if r["model"] == "dcmm:1"}
    assert sorted(r["point"] for r in ref) == sample.tolist()
    assert len(model) == 40 and all(r["status"] == "ok" for r in model.values())
    assert all(r["seconds"] > 0 and r["peak_stress"] is None for r in model.values())
    with_errors = sorted(k for k, r in model.items() if r["end_rot"] is not None)
    assert with_errors == sample.tolist()
    assert all(r["reason"] is None for r in model.values())
    assert stats.rows_written == 45 and stats.rows_failed == 0
    again = run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    assert again.tasks == 0 and again.rows_skipped == 45


def test_invalid_random_draws_are_found_by_the_workers_once(tmp_path, client):
    """h drawn up to 8 mm: the loader refuses some draws; a lazy sweep finds them on the
    workers, stores one invalid-point row each, learns them, and a rerun runs nothing."""
    path = tmp_path / "bad.toml"
    text = TOLERANCE.format(count=8, extra="").replace(
        'sample = "normal"\nmean = 0.1\nstd = 0.002', 'sample = "uniform"\nlow = 0.05\nhigh = 8.0'
    )
    path.write_text(textwrap.dedent(text), "utf-8")
    sweep = load_sweep(path)
    bad = {p.index for p in sweep.points if p.scene is None}
    assert bad and len(bad) < 8 and sweep.points.valid_count == 8
    run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    assert len(sweep.valid_points) == 8 - len(bad)
    fresh = load_sweep(path)
    rows = sweep_rows(fresh, tmp_path / "o")
    assert {r["point"] for r in rows if r["status"] == "invalid_point"} == bad
    assert len(rows) == len(bad) + 2 * (8 - len(bad)) and fresh.points.valid_count == 8 - len(bad)
    assert run_sweep(fresh, tmp_path / "o", client, use_cache=False).tasks == 0


def test_a_task_cost_fits_its_fixed_part_apart_once_sizes_differ():
    """Tasks costing 30 ms plus 0.3 ms a point: the first (25 points each) give their mean
    cost per point, fixed part included; with tasks twice as large, the fitted slope."""
    cost = TaskCost()
    assert cost.per_point() is None
    for _ in range(4):
        cost.add(25, 0.030 + 25 * 3e-4)
    assert cost.per_point() == pytest.approx((0.030 + 25 * 3e-4) / 25)
    for n in (600, 700, 2400):
        cost.add(n, 0.030 + n * 3e-4)
    assert cost.per_point() == pytest.approx(3e-4, rel=1e-9)
    noisy = TaskCost()  # a slope past the mean (a negative fixed part) is not taken
    noisy.add(25, 0.001)
    noisy.add(100, 0.100)
    assert noisy.per_point() == pytest.approx(0.101 / 125)
