"""A model's first critical load and its natural frequencies, as the report finds them.

``flexval gate``'s ``limit_load`` and ``frequency`` metrics
(:mod:`flexval.validation.studies.gate`) take their figures from here, and here from
the report's own code, so a gate's numbers are the report's:

* :func:`critical_load`: the model's load-control path on a load case
  (:func:`flexval.validation.studies.campaign.timed_run`); where it stops short of full
  load, :func:`flexval.validation.failures.failure_of` searches it by arc
  length for a limit point (the report's limit-load table) or names the
  bifurcation it stopped at; the first bifurcation point on the path
  (:attr:`flexval.reducedmodels.LoadPath.bifurcations`, the table's
  bifurcation rows) counts too. The first critical load is the smaller of the
  two. Both searches end at the full load (:data:`SEARCH_RANGE` times it).
* :func:`natural_frequencies`: the lowest natural frequencies at rest
  (:func:`flexval.validation.report.frequencies.lowest_frequencies`), with the flexure
  density the report chooses (:func:`flexval.validation.studies.modes.choose_density`
  with :data:`flexval.validation.report.frequencies.DEFAULT_DENSITY`).

Both are kept in the result cache as JSON records
(:meth:`flexval.validation.cache.ResultCache.record`) under the exact
scene (mass data included), model id, load case or mode count, and code, as
load paths are; a model of a plug-in family is always computed (the key holds
flexval's code, not the plug-in's). Units: N or N mm, Hz, t/mm^3.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.reducedmodels import ModelSpec, SolverError

from ..cache import ResultCache, record_key
from ..failures import BIFURCATION, LIMIT_POINT, failure_of
from ..report.frequencies import DEFAULT_DENSITY, MODAL_ERRORS, lowest_frequencies, modal_reason
from .campaign import RunMemo, timed_run
from .modes import DensityChoice, choose_density

SEARCH_RANGE = 1.0
"""How far the report's searches for a critical load go, in times the load case's full
load: load control and the arc-length limit search both stop there."""


@dataclass(frozen=True)
class Critical:
    """A model's first critical load on one load case.

    Attributes
    ----------
    kind : str or None
        :data:`~flexval.validation.failures.LIMIT_POINT` or
        :data:`~flexval.validation.failures.BIFURCATION`; None: none within
        :data:`SEARCH_RANGE` times the load (or ``failure`` says why none was found).
    load : float or None
        Its load, N or N mm.
    unit : str
    failure : str
        Non-empty when the model neither reached full load nor a critical load
        (the solver's reason, or why it cannot model the scene).
    seconds : float
        Time of the load-control path and the search (of the run that filled the cache
        when read from it).
    """

    kind: str | None
    load: float | None
    unit: str
    failure: str = ""
    seconds: float = 0.0

    def describe(self) -> str:
        """E.g. ``limit point at 8.9704 N``."""
        return f"{self.kind} at {self.load:.5g} {self.unit}" if self.kind else "none"

    def record(self) -> dict:
        """JSON form (the cache's record)."""
        return {
            "kind": self.kind,
            "load": self.load,
            "unit": self.unit,
            "failure": self.failure,
            "seconds": self.seconds,
        }


def _first(candidates: list[tuple[float, str]], unit: str, seconds: float) -> Critical:
    if not candidates:
        return Critical(None, None, unit, "", seconds)
    load, kind = min(candidates)
    return Critical(kind, float(load), unit, "", seconds)


def _search(scene: Scene, spec: ModelSpec, case: LoadCase, memo: RunMemo | None) -> Critical:
    t0 = time.perf_counter()
    try:
        lp = timed_run(scene, spec, case, 1, memo)
    except SceneError as exc:
        return Critical(None, None, case.unit, f"cannot model the scene: {exc.reason}")
    except SolverError as exc:
        failure = failure_of(exc, scene, spec, case)
        found = failure.reason in (LIMIT_POINT, BIFURCATION)
        candidates = [(float(failure.load), failure.reason)] if found else []
        if exc.path is not None and exc.path.bifurcations:
            candidates.append((float(exc.path.bifurcations[0]["load"]), BIFURCATION))
        if not candidates:
            why = f"did not reach full load ({100 * exc.load_factor:.0f} %): {failure.reason}"
            return Critical(None, None, case.unit, why, _since(t0))
        return _first(candidates, case.unit, _since(t0))
    first = lp.bifurcations[0] if lp.bifurcations else None
    candidates = [] if first is None else [(float(first["load"]), BIFURCATION)]
    return _first(candidates, case.unit, lp.seconds)


def _since(t0: float) -> float:
    return time.perf_counter() - t0


def critical_load(
    scene: Scene, spec: ModelSpec, case: LoadCase, memo: RunMemo, cacheable: bool = True
) -> Critical:
    """The first critical load of ``spec`` on ``case`` (see the module text): from the
    result cache, else searched and stored there (not when ``cacheable`` is False, nor a
    result without a verdict: ``failure`` set)."""
    key = record_key(scene, spec.id, "critical_load", {"case": case, "range": SEARCH_RANGE})
    return memo.disk.record(
        key if cacheable else None,
        lambda: _search(scene, spec, case, memo if cacheable else None),
        lambda hit: Critical(**hit) if set(hit) == set(Critical.__dataclass_fields__) else None,
        lambda found: None if found.failure else found.record(),
    )


@dataclass(frozen=True)
class Frequencies:
    """A model's lowest natural frequencies at rest.

    Attributes
    ----------
    values : list of float
        Hz, ascending (negative: unstable); empty when ``failure`` is set.
    density : DensityChoice
        The flexure density used and where it comes from.
    failure : str
        Why the modal analysis failed; empty otherwise.
    seconds : float
        Time of the analysis (of the run that filled the cache when read from it).
    """

    values: list[float]
    density: DensityChoice
    failure: str = ""
    seconds: float = 0.0


def natural_frequencies(
    scene: Scene, spec: ModelSpec, count: int, cache: ResultCache, cacheable: bool = True
) -> Frequencies:
    """The ``count`` lowest natural frequencies of ``spec`` at rest on ``scene``, as the
    report's natural-frequency table gives them: from the result cache, else computed and
    stored there (not when ``cacheable`` is False, nor a failed analysis)."""
    massive, density = choose_density(scene, None, DEFAULT_DENSITY)
    key = record_key(massive, spec.id, "natural_frequencies", {"count": count})

    def compute() -> Frequencies:
        t0 = time.perf_counter()
        try:
            values = lowest_frequencies(massive, spec, count)
        except MODAL_ERRORS as exc:
            return Frequencies([], density, modal_reason(exc), _since(t0))
        return Frequencies(values, density, "", _since(t0))

    def read(hit: dict) -> Frequencies | None:
        if not {"values", "seconds"} <= set(hit):
            return None
        return Frequencies(list(hit["values"]), density, "", hit["seconds"])

    return cache.record(
        key if cacheable else None,
        compute,
        read,
        lambda found: None if found.failure else {"values": found.values, "seconds": found.seconds},
    )
