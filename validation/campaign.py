"""Run many models on many load cases, with caching, timing and progress.

Timing is wall-clock per whole load path (model build included), the median
of ``repeats`` runs; the median and every sample are kept in the LoadPath's
``stats`` (``seconds_median``, ``seconds_samples``) and ``seconds`` holds the
median.
"""

from __future__ import annotations

import statistics
import sys
import time
from typing import Callable

from geometry import LoadCase, Scene, SceneError
from reducedmodels import LoadPath, ModelSpec, SolverError

from .cache import ResultCache, result_key
from .failures import Failure, failure_of
from .run import run_model


class Progress:
    """A one-line text progress bar on stderr (silent when disabled)."""

    def __init__(self, total: int, enabled: bool = True, width: int = 24):
        self.total, self.done, self.enabled, self.width = total, 0, enabled, width
        self.t0 = time.perf_counter()

    def step(self, label: str) -> None:
        """Count one unit of work done, labelled ``label``."""
        self.done += 1
        if not self.enabled:
            return
        filled = int(self.width * self.done / max(self.total, 1))
        bar = "#" * filled + "." * (self.width - filled)
        elapsed = time.perf_counter() - self.t0
        end = "\n" if self.done >= self.total else ""
        print(f"\r[{bar}] {self.done:>3}/{self.total} {elapsed:7.1f} s  {label:<40.40}",
              end=end, file=sys.stderr, flush=True)


def timed_run(scene: Scene, spec: ModelSpec, case: LoadCase, repeats: int = 1,
              cache: ResultCache | None = None, record: bool = False) -> LoadPath:
    """One model on one load case: cached, else run ``repeats`` times (median seconds).

    ``record`` also records body poses and deformed shapes (for figures).
    Raises SolverError on failure (failures are not cached).
    """
    key = result_key(scene, spec.id, case.name, None, {"record": record, "repeats": repeats})
    if cache is not None:
        hit = cache.get(key)
        if hit is not None:
            hit.stats["cached"] = True
            return hit
    samples, lp = [], None
    for _ in range(max(1, repeats)):
        lp = run_model(scene, spec, case, record_poses=record, record_shapes=record)
        samples.append(lp.seconds)
    lp.seconds = statistics.median(samples)
    lp.stats["seconds_median"] = lp.seconds
    lp.stats["seconds_samples"] = samples
    if cache is not None:
        cache.put(key, lp)
    return lp


def run_campaign(scene: Scene, specs: list[ModelSpec], cases: list[LoadCase], repeats: int,
                 cache: ResultCache | None, progress: Progress | None = None,
                 record_models: tuple[str, ...] = (),
                 repeats_for: Callable[[ModelSpec], int] | None = None,
                 ) -> tuple[dict[tuple[str, str], LoadPath], list[Failure]]:
    """Every spec on every case: ({(model, case): LoadPath}, failures).

    A model that fails on a case is a result, not an error: its
    :class:`~validation.failures.Failure` is listed and its partial path
    (the levels it reached) kept, and the campaign carries on. So is a
    model that cannot represent a flexure of the scene (a failure at load 0).
    """
    results: dict[tuple[str, str], LoadPath] = {}
    failures: list[Failure] = []
    for spec in specs:
        for case in cases:
            reps = repeats_for(spec) if repeats_for else repeats
            try:
                lp = timed_run(scene, spec, case, reps, cache, record=spec.id in record_models)
                results[(spec.id, case.name)] = lp
                label = f"{scene.name} {spec.id} {case.name} {lp.seconds:.3g} s"
            except (SolverError, SceneError) as exc:
                failures.append(failure_of(exc, scene, spec, case))
                if getattr(exc, "path", None) is not None:
                    results[(spec.id, case.name)] = exc.path
                label = f"{scene.name} {spec.id} {case.name} FAILED"
            if progress:
                progress.step(label)
    return results, failures
