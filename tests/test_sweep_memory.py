"""A sweep's driver holds a small record per point, not the points: its memory stays flat in
the point count.

Two checks: the driver's own peak memory (``VmHWM``, see ``peakmemory.py``) after checking
every point of a sweep and listing its row keys grows by far less than a built point holds
(:data:`~flexval.validation.sweep.fields.BYTES_PER_POINT` before records: 6 kB measured on
open_chain) from a few hundred points to a few thousand; and the engine, run on an
in-process Dask cluster, never holds the built points of more than the blocks in flight
(:data:`~flexval.validation.sweep.engine.BLOCKS_IN_FLIGHT`, each of
:data:`~flexval.validation.sweep.engine.BLOCK_TASKS` tasks per worker) while it builds them.
"""

import gc
import subprocess
import sys
import textwrap
import weakref

import pyarrow.parquet as pq
from builders import in_process_client
from peakmemory import PEAK_KB

from flexval.validation.sweep import load_sweep, run_sweep
from flexval.validation.sweep.engine import BLOCK_TASKS, BLOCKS_IN_FLIGHT
from flexval.validation.sweep.points import PointSet

CHILD = """
import sys
from flexval.validation.sweep import load_sweep
from flexval.validation.sweep.engine import current_keys

sweep = load_sweep(sys.argv[1])
keys = current_keys(sweep)
assert len(keys) == 2 * len(sweep.points) == 2 * int(sys.argv[2])
print({peak})
"""


def _sweep(tmp_path, count: int, name: str = "flat"):
    """open_chain with ``count`` zipped thickness and modulus values, ee against prbm."""
    path = tmp_path / f"{name}{count}.toml"
    path.write_text(
        textwrap.dedent(
            f"""
            name = "{name}"
            base = "open_chain"
            models = ["ee"]
            reference = "prbm"
            load_cases = ["m+"]
            combine = "zip"

            [[axes]]
            path = "section.thickness"
            linspace = [0.08, 0.12, {count}]

            [[axes]]
            path = "material.youngs_modulus"
            linspace = [2000.0, 2400.0, {count}]
            """
        ),
        encoding="utf-8",
    )
    return path


def _peak_kb(path, count: int) -> int:
    code = CHILD.format(peak=PEAK_KB)
    done = subprocess.run(
        [sys.executable, "-c", code, str(path), str(count)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    return int(done.stdout.split()[-1])


def test_checking_many_points_keeps_the_driver_flat(tmp_path):
    """200 and 1800 points: the 1600 more cost well under 1 kB each (a built point held
    6 kB); the allocator's own rounding is a few hundred kB."""
    small, large = 200, 1800
    grow = _peak_kb(_sweep(tmp_path, large), large) - _peak_kb(_sweep(tmp_path, small), small)
    assert grow * 1024 < 1000 * (large - small), f"{grow} kB more for {large - small} points"


class _Tracked(PointSet):
    """A lazy point set that counts its built points still alive each time it builds one."""

    def __init__(self, points: PointSet):
        super().__init__(points._builder, points._digests, points._reasons)
        self.alive: list[weakref.ref] = []
        self.most = 0

    def __getitem__(self, k):
        point = super().__getitem__(k)
        self.alive = [r for r in self.alive if r() is not None] + [weakref.ref(point)]
        self.most = max(self.most, len(self.alive))
        return point


def test_the_engine_builds_and_drops_the_points_block_by_block(tmp_path):
    """60 points, one per task on one worker: blocks of 4 points, at most 2 in flight
    while the third is built; all 120 rows are written."""
    import dataclasses

    sweep = load_sweep(_sweep(tmp_path, 60, "blocks"))
    tracked = _Tracked(sweep.points)
    sweep = dataclasses.replace(sweep, points=tracked, batch=1)
    with in_process_client() as client:
        gc.disable()  # only reference counts free the points: the bound is not gc's timing
        try:
            stats = run_sweep(sweep, tmp_path / "out", client, use_cache=False)
        finally:
            gc.enable()
    rows = pq.read_table(tmp_path / "out" / "results").to_pylist()
    assert stats.tasks == 120 and len(rows) == 120
    assert all(r["status"] == "ok" for r in rows)
    block = 1 * 1 * BLOCK_TASKS
    assert tracked.most <= (BLOCKS_IN_FLIGHT + 1) * block < len(sweep.points), tracked.most
