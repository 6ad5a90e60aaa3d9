"""The results of a sweep as a Parquet dataset: one part file per finished task.

One row per (point, model, load case). A part file is written to a
temporary name and renamed into place, so a sweep interrupted at any moment
leaves only whole parts; rerunning it reads the ``key`` column of every part
and skips what is there. The workers write their tasks' parts themselves, as
*staged* parts (:meth:`ResultStore.stage`, a name the dataset does not read);
the driver renames each into the dataset once it has counted the task
(:meth:`ResultStore.publish`), so the dataset holds exactly the tasks the
driver reported, and the staged parts an interruption leaves are removed by
the next run (:meth:`ResultStore.clear_staged`). Failed runs are rows too (``status`` and
``reason``), with empty (null) errors: a Parquet file never holds a NaN.

Every part of a dataset has the same schema (:func:`schema`). A folder
whose parts have another one (written by a flexval version with other
columns, or by a sweep over other parameters) is
refused with a :class:`SceneError` naming the folder and the differing
columns, rather than mixed into a dataset that Parquet readers would
silently truncate to the first part's columns.

Units: errors in percent, times in s, ``load_reached`` and ``peak_stress_load`` as
fractions of the full load, stresses in MPa, limit loads in ``load_unit`` (N or N mm),
parameters in their scene field's unit.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from flexval.geometry import SceneError
from flexval.geometry.files import atomic_path

from ..studies.compare import METRICS
from .columns import Columns

PARAM_PREFIX = "param:"
STAGED = ".staged-"
"""Name prefix of a part written by a worker and not yet published into the dataset."""
STATUSES = ("ok", "solver_failure", "model_invalid", "error", "invalid_point")
"""``ok``: converged (errors null only if the reference failed); ``solver_failure``: the
model stopped below full load (``load_reached``); ``model_invalid``: the model refuses
the geometry (e.g. PRBM outside its fitted range); ``error``: an unexpected exception or a
lost task; ``invalid_point``: a generated point that the scene loader refuses.
Independently, ``valid`` says whether the validity monitor found every level of a converged
path inside the model's range of meaning, and ``validity`` gives its first reason."""
_FIXED = [
    ("key", pa.string()),
    ("sweep", pa.string()),
    ("point", pa.int64()),
    ("model", pa.string()),
    ("reference", pa.string()),
    ("load_case", pa.string()),
    ("status", pa.string()),
    ("reason", pa.string()),
    ("load_reached", pa.float64()),
    *[(m, pa.float64()) for m in METRICS],
    ("seconds", pa.float64()),
    ("newton_iterations", pa.int64()),
    ("valid", pa.bool_()),
    ("validity", pa.string()),
    ("load_unit", pa.string()),
    ("peak_stress", pa.float64()),
    ("peak_stress_flexure", pa.string()),
    ("peak_stress_at", pa.float64()),
    ("peak_stress_load", pa.float64()),
    ("peak_stress_error", pa.float64()),
    ("parasitic", pa.float64()),
    ("limit_load", pa.float64()),
    ("limit_load_error", pa.float64()),
    ("bifurcation_load", pa.float64()),
    ("target_dx", pa.float64()),
    ("target_dy", pa.float64()),
    ("target_rotation", pa.float64()),
    ("first_yield_load", pa.float64()),
    ("first_yield_fraction", pa.float64()),
    ("first_yield_flexure", pa.string()),
    ("first_yield_at", pa.float64()),
    ("safety_factor", pa.float64()),
    ("fatigue_safety_factor", pa.float64()),
]
"""The columns of every row besides the parameters. ``peak_stress``: the largest outer-fibre
stress over the flexures (MPa) at the load ``peak_stress_load`` (fraction of full load: 1
for a converged row; for a ``solver_failure``, the last recorded level of the path, at or
below ``load_reached``), on ``peak_stress_flexure`` at the fraction ``peak_stress_at`` of
its length from its first end; ``peak_stress_error``: (model - reference) / reference at
full load (converged rows only), percent. ``parasitic``: the largest error of the target's
parasitic components at full load (across a force and the rotation; a moment's dx and dy;
a prescribed motion's free components), each against the reference's own value, percent
(:func:`flexval.validation.studies.parasitic.largest_parasitic_error`; converged rows only, null
where none is scored). ``limit_load``: the first limit point below full load of a
run that stopped there (N or N mm, ``load_unit``; asked for with ``outputs``);
``limit_load_error``: against the reference's, percent. ``bifurcation_load``: the first
bifurcation point on the run's load-control path, where it stopped or one it passed (N or
N mm; asked for with ``limit_load``), null where there is none. ``target_dx``,
``target_dy``, ``target_rotation``: the target's displacement (mm) and rotation (rad) at
full load (converged rows; :func:`~flexval.validation.sweep.tolerance.target_columns`).
``first_yield_*`` and the safety factors: the first yield point and the safety factors at
full load against the scene's ``material.yield_strength`` and ``fatigue_strength``
(:func:`flexval.validation.studies.yieldpoint.yield_columns`; asked for with ``first_yield``), null
without them or where the path does not tell."""


