"""``flexval sweep``: parameter sweeps of a scene on Dask, results in a Parquet dataset.

:mod:`.spec` reads a sweep file into checked points, :mod:`.engine` runs them
on a Dask cluster (:mod:`.tasks` is what the workers run), :mod:`.store`
keeps the rows, :mod:`.summary` writes the Markdown summary and figures,
:mod:`.builtin` holds the built-in sweeps.
"""

from .engine import (
    SweepStats,
    current_keys,
    local_cluster,
    results_store,
    run_sweep,
    sweep_models,
    sweep_rows,
)
from .points import Point
from .spec import Axis, Sweep, load_sweep, parse_sweep
from .summary import write_outputs

__all__ = [
    "Axis",
    "Point",
    "Sweep",
    "SweepStats",
    "current_keys",
    "load_sweep",
    "local_cluster",
    "parse_sweep",
    "results_store",
    "run_sweep",
    "sweep_models",
    "sweep_rows",
    "write_outputs",
]
