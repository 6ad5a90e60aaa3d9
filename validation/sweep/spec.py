"""Sweep files: a base scene, parameter axes and models, expanded into checked points.

A sweep file (TOML) names a base scene, the models and the reference they are measured
against, the load cases and the parameter axes to vary (values listed, spaced, or drawn at
random). Its fields are declared in :mod:`flexval.validation.sweep.fields`, from which the
documentation's sweep file reference, with a complete example, is generated.

An axis's path walks the scene's TOML tables: ``material.youngs_modulus``,
``flexures.e12.thickness``, ``load_cases.f+.value`` (arrays of tables are
addressed by their ``name``), ``ground.points.0.1`` (plain arrays by index).
The last key may be absent from the base scene when the scene format allows
it there (``flexures.e12.thickness`` overrides the ``[section]`` default).

Every point is the base scene's parsed TOML with the axis values written in,
loaded through :func:`flexval.geometry.scene.parse_scene`, so every scene check
applies. A point built from listed values (``values``, ``linspace``,
``logspace``) that the loader refuses is bad input (:class:`SceneError`
naming the point and the field); a point built from random samples that the
loader refuses is kept as an *invalid point* and reported, since a random
draw can fall outside the mechanism's valid range.

Units: those of the addressed scene fields (mm, MPa, N, N mm, degrees).
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import hashlib
import json
import math
import tomllib
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flexval.geometry import BUILTIN_SCENES, Scene, SceneError
from flexval.geometry.errors import did_you_mean
from flexval.geometry.scene import parse_scene, read_scene_data
from flexval.geometry.scenepaths import field_slot
from flexval.reducedmodels import ModelSpec, parse_model, run_reduced

from ..studies.stress import scale_case
from .fields import (
    ALWAYS_OUTPUTS,
    AXES,
    AXIS_KINDS,
    BYTES_PER_POINT,
    CHECK_BLOCK,
    COMBINE,
    DEFAULT_OUTPUTS,
    MAX_COUNT,
    MAX_POINTS,
    OPTIONAL_OUTPUTS,
    SAMPLES,
    SECONDS_PER_POINT,
    SUMMARY_METRICS,
    SWEEP,
)
from .incremental import IncrementalBuilder, builder_key, incremental_builder
from .points import Point, PointSet, ValidPoints, digest


@dataclass(frozen=True)
class Axis:
    """One swept parameter: the scene path and its values (in the field's unit)."""

    path: str
    values: tuple[float, ...]
    random: bool
    seed: int | None = None
    """The seed of a random axis's draws (None for listed values)."""


@dataclass(frozen=True)
class PointBuilder:
    """Builds the point of a given index from the base scene's data and the axes."""

    base: dict
    axes: tuple[Axis, ...]
    combine: str
    source: str
    name: str
    cases: tuple[str, ...]
    rotation: float | None

    def params(self, index: int) -> dict[str, float]:
        """The axis values of point ``index`` (the order of :func:`_combine`)."""
        if self.combine == "zip" or not self.axes:
            return {a.path: a.values[index] for a in self.axes}
        values = {}
        for a in reversed(self.axes):  # itertools.product: the last axis varies fastest
            index, k = divmod(index, len(a.values))
            values[a.path] = a.values[k]
        return {a.path: values[a.path] for a in self.axes}

    def values(self, indices: np.ndarray) -> np.ndarray:
        """The axis values of the points ``indices``, one row each (the order of
        :meth:`params`), without building a scene."""
        indices = np.asarray(indices, dtype=np.int64)
        out = np.empty((len(indices), len(self.axes)))
        if self.combine == "zip" or not self.axes:
            for j, a in enumerate(self._arrays):
                out[:, j] = a[indices]
            return out
        shape = tuple(len(a.values) for a in self.axes)
        for j, (a, k) in enumerate(zip(self._arrays, np.unravel_index(indices, shape))):
            out[:, j] = a[k]
        return out

    @functools.cached_property
    def _arrays(self) -> tuple[np.ndarray, ...]:
        """Each axis's values as an array (made once: converting a large axis's tuple
        at every call would cost more than picking the values)."""
        return tuple(np.asarray(a.values, dtype=float) for a in self.axes)

    def light(self) -> PointBuilder:
        """This builder without the axes' values (what a worker needs to build a point whose
        parameters it is given: a few kB, whatever the point count)."""
        return dataclasses.replace(
            self, axes=tuple(dataclasses.replace(a, values=()) for a in self.axes)
        )

    @functools.cached_property
    def _digest_template(self) -> tuple[str, ...]:
        """The JSON text of :func:`digest` of a point's data, split where the axis values go
        (every other piece is the index of the axis whose value goes there)."""
        data = copy.deepcopy(self.base)
        marks = {}
        for k, a in enumerate(self.axes):
            mark = f"\x00axis{k}\x00"
            node, key = field_slot(data, a.path, self.source, f"axes[{k}].path")
            node[key] = mark
            marks[json.dumps(mark)] = k
        text = json.dumps(data, sort_keys=True, default=str)
        pieces: list = [text]
        for mark, k in marks.items():
            split = []
            for piece in pieces:
                if isinstance(piece, int):
                    split.append(piece)
                    continue
                parts = piece.split(mark)
                for n, part in enumerate(parts):
                    split += [k, part] if n else [part]
            pieces = split
        return tuple(pieces)

    def digest_of(self, values: Sequence[float]) -> str:
        """:func:`digest` of the data of the point with the axis ``values``, without copying
        the base scene or writing JSON (for a sweep without ``linear_rotation``, whose
        points' data differ from the base's in the axis values only)."""
        text = "".join(
            json.dumps(float(values[p])) if isinstance(p, int) else p for p in self._digest_template
        )
        return hashlib.sha256(text.encode()).hexdigest()[:24]

    def _data(self, params: dict[str, float]) -> dict:
        """The base scene's data with the axis values ``params`` written in."""
        pdata = copy.deepcopy(self.base)
        for k, (path, v) in enumerate(params.items()):
            node, key = field_slot(pdata, path, self.source, f"axes[{k}].path")
            node[key] = v
        return pdata

    def _where(self, index: int, params: dict[str, float]) -> str:
        """The source label of point ``index``'s scene (its errors name it)."""
        return f"{self.source}: point {index} {params}"

    @functools.cached_property
    def _key(self) -> str:
        """:func:`.incremental.builder_key` of this builder's base data, axes and labels."""
        return builder_key(self.base, [a.path for a in self.axes], self.source, self.name)

    def incremental(self) -> IncrementalBuilder | None:
        """This process's incremental builder of the points (None: an axis is not a value
        field, :mod:`.incremental`)."""
        paths = [a.path for a in self.axes]

        def template(data: dict) -> Scene:
            return parse_scene(
                data, f"{self.source}: base", default_name=self.name, keep_data=False
            )

        def corner(values: tuple) -> Scene:
            params = dict(zip(paths, values))
            return parse_scene(
                self._data(params), self._where(-1, params), self.name, keep_data=False
            )

        return incremental_builder(self._key, self.base, paths, template, corner)

    def build_block(self, indices: Sequence[int], values: np.ndarray) -> Iterator[Point]:
        """The points ``indices`` with the axis ``values`` (one row each, in axis order), as
        :meth:`build` builds them, one at a time as they are iterated; the scenes of those
        an incremental build proves valid (all proofs made first, from the values alone)
        are built from the base scene without a parse (:mod:`.incremental`)."""
        values = np.asarray(values, dtype=float).reshape(len(indices), len(self.axes))
        inc = self.incremental()
        fast = inc.proven(values) if inc is not None else np.zeros(len(indices), dtype=bool)
        paths = [a.path for a in self.axes]
        for index, row, quick in zip(indices, values.tolist(), fast.tolist()):
            params = dict(zip(paths, row))
            if not quick:
                yield self.build(index, params)
                continue
            scene = inc.scene(row, self._where(index, params))
            if self.rotation is None:
                yield Point(index, params, scene, self.digest_of(row))
                continue
            pdata = self._data(params)
            scene = _normalise(scene, pdata, self.cases, self.rotation)
            yield Point(index, params, scene, digest(pdata))

    def build(self, index: int, params: dict[str, float] | None = None) -> Point:
        """Point ``index`` with its loaded scene (scene None and a reason for a refused random
        draw; a refused listed point raises SceneError naming the point and the field)."""
        params = self.params(index) if params is None else params
        pdata = self._data(params)
        where = self._where(index, params)
        try:
            # it reads, never writes; a point keeps no data: it changes by the axes
            scene = parse_scene(pdata, where, default_name=self.name, keep_data=False)
        except SceneError as exc:
            if not any(a.random for a in self.axes):
                raise
            return Point(index, params, None, digest(pdata), f"{exc.field}: {exc.reason}")
        if self.rotation is not None:
            scene = _normalise(scene, pdata, self.cases, self.rotation)
        return Point(index, params, scene, digest(pdata))


@dataclass(frozen=True)
class Sweep:
    """A checked sweep: axes, models, reference and its points (built on demand)."""

    name: str
    description: str
    source: str
    base: str
    axes: tuple[Axis, ...]
    combine: str
    models: tuple[ModelSpec, ...]
    reference: ModelSpec
    load_cases: tuple[str, ...]
    metric: str
    linear_rotation: float | None
    batch: int | None
    points: PointSet
    """Every point; a tuple of built points is taken as :meth:`PointSet.of` it."""
    outputs: tuple[str, ...] = DEFAULT_OUTPUTS
    """The optional outputs asked for (a subset of :data:`OPTIONAL_OUTPUTS`, in that order)."""
    reference_sample: int | None = None
    """How many of the valid points the reference runs on (None: every point); the rows of
    the other points carry no errors."""

    def __post_init__(self) -> None:
        if not isinstance(self.points, PointSet):
            object.__setattr__(self, "points", PointSet.of(self.points))

    @property
    def valid_points(self) -> ValidPoints:
        """The points whose scene loaded (built as they are iterated)."""
        return ValidPoints(self.points)


def _fail(source: str, field: str, value: Any, reason: str) -> None:
    raise SceneError(source, field, value, reason)


def _number(source: str, field: str, v: Any, positive: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        _fail(source, field, v, "must be a finite number")
    if positive and v <= 0:
        _fail(source, field, v, "must be positive")
    return float(v)


def _count(source: str, field: str, v: Any) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= MAX_COUNT:
        _fail(source, field, v, f"must be an integer from 1 to {MAX_COUNT}")
    return v


def _axis(source: str, k: int, a: Any) -> Axis:
    """Parse ``axes[k]``: one of values, linspace, logspace or sample."""
    where = f"axes[{k}]"
    if not isinstance(a, dict):
        _fail(source, where, a, "must be a table [[axes]]")
    known = AXES.keys()
    for key in a:
        if key not in known:
            _fail(
                source,
                f"{where}.{key}",
                a[key],
                f"unknown field{did_you_mean(key, known)}; expected one of {sorted(known)}",
            )
    path = a.get("path")
    if not isinstance(path, str) or not path.strip():
        _fail(source, f"{where}.path", path, "must be a scene field path, e.g. section.thickness")
    kinds = [x for x in AXIS_KINDS if x in a]
    if len(kinds) != 1:
        _fail(source, where, kinds, "give exactly one of values, linspace, logspace, sample")
    kind = kinds[0]
    field = f"{where}.{kind}"
    if kind == "values":
        vals = a["values"]
        if not isinstance(vals, list) or not vals:
            _fail(source, field, vals, "must be a non-empty list of numbers")
        return Axis(path, tuple(_number(source, field, v) for v in vals), False)
    if kind in ("linspace", "logspace"):
        spec = a[kind]
        if not (isinstance(spec, list) and len(spec) == 3):
            _fail(source, field, spec, "must be [first, last, count]")
        lo = _number(source, field, spec[0], positive=kind == "logspace")
        hi = _number(source, field, spec[1], positive=kind == "logspace")
        n = _count(source, field, spec[2])
        vals = np.linspace(lo, hi, n) if kind == "linspace" else np.geomspace(lo, hi, n)
        return Axis(path, tuple(float(v) for v in vals), False)
    dist = a["sample"]
    if dist not in SAMPLES:
        _fail(source, field, dist, f"must be one of {sorted(SAMPLES)}")
    p1, p2 = SAMPLES[dist]
    x1 = _number(source, f"{where}.{p1}", a.get(p1), positive=dist == "lognormal")
    x2 = _number(source, f"{where}.{p2}", a.get(p2), positive=dist != "uniform")
    if dist == "uniform" and not x1 < x2:
        _fail(source, f"{where}.high", x2, f"must exceed low = {x1:g}")
    n = _count(source, f"{where}.count", a.get("count"))
    seed = a.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        _fail(source, f"{where}.seed", seed, "must be a non-negative integer (repeatable draws)")
    rng = np.random.default_rng(seed)
    vals = {
        "uniform": lambda: rng.uniform(x1, x2, n),
        "normal": lambda: rng.normal(x1, x2, n),
        "lognormal": lambda: rng.lognormal(math.log(x1), x2, n),
    }[dist]()
    return Axis(path, tuple(float(v) for v in vals), True, seed)


def _outputs(source: str, value: Any) -> tuple[str, ...]:
    """The optional outputs named in ``outputs`` (errors and times are always there)."""
    known = ALWAYS_OUTPUTS + OPTIONAL_OUTPUTS
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        _fail(source, "outputs", value, f"must be a list of names from {list(known)}")
    for v in value:
        if v not in known:
            _fail(source, "outputs", v, f"unknown output; expected one of {list(known)}")
    return tuple(o for o in OPTIONAL_OUTPUTS if o in value)


def point_count(axes: tuple[Axis, ...], combine: str, source: str) -> int:
    """The number of points the axes give, without building them (zipped axes: checked equal)."""
    if combine == "zip" and axes:
        lengths = {len(a.values) for a in axes}
        if len(lengths) != 1:
            _fail(
                source,
                "axes",
                [len(a.values) for a in axes],
                "zipped axes must have the same number of values",
            )
        return len(axes[0].values)
    return math.prod(len(a.values) for a in axes)


def check_point_count(count: int, source: str, max_points: int) -> None:
    """Refuse ``count`` points above ``max_points`` or above what memory holds (SceneError)."""
    if count > max_points:
        _fail(
            source,
            "axes",
            f"{count:,} points",
            f"more than --max-points {max_points:,} (a bound against sweeps that never "
            "end); give --max-points to accept them, or fewer axis values",
        )
    from ..resources import available_memory, gigabytes

    room, what = available_memory()
    if count * BYTES_PER_POINT > room:
        _fail(
            source,
            "axes",
            f"{count:,} points",
            f"they need about {gigabytes(count * BYTES_PER_POINT)} of memory but {what} is "
            f"{gigabytes(room)}; sweep fewer values, or split the sweep",
        )


def _normalise(scene: Scene, data: dict, cases: tuple[str, ...], rotation: float) -> Scene:
    """``scene`` with each load case scaled so that the ee end rotation is ``rotation`` (rad).

    The case values in ``data`` are scaled alike, so the digest sees them.
    """
    scaled = []
    for case in scene.load_cases:
        if case.name not in cases:
            scaled.append(case)
            continue
        lin = run_reduced(scene.mechanism, parse_model("ee"), case)
        factor = rotation / max(abs(lin.rotation[-1]), np.finfo(float).tiny)
        scaled.append(scale_case(case, factor))
        entry = next(c for c in data["load_cases"] if str(c.get("name")) == case.name)
        for comp in entry.get("loads", [entry]):
            comp["value"] = comp["value"] * factor
    return dataclasses.replace(scene, load_cases=tuple(scaled), data=None)


def _base_data(base: Any, source: str, folder: Path) -> tuple[str, dict]:
    """(label, parsed TOML) of the base scene: a built-in name, a path (relative to the
    sweep file's folder) or an inline table."""
    if isinstance(base, dict):
        return "<inline>", base
    if not isinstance(base, str):
        _fail(source, "base", base, "must be a built-in scene name or a scene file path")
    if base in BUILTIN_SCENES:
        return base, read_scene_data(base)[1]
    path = Path(base) if Path(base).is_absolute() else folder / base
    if not path.is_file():
        _fail(
            source,
            "base",
            base,
            f"no such scene file, and not a built-in scene {list(BUILTIN_SCENES)}",
        )
    return str(path), read_scene_data(path)[1]


def parse_sweep(
    data: dict,
    source: str,
    folder: Path = Path("."),
    default_name: str = "sweep",
    max_points: int = MAX_POINTS,
    progress: Callable[[str], None] | None = None,
) -> Sweep:
    """Check a parsed sweep file and every point (nothing is run but ee scaling).

    The point count is checked (``max_points``, and the memory the points'
    records would hold) from the axes before any point is built. A sweep with a
    random axis and no ``linear_rotation`` is not built here at all: a refused draw
    is an invalid point, not bad input, so the workers that build the points find
    them (a lazy :class:`PointSet`; the digests follow from the axis values).
    Otherwise the points are generated block by block from the axes
    (:meth:`PointBuilder.build_block`), checked, and kept only as a :class:`PointRecord`
    (the sweep's :class:`PointSet` builds them again on demand); when checking them is
    estimated to take longer than a minute, ``progress`` is told the estimate and then
    every tenth of the points checked.

    Raises
    ------
    SceneError
        For a bad field of the sweep file, more points than ``max_points`` or
        memory allow, or a listed point that the scene loader refuses (the
        message names the point, its values and the field).
    """
    known = SWEEP.keys()
    for key in data:
        if key not in known:
            hint = did_you_mean(key, known)
            _fail(source, key, data[key], f"unknown field{hint}; expected one of {sorted(known)}")
    name = str(data.get("name", default_name))
    if "base" not in data:
        _fail(source, "base", None, "missing: the base scene (built-in name or path)")
    label, base = _base_data(data["base"], source, folder)
    base_scene = parse_scene(copy.deepcopy(base), f"{source}: base {label}")
    models = data.get("models")
    if not isinstance(models, list) or not models:
        _fail(source, "models", models, "must be a non-empty list of model ids")
    specs = tuple(parse_model(m, source, "models") for m in models)
    if len({s.id for s in specs}) != len(specs):
        _fail(source, "models", models, "lists a model twice")
    reference = parse_model(data.get("reference", SWEEP["reference"].default), source, "reference")
    if reference in specs:
        _fail(source, "models", reference.id, "the reference is not compared with itself")
    names = [c.name for c in base_scene.load_cases]
    cases = data.get("load_cases", names)
    if not isinstance(cases, list) or not cases:
        _fail(source, "load_cases", cases, "must be a non-empty list of load case names")
    for c in cases:
        if c not in names:
            _fail(source, "load_cases", c, f"unknown load case; the base scene has {names}")
    combine = data.get("combine", SWEEP["combine"].default)
    if combine not in COMBINE:
        _fail(source, "combine", combine, f"must be one of {list(COMBINE)}")
    metric = data.get("metric", SWEEP["metric"].default)
    if metric not in SUMMARY_METRICS:
        _fail(source, "metric", metric, f"must be one of {list(SUMMARY_METRICS)}")
    rotation = data.get("linear_rotation")
    if rotation is not None:
        rotation = _number(source, "linear_rotation", rotation, positive=True)
    batch = data.get("batch")
    if batch is not None:
        batch = _count(source, "batch", batch)
    outputs = _outputs(source, data.get("outputs", list(DEFAULT_OUTPUTS)))
    sample = data.get("reference_sample")
    if sample is not None:
        sample = _count(source, "reference_sample", sample)
    raw_axes = data.get("axes", [])
    if not isinstance(raw_axes, list):
        _fail(source, "axes", raw_axes, "must be an array of tables [[axes]]")
    axes = tuple(_axis(source, k, a) for k, a in enumerate(raw_axes))
    if len({a.path for a in axes}) != len(axes):
        _fail(source, "axes", [a.path for a in axes], "a path is swept twice")
    for k, a in enumerate(axes):
        field_slot(base, a.path, source, f"axes[{k}].path")
    if (
        "first_yield" in outputs
        and base_scene.mechanism.material.yield_strength is None
        and "material.yield_strength" not in {a.path for a in axes}
    ):
        _fail(
            source,
            "outputs",
            list(outputs),
            "first_yield needs the base scene's material.yield_strength (MPa), which it "
            "does not give: every first-yield column would be empty",
        )

    count = point_count(axes, combine, source)
    check_point_count(count, source, max_points)
    builder = PointBuilder(base, axes, combine, source, name, tuple(cases), rotation)
    if rotation is None and any(a.random for a in axes):
        # a refused random draw is an invalid point, not bad input: the workers find them
        points = PointSet(builder, count=count)
    else:
        points = _checked_points(builder, count, progress)
    return Sweep(
        name,
        str(data.get("description", "")),
        source,
        label,
        axes,
        combine,
        specs,
        reference,
        tuple(cases),
        metric,
        rotation,
        batch,
        points,
        outputs,
        reference_sample=sample,
    )


def _checked_points(
    builder: PointBuilder, count: int, progress: Callable[[str], None] | None
) -> PointSet:
    """The points of ``builder``, each built and checked once, kept as records (a listed
    point that the loader refuses raises SceneError; ``progress`` as for
    :func:`parse_sweep`)."""
    from ..resources import LONG_SECONDS, duration

    tell = progress if count * SECONDS_PER_POINT > LONG_SECONDS else None
    if tell is not None:
        tell(f"checking {count:,} points: about {duration(count * SECONDS_PER_POINT)}")
    digests = np.empty(count, dtype="S24")
    reasons = {}
    for start in range(0, count, CHECK_BLOCK):
        block = np.arange(start, min(start + CHECK_BLOCK, count), dtype=np.int64)
        for i, point in zip(
            block.tolist(), builder.build_block(block.tolist(), builder.values(block))
        ):
            if tell is not None and i and i % max(1, count // 10) == 0:
                tell(f"checked {i:,} of {count:,} points")
            digests[i] = point.digest.encode()
            if point.scene is None:
                reasons[i] = point.reason
    return PointSet(builder, digests, reasons)


def load_sweep(
    name_or_path: str | Path,
    max_points: int = MAX_POINTS,
    progress: Callable[[str], None] | None = None,
) -> Sweep:
    """Load a built-in sweep by name (see :mod:`flexval.validation.sweep.builtin`) or a sweep file
    (at most ``max_points`` points; ``progress`` as for :func:`parse_sweep`).

    Raises
    ------
    SceneError
        If the file is missing, malformed, or any field or point is bad.
    """
    from .builtin import BUILTIN_SWEEPS, builtin_sweep

    text_id = str(name_or_path)
    if text_id in BUILTIN_SWEEPS:
        return parse_sweep(
            builtin_sweep(text_id),
            f"<builtin sweep {text_id}>",
            default_name=text_id,
            max_points=max_points,
            progress=progress,
        )
    path = Path(text_id)
    if not path.is_file():
        _fail(
            text_id,
            "sweep",
            text_id,
            f"no such file, and not a built-in sweep {sorted(BUILTIN_SWEEPS)}",
        )
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        _fail(str(path), "toml", None, f"malformed TOML: {exc}")
    return parse_sweep(
        data, str(path), path.parent, path.stem, max_points=max_points, progress=progress
    )
