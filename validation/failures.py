"""A model that cannot reach full load is a result: how far it got and why.

Every command that runs several models (``report``, ``bench``, ``converge``,
``stress``) turns a :class:`reducedmodels.SolverError` into a
:class:`Failure` and carries on. When the model can be traced by arc length
(capability ``arclength``) the path is searched for a limit point below full
load: if there is one, the failure is that limit point (load control cannot
pass it whatever the solver) and its load is given; the arc-length path is kept
with the failure (:attr:`Failure.trace`) so the report can draw the traced
branch. A path that load control cannot continue past a bifurcation point (the
tracer located it: :attr:`reducedmodels.LoadPath.bifurcations`) fails there, at the
bifurcation's load, unless a limit point comes first. Units: N or N mm.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.reducedmodels import LoadPath, SolverError, SolverSettings, build_system
from flexval.reducedmodels.catalogue import ARCLENGTH, ModelSpec
from flexval.reducedmodels.core.continuation import limit_loads, solve_arclength

LIMIT_SETTINGS = SolverSettings(max_translation_step=0.01, max_rotation_step=0.05)
"""Step bounds (1 % of the size, 0.05 rad) of the arc-length search for limit points: fine
enough that the parabola through the peak's points gives the limit load to ~1e-5 (measured
against the last load that load control converges on the closed chain)."""

#: ``Failure.reason`` of a path that stops at a limit point found by arc length
LIMIT_POINT = "limit point"
#: ``Failure.reason`` of a path that stops at a bifurcation point (load control finds only
#: unstable equilibria beyond it)
BIFURCATION = "bifurcation point"


@dataclass(frozen=True)
class Failure:
    """A model's failure on one load case.

    Attributes
    ----------
    model, load_case : str
        Model id and load case name.
    factor : float
        Last converged load factor (0..1).
    load : float
        The load of the failure (N or N mm): the limit load when
        ``reason`` is :data:`LIMIT_POINT`, the bifurcation's load when it is
        :data:`BIFURCATION`, else the last converged load.
    unit : str
        ``N`` or ``N mm``.
    reason : str
        :data:`LIMIT_POINT`, :data:`BIFURCATION` or the solver's own reason.
    message : str
        The solver's full message.
    trace : LoadPath or None
        The arc-length path up to just past the limit point when ``reason``
        is :data:`LIMIT_POINT` (its largest load is near ``load``), else None.
        Not part of :meth:`to_dict` (results.json keeps the load-control path).
    """

    model: str
    load_case: str
    factor: float
    load: float
    unit: str
    reason: str
    message: str
    trace: LoadPath | None = field(default=None, compare=False, repr=False)

    def summary(self) -> str:
        """E.g. ``fails at 78 % (limit point, 2.65 N)``."""
        return f"fails at {100 * self.factor:.0f} % ({self.reason}, {self.load:.3g} {self.unit})"

    def to_dict(self) -> dict:
        """JSON-ready fields (all but ``trace``)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "trace"}


def first_limit(scene: Scene, spec: ModelSpec, case: LoadCase) -> tuple[float, LoadPath] | None:
    """The first limit point of ``case``'s path below full load: (load, arc-length path), or None.

    Arc-length continuation from rest with the step bounds of
    :data:`LIMIT_SETTINGS`, stopped just past the first local maximum of the
    load magnitude; the load (N or N mm) is refined by the parabola through
    the peak's points. None for models without the ``arclength`` capability,
    or when the path reaches full load (or fails) without one.
    """
    if not spec.model_family.has(ARCLENGTH):
        return None
    system = build_system(spec.model_family.loaded(scene.mechanism, case), spec, LIMIT_SETTINGS)
    try:
        lp = solve_arclength(
            system,
            case,
            1.0,
            20,
            model=spec.id,
            max_steps=2000,
            stop=lambda p: bool(p.stats["limit_points"]),
        )
    except SolverError:
        return None
    loads = limit_loads(lp)
    return (loads[0], lp) if loads else None


def failure_of(
    exc: SolverError | SceneError, scene: Scene, spec: ModelSpec, case: LoadCase
) -> Failure:
    """The :class:`Failure` of ``spec`` on ``case`` that raised ``exc``.

    A SceneError here means the model cannot represent a flexure of the
    scene (e.g. a PRBM arc outside its fitted range): a failure at load 0.
    """
    if isinstance(exc, SceneError):
        return Failure(spec.id, case.name, 0.0, 0.0, case.unit, exc.reason, str(exc))
    reason = (exc.path.stats.get("failure") if exc.path is not None else None) or str(exc)
    load = exc.load_factor * case.magnitude
    limit = first_limit(scene, spec, case)
    trace = None
    stop = stopping_bifurcation(exc)
    if limit is not None and limit[0] <= case.magnitude and (stop is None or limit[0] < stop):
        (load, trace), reason = limit, LIMIT_POINT
    elif stop is not None:
        load, reason = stop, BIFURCATION
    return Failure(spec.id, case.name, exc.load_factor, load, case.unit, reason, str(exc), trace)


def stopping_bifurcation(exc: SolverError) -> float | None:
    """The load (N or N mm) of the bifurcation point a load-control path stopped at, or None.

    The recorder names it in the partial path's ``stats["stopped_at_bifurcation"]``
    (its load factor; see :class:`flexval.reducedmodels.core.recorder.PathRecorder`).
    """
    path = exc.path
    factor = path.stats.get("stopped_at_bifurcation") if path is not None else None
    if factor is None:
        return None
    return next(
        (float(b["load"]) for b in path.bifurcations or () if b["fraction"] == factor), None
    )
