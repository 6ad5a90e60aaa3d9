"""Batched cost per path: one load path run as a batch of identical copies.

The wall time of one load path of a small model is mostly the per-call
costs of the core that every model shares (Python, numpy's and LAPACK's
per-call checks at every Newton iteration), not the model's arithmetic: a
9-unknown ``dcmm:1`` path costs about a millisecond, a quarter of a
900-unknown ``beam:100`` path. A design study runs thousands of paths of one
mechanism topology, and :func:`flexval.reducedmodels.core.batch.run_batch` traces
them together: one tracer and one Newton iteration for all copies, one
compiled assembly per connector group, one block-diagonal factorisation, so
the per-call costs are paid once per batch. The *batched cost per path* is
the wall time of one such batch of N identical copies of the path (same
scene, model and load case; the copies' Systems built inside the clock,
their paths recorded) divided by N: what a path of the model costs when many
are run, its own cost with the shared overheads spread thin. N is where that
cost stops falling, :data:`BATCH_COPIES`, with fewer copies of a larger model
(:data:`BATCH_UNKNOWNS`) or costlier path (:data:`BATCH_SECONDS`), but for the
reference of the speed-ups (:data:`REFERENCE_COPIES`). Speed-ups of
batched costs compare the models themselves; speed-ups of single paths
compare what one ``flexval run`` costs.

Every timing checks that it timed the real path: each copy's end
displacement and rotation must equal those of the same path run alone
(:func:`end_agreement`, to :data:`AGREEMENT_BAR`). The continuum reference
is not batched (its path costs seconds: the per-call costs are already
negligible). A linear family (``ee``) has no Newton to share; its copies'
linear responses are computed together
(:func:`flexval.reducedmodels.core.linearbatch.linear_responses`: one assembly of
every copy's K0, one pass for the outputs and one for the stresses).

Timings are median seconds of repeats, cached on disk as JSON records
(:meth:`flexval.validation.cache.ResultCache.record`) beside the load
paths, and computed ahead on several processes (:meth:`BatchMemo.prefetch`)
as the report's paths are.

Units: s; agreements in the solver's scale (displacements over the mechanism's size, rad).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.reducedmodels import LoadPath, ModelSpec, SolverError
from flexval.reducedmodels.catalogue import REFERENCE

from ..cache import ResultCache, record_key
from ..interrupt import stop_pool, worker_signals
from ..run import run_model
from .campaign import Progress

SPEED_REFERENCE = "beam:100"
"""The model every speed-up of the run times is measured against (the paper's FEM100)."""

BATCH_COPIES = 100
"""Copies in a timed batch of a small model: where the per-path cost stops falling with the
number of copies, as ``python benchmarks/bench_batch_copies.py`` measures it (open chain
f+; ``dcmm:1``, ``prbm``, ``beam:20``). From 100 copies on the per-batch costs are spread
thin; larger batches cost no less per path (their arrays leave the processor's caches) and
take more of the report's time. A linear model's copies share their assembly and recording
the same way (``ee`` on ``notch_fourbar`` f+, ``--scene notch_fourbar``)."""

BATCH_UNKNOWNS = 5_000
"""Most unknowns in a timed batch: a model of n unknowns is timed with
min(:data:`BATCH_COPIES`, BATCH_UNKNOWNS // n) copies (at least one). A large model's
arithmetic outweighs the per-batch costs with few copies: ``beam:20`` (180 unknowns) costs
little more per path with 30 copies than with 1000 (same benchmark), so that its 27 copies
come close to its least. The bound keeps a batch of a large model (2 copies of
``beam:200``, 1 of ``beam:400``, its path alone) to a fraction of a second, so that timing
every model of the report adds seconds, not minutes."""

BATCH_SECONDS = 0.2
"""A model whose path alone costs more than :data:`BATCH_SECONDS` / :data:`BATCH_COPIES`
(2 ms) gets fewer copies: at most BATCH_SECONDS / its time alone (s). Such a path spends its
time in its own work, which a batch does not share (connectors evaluated one by one in
Python, quadratures), and its cost per path is flat in the batch size (``prbm``'s notch
pivots on ``notch_fourbar``: ``benchmarks/bench_batch_copies.py --scene notch_fourbar``), so
that 23 copies time it as well as 100 at a quarter of the cost."""

REFERENCE_COPIES = 30
"""Copies in a timed batch of :data:`SPEED_REFERENCE`, whose batched cost divides every
batched speed-up. ``beam:100`` (900 unknowns) is past
:data:`~flexval.reducedmodels.core.batch.SOLO_UNKNOWNS`: a batch traces its copies one by one,
so its batched cost is its cost alone, averaged over these copies (30 paths: a median as
steady as the small models' 100-copy batches)."""

AGREEMENT_BAR = 1e-9
"""Largest difference allowed between a batched copy's end values and the same path run
alone, in the solver's scale (:func:`end_agreement`). Both stop Newton once the error
left is below 1e-10 in that scale, and where a test lands within round-off of its bound
they stop one iteration apart (``tests/test_batch.py``): two states that both meet it.
Measured over every reduced model of the runtime-versus-error study on every load case
of the built-in scenes (236 paths, 3 copies each): at most 1.6e-11 (``dcmm:4`` on the
open chain's m+, 24 Newton iterations batched, 26 alone), 2.1e-12 on the next, below
2.5e-13 on the others. A larger difference means the batch traced another path than the
one timed alone."""


def batched(spec: ModelSpec) -> bool:
    """Whether ``spec`` is timed in batches: every model but a reference (the continuum)."""
    return not spec.model_family.has(REFERENCE)


def batch_copies(unknowns: int, model: str = "", seconds: float = 0.0) -> int:
    """Copies in a timed batch of ``model``, of ``unknowns`` unknowns, whose path alone
    takes ``seconds`` (s): :data:`BATCH_COPIES`, at most :data:`BATCH_UNKNOWNS` unknowns and
    :data:`BATCH_SECONDS` of paths alone; :data:`REFERENCE_COPIES` for the
    :data:`SPEED_REFERENCE`."""
    if model == SPEED_REFERENCE:
        return REFERENCE_COPIES
    most = BATCH_COPIES if seconds <= 0 else int(BATCH_SECONDS / seconds)
    return max(1, min(BATCH_COPIES, most, BATCH_UNKNOWNS // max(int(unknowns), 1)))


@dataclass
class BatchTiming:
    """The batched cost per path of one model on one load case of a scene.

    Attributes
    ----------
    model, load_case : str
    copies : int
        Identical copies in each timed batch (:func:`batch_copies`).
    seconds : float
        Median over the repeats of the batch's wall time / ``copies`` (s).
    samples : list of float
        Every repeat's wall time / ``copies`` (s).
    agreement : float or None
        Largest relative difference of a copy's end displacement or rotation from the
        path run alone (:func:`end_agreement`); None when a copy did not reach full load.
    batches : list of int
        The batch sizes the copies were traced in (``[copies]``: all together).
    cached : bool
        Read from the result cache (its seconds are those of the run that filled it).
    """

    model: str
    load_case: str
    copies: int
    seconds: float
    samples: list[float]
    agreement: float | None
    batches: list[int] = field(default_factory=list)
    cached: bool = False

    @property
    def agrees(self) -> bool:
        """Whether every copy reproduced the path run alone (to :data:`AGREEMENT_BAR`)."""
        return self.agreement is not None and self.agreement <= AGREEMENT_BAR

    def to_dict(self) -> dict:
        """JSON-ready fields (a record of the cache and of timings.json)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> BatchTiming:
        """The timing of :meth:`to_dict`."""
        return cls(**d)


def end_agreement(
    single: LoadPath, paths: list[LoadPath | SolverError], length: float
) -> float | None:
    """Largest difference of the ``paths``' end values from ``single``'s, in the solver's
    scale: the end target displacement vector's (mm) over ``length`` (the mechanism's
    size, mm) and the end rotation's (rad), as Newton's error test measures a state
    (:mod:`flexval.reducedmodels.core.newton`). None when a path is an error or does not reach
    ``single``'s load levels.
    """
    worst = 0.0
    for lp in paths:
        if not isinstance(lp, LoadPath) or len(lp.load) != len(single.load):
            return None
        d = math.hypot(lp.dx[-1] - single.dx[-1], lp.dy[-1] - single.dy[-1]) / length
        worst = max(worst, d, abs(lp.rotation[-1] - single.rotation[-1]))
    return worst


def batch_paths(
    scene: Scene, spec: ModelSpec, case: LoadCase, copies: int
) -> tuple[list[LoadPath | SolverError], float]:
    """``copies`` identical copies of ``case`` with ``spec`` run as one batch, and the wall
    time of the whole call (s: the copies' Systems built, traced and recorded)."""
    from flexval.reducedmodels.core.batch import run_batch

    t0 = time.perf_counter()
    paths = run_batch(
        [scene.mechanism] * copies, spec, [case] * copies, levels=None, scene=scene.name
    )
    return paths, time.perf_counter() - t0


def time_batch(
    scene: Scene,
    spec: ModelSpec,
    case: LoadCase,
    repeats: int = 3,
    copies: int | None = None,
) -> BatchTiming | None:
    """The batched cost per path of ``spec`` on ``case``: median of ``repeats`` batches.

    The path is first run alone: its end values are what every copy of every batch
    must reproduce, and its unknowns and time alone (the faster of two runs: the first
    in a process also loads the model's code) set the copies (:func:`batch_copies`)
    unless ``copies`` is given. None for a model that is not batched (:func:`batched`) or whose
    path alone does not reach full load (the timing tables show its failure).
    """
    if not batched(spec):
        return None
    try:
        single = run_model(scene, spec, case)  # also loads the family's code and kernels
    except (SolverError, SceneError):
        return None
    if not single.converged:
        return None
    n = copies
    if n is None:
        alone = min(single.seconds, run_model(scene, spec, case).seconds)  # loaded: its cost
        n = batch_copies(single.stats["unknowns"], spec.id, alone)
    samples: list[float] = []
    agreements: list[float | None] = []
    sizes: set[int] = set()
    for _ in range(max(1, repeats)):
        paths, wall = batch_paths(scene, spec, case, n)
        samples.append(wall / n)
        agreements.append(end_agreement(single, paths, scene.mechanism.size()))
        sizes.update(lp.stats.get("batch", 1) for lp in paths if isinstance(lp, LoadPath))
    return BatchTiming(
        spec.id,
        case.name,
        n,
        statistics.median(samples),
        samples,
        None if None in agreements else max(agreements),
        sorted(sizes),
    )


def batch_key(scene: Scene, spec: ModelSpec, case: LoadCase, repeats: int) -> str:
    """Cache key of one :func:`time_batch` (the code version covers the copy rule)."""
    extra = {"case": scene.load_case(case.name), "repeats": repeats}
    return record_key(scene, spec.id, "batch_timing", extra)


def _time_task(
    scene: Scene, spec: ModelSpec, case: LoadCase, repeats: int, disk: ResultCache | None
) -> BatchTiming | None:
    """:func:`time_batch` through the disk cache (a worker's task, or the caller's)."""
    if disk is None:
        return time_batch(scene, spec, case, repeats)
    return disk.record(
        batch_key(scene, spec, case, repeats),
        lambda: time_batch(scene, spec, case, repeats),
        lambda hit: BatchTiming.from_dict({**hit, "cached": True}),
        lambda timing: None if timing is None else timing.to_dict(),
    )


class BatchMemo:
    """The batched timings of one command: in memory, in front of the disk cache.

    Parameters
    ----------
    repeats : int
        Timed batches per path (median).
    disk : ResultCache, optional
        Where timings are kept between commands (None or disabled: recomputed).
    enabled : bool
        False: no model is timed in batches (every timing is None).
    repeats_for : callable, optional
        The repeats of each model (default: ``repeats`` for every one).
    """

    def __init__(
        self,
        repeats: int,
        disk: ResultCache | None = None,
        enabled: bool = True,
        repeats_for: Callable[[ModelSpec], int] | None = None,
    ):
        self.repeats, self.disk, self.enabled = repeats, disk, enabled
        self.repeats_for = repeats_for or (lambda spec: repeats)
        self.timings: dict[str, BatchTiming | None] = {}
        #: wall time spent computing timings here (s; cached ones cost nothing)
        self.wall = 0.0

    def get(self, scene: Scene, spec: ModelSpec, case: LoadCase) -> BatchTiming | None:
        """The timing of ``spec`` on ``case`` (computed here unless memoised or cached);
        None when disabled or the model is not batched."""
        if not (self.enabled and batched(spec)):
            return None
        repeats = self.repeats_for(spec)
        key = batch_key(scene, spec, case, repeats)
        if key not in self.timings:
            t0 = time.perf_counter()
            self.timings[key] = _time_task(scene, spec, case, repeats, self.disk)
            self.wall += time.perf_counter() - t0
        return self.timings[key]

    def prefetch(
        self,
        tasks: list[tuple[Scene, ModelSpec, LoadCase]],
        workers: int,
        progress: bool = True,
    ) -> None:
        """Compute the timings of ``tasks`` (scene, model, case) on ``workers`` processes.

        Duplicates and models that are not batched are skipped; nothing happens with
        fewer than two workers (:meth:`get` then computes each when asked). Two batches
        run at a time on two workers, as the single paths are timed.
        """
        todo: dict[str, tuple[Scene, ModelSpec, LoadCase]] = {}
        for scene, spec, case in tasks:
            if not (self.enabled and batched(spec)):
                continue
            key = batch_key(scene, spec, case, self.repeats_for(spec))
            if key not in self.timings:
                todo.setdefault(key, (scene, spec, case))
        if workers < 2 or len(todo) < 2:
            return
        t0 = time.perf_counter()
        bar = Progress(len(todo), enabled=progress)
        pool = ProcessPoolExecutor(max_workers=workers, initializer=worker_signals)
        try:
            futures = {
                pool.submit(_time_task, *task, self.repeats_for(task[1]), self.disk): key
                for key, task in todo.items()
            }
            for fut in as_completed(futures):
                key = futures[fut]
                self.timings[key] = timing = fut.result()
                scene, spec, case = todo[key]
                state = "-" if timing is None else f"{timing.seconds:.3g} s/path"
                bar.step(f"{scene.name} {spec.id} {case.name} batched {state}")
        except BaseException:  # an interruption (flexval.validation.interrupt) or a failure
            stop_pool(pool)
            raise
        pool.shutdown()
        self.wall += time.perf_counter() - t0
