"""What the forkserver of a local cluster loads before it forks the workers: the sweep's models.

A worker forked from a process that has loaded a model's code and compiled
kernels (:attr:`flexval.reducedmodels.catalogue.Family.load`: numba's import
and every kernel's machine code, read from the on-disk cache or compiled)
starts its first task with them in memory, instead of loading them itself, a
cost that grows when many workers load at once and that is comparable with a
large sweep's whole work per worker (``benchmarks/bench_sweep.py --scaling``).
The forkserver loads them once, while the driver starts the scheduler.

The models are those :func:`flexval.validation.sweep.engine.local_cluster`
names in the environment variable :data:`MODELS_ENV` when the forkserver
starts (one forkserver serves a process's clusters: a later cluster's
workers load what the first one's did not). A model that cannot be loaded
here is left for its worker, which reports the failure in its rows.
"""

from __future__ import annotations

import os
from collections.abc import Iterable

MODELS_ENV = "FLEXVAL_SWEEP_MODELS"
"""The environment variable naming the models to load, ids joined by :data:`SEPARATOR`."""

SEPARATOR = ";"
"""Between two model ids in :data:`MODELS_ENV` (an id's options are separated by commas)."""


def load_models(ids: Iterable[str]) -> list[str]:
    """Load the code and kernels of each model of ``ids``; the ids loaded.

    A model that fails to parse or to load is skipped: its worker meets the
    same error in its own task and records it.
    """
    from flexval.reducedmodels.catalogue import parse_model

    loaded = []
    for text in ids:
        try:
            spec = parse_model(text)
            load = spec.model_family.load
            if load is not None:
                load(spec)
                loaded.append(spec.id)
        except Exception:  # noqa: BLE001 - the worker reports it, with its context
            continue
    return loaded


load_models(m for m in os.environ.get(MODELS_ENV, "").split(SEPARATOR) if m)