def schema(paths: list[str]) -> pa.Schema:
    """The dataset's schema for a sweep over the parameter ``paths``."""
    return pa.schema(_FIXED + [(PARAM_PREFIX + p, pa.float64()) for p in paths])


def _finite_or_null(table: pa.Table) -> pa.Table:
    """``table`` with every non-finite float (NaN, inf) replaced by null, column by column."""
    for i, f in enumerate(table.schema):
        if not pa.types.is_floating(f.type):
            continue
        column = table.column(i)
        bad = pc.invert(pc.is_finite(column))  # null where the value is null
        if pc.any(bad).as_py():
            table = table.set_column(i, f, pc.if_else(bad, pa.scalar(None, f.type), column))
    return table


class ResultStore:
    """The Parquet dataset in ``folder`` (created on first write)."""

    def __init__(self, folder: str | Path, paths: list[str]):
        self.folder = Path(folder)
        self.schema = schema(paths)

    def parts(self) -> list[Path]:
        """The finished part files, sorted by name."""
        return sorted(self.folder.glob("part-*.parquet")) if self.folder.is_dir() else []

    def check(self) -> None:
        """Raise SceneError (field ``results``) if a stored part has another schema."""
        for part in self.parts():
            found = pq.read_schema(part)
            if found.equals(self.schema, check_metadata=False):
                continue
            missing = [n for n in self.schema.names if n not in found.names]
            extra = [n for n in found.names if n not in self.schema.names]
            raise SceneError(
                str(self.folder),
                "results",
                part.name,
                "holds a sweep dataset of another format (missing columns "
                f"{missing or 'none'}, other columns {extra or 'none'}; written by "
                "another flexval version or for other parameters): choose another --out "
                "or remove this folder",
            )

    def keys(self) -> set[str]:
        """Keys of every row already stored (after :meth:`check`)."""
        self.check()
        out: set[str] = set()
        for part in self.parts():
            out.update(pq.read_table(part, columns=["key"]).column("key").to_pylist())
        return out

    def key_array(self) -> np.ndarray:
        """Keys of every row already stored, sorted, as 24-byte strings (after :meth:`check`):
        24 bytes a row, for :func:`numpy.isin`, where a set of str holds about 100."""
        self.check()
        keys = [pq.read_table(p, columns=["key"]).column("key").to_numpy() for p in self.parts()]
        if not keys:
            return np.empty(0, dtype="S24")
        return np.unique(np.concatenate(keys).astype("S24"))

    def append(self, rows: list[dict]) -> Path | None:
        """Write ``rows`` as one new part file, atomically; None if ``rows`` is empty."""
        staged = self.stage(rows)
        return None if staged is None else self.publish(staged)

    def stage(self, rows: list[dict]) -> Path | None:
        """Write ``rows`` as one staged part, atomically (not yet read as part of the
        dataset); None if ``rows`` is empty."""
        if not rows:
            return None
        table = _finite_or_null(pa.Table.from_pylist(rows, schema=self.schema))
        name = hashlib.sha256("".join(sorted(r["key"] for r in rows)).encode()).hexdigest()[:20]
        self.folder.mkdir(parents=True, exist_ok=True)
        staged = self.folder / f"{STAGED}part-{name}.parquet"
        with atomic_path(staged) as tmp:
            pq.write_table(table, tmp)
        return staged

    def publish(self, staged: str | Path) -> Path:
        """Rename the staged part ``staged`` into the dataset; its final path."""
        staged = Path(staged)
        final = staged.with_name(staged.name.removeprefix(STAGED))
        os.replace(staged, final)
        return final

    def clear_staged(self) -> None:
        """Remove the staged parts that an interrupted run left unpublished (and the
        temporary files of those a worker was writing when it was stopped)."""
        if self.folder.is_dir():
            # a staged part is ``.staged-part-NAME.parquet``; the temporary file it is
            # written through is ``..staged-part-NAME.parquet.XXXX.tmp.parquet``
            for path in self.folder.glob(f"*{STAGED}part-*.parquet"):
                path.unlink(missing_ok=True)

    def rows(self, keys: set[str] | np.ndarray | None = None) -> Columns:
        """The stored rows (those whose key is in ``keys``, if given: strings, or 24-byte
        strings as :meth:`key_array` gives them), sorted by point, model and load case
        (after :meth:`check`), as columns that are also a sequence of dicts."""
        self.check()
        tables = [pq.read_table(p, schema=self.schema) for p in self.parts()]
        if not tables:
            return Columns(self.schema.empty_table())
        table = pa.concat_tables(tables)
        if keys is not None:
            wanted = (
                pa.array(keys.astype(object), type=pa.binary()).cast(pa.string())
                if isinstance(keys, np.ndarray)
                else pa.array(list(keys), type=pa.string())
            )
            table = table.filter(pc.is_in(table["key"], value_set=wanted))
        # a stable sort (Arrow's is), strings by their UTF-8 bytes: Python's code point order
        order = [("point", "ascending"), ("model", "ascending"), ("load_case", "ascending")]
        return Columns(table.sort_by(order))
