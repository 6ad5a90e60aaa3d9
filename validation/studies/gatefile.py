"""Gates files: which models must stay within which error of a reference, on which scenes.

A gates file (TOML) is read by ``flexval gate``::

    reference = "continuum:1"
    scenes = ["open_chain", "closed_chain", "my_mechanism.toml"]
    [[gates]]
    model = "dcmm:3"
    path_disp = 3.0          # percent, every load case of every scene
    end_rot = 2.0
    limit_load = 5.0         # first critical load (limit or bifurcation point)
    frequency = 2.0          # worst of the lowest ``modes`` natural frequencies

Its fields are declared once (:data:`GATES`, :data:`GATE`), for the parser
here and for the generated reference (:func:`field_reference`). Every bad
field is a :class:`geometry.SceneError` naming the file, the field and the
value (the CLI's exit code 2). Thresholds are in percent, the unit of the
error metrics (:mod:`flexval.validation.studies.compare`).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flexval.geometry import BUILTIN_SCENES, Scene, SceneError, load_scene
from flexval.geometry.errors import did_you_mean
from flexval.geometry.fields import ABSENT, Field, Table, markdown_table
from flexval.reducedmodels.catalogue import ModelSpec, parse_model

from ..report.frequencies import MODE_COUNT

MAX_MODES = 1000
"""The most natural frequencies a modal analysis gives (``flexval modes --count``)."""

PATH_METRICS = ("end_disp", "end_disp_vec", "end_rot", "path_disp", "path_rot")
"""The error metrics of a load path against the reference's
(:data:`flexval.validation.studies.compare.METRICS`, percent)."""
STRESS_METRICS = ("peak_stress",)
"""|peak fibre stress at full load - the reference's| / the reference's, percent."""
PARASITIC_METRICS = ("parasitic",)
"""The largest error of the target's parasitic components at full load, each against the
reference's own value, percent (:mod:`flexval.validation.studies.parasitic`)."""
LIMIT_METRICS = ("limit_load",)
"""|first critical load - the reference's| / the reference's, percent (the report's limit
loads and bifurcations: :func:`flexval.validation.studies.gatemetrics.critical_load`)."""
FREQUENCY_METRICS = ("frequency",)
"""The largest |f_k - f_k,ref| / f_k,ref over the lowest ``modes`` natural frequencies at
rest, percent (the report's natural-frequency table: one check per scene, not per case)."""
METRICS = PATH_METRICS + STRESS_METRICS + PARASITIC_METRICS + LIMIT_METRICS + FREQUENCY_METRICS
"""The metrics a gate checks, in the order of its tables."""

_METRIC_TEXT = {
    "end_disp": "|end displacement| (magnitude) error",
    "end_disp_vec": "end displacement vector error",
    "end_rot": "end rotation error",
    "path_disp": "largest displacement error along the path, of the largest reference one",
    "path_rot": "largest rotation error along the path, of the largest reference one",
    "peak_stress": "error of the peak outer-fibre stress at full load",
    "parasitic": "largest error of the parasitic motion at full load (across a force and the "
    "rotation; the translation under a moment), each component against the reference's own "
    "value; passes with nothing to score where the reference's is round-off or the load case "
    "has several loads",
    "limit_load": "error of the first critical load (limit or bifurcation point) within the "
    "full load; passes where neither model has one, fails where only one has",
    "frequency": "largest error of the lowest `modes` natural frequencies at rest, each "
    "against the reference's of the same rank (one check per scene)",
}

GATES = Table(
    "",
    "The reference, the scenes and load cases every gate is checked on.",
    (
        Field("reference", "text", "model id every error is measured against"),
        Field(
            "scenes",
            "texts",
            "built-in scene names or scene file paths (relative to the gates file)",
        ),
        Field(
            "load_cases",
            "texts",
            "load cases checked (each must be in every scene)",
            default=ABSENT,
            default_text="all of each scene's",
        ),
        Field("gates", "tables", "one table per model and its thresholds"),
    ),
)
"""The top level of a gates file."""

GATE = Table(
    "gates",
    "One model and the largest error it may have on every load case of every scene, per "
    "metric (at least one metric). A model that does not reach full load fails all of its "
    "gates on that load case but `limit_load`.",
    (Field("model", "text", "model id of the model gated (not the reference)"),)
    + tuple(
        Field(m, "number", _METRIC_TEXT[m], unit="%", default=ABSENT, minimum=0.0) for m in METRICS
    )
    + (
        Field(
            "modes",
            "integer",
            "how many of the lowest natural frequencies `frequency` compares (only with it)",
            default=MODE_COUNT,
            minimum=1,
            maximum=MAX_MODES,
        ),
    ),
    array=True,
)
"""One ``[[gates]]`` entry."""


@dataclass(frozen=True)
class Gate:
    """One model and its thresholds (percent), by metric in :data:`METRICS` order, and how
    many natural frequencies its ``frequency`` threshold covers."""

    model: ModelSpec
    thresholds: dict[str, float]
    modes: int = MODE_COUNT


@dataclass(frozen=True)
class GateFile:
    """A checked gates file.

    Attributes
    ----------
    source : str
        The file, for messages.
    reference : ModelSpec
    scenes : tuple of Scene
    cases : dict of str -> tuple of str
        Scene name -> the load cases checked on it.
    gates : tuple of Gate
    """

    source: str
    reference: ModelSpec
    scenes: tuple[Scene, ...]
    cases: dict[str, tuple[str, ...]]
    gates: tuple[Gate, ...]


def _fail(source: str, field: str, value: Any, reason: str) -> None:
    raise SceneError(source, field, value, reason)


def _unknown(table: Table, data: dict, source: str, prefix: str) -> None:
    known = table.keys()
    for key in data:
        if key not in known:
            _fail(
                source,
                prefix + key,
                data[key],
                f"unknown field{did_you_mean(key, known)}; expected one of {sorted(known)}",
            )


def _texts(data: dict, name: str, source: str) -> list[str]:
    value = data.get(name)
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        _fail(source, name, value, "must be a non-empty list of strings")
    return value


def _scene(text: str, folder: Path, source: str) -> Scene:
    if text in BUILTIN_SCENES:
        return load_scene(text)
    path = Path(text) if Path(text).is_absolute() else folder / text
    if not path.is_file():
        known = list(BUILTIN_SCENES)
        _fail(source, "scenes", text, f"no such scene file, and not a built-in scene {known}")
    return load_scene(path)


def _gate(k: int, entry: Any, reference: ModelSpec, source: str) -> Gate:
    where = f"gates[{k}]"
    if not isinstance(entry, dict):
        _fail(source, where, entry, "must be a table [[gates]]")
    _unknown(GATE, entry, source, where + ".")
    if "model" not in entry:
        _fail(source, where + ".model", None, "missing: the model id gated")
    spec = parse_model(entry["model"], source, where + ".model")
    if spec == reference:
        _fail(source, where + ".model", spec.id, "is the reference; it is not compared with itself")
    thresholds = {}
    for name in METRICS:
        if name not in entry:
            continue
        value = entry[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            _fail(source, f"{where}.{name}", value, "must be a number (percent)")
        if not (math.isfinite(value) and value >= 0.0):
            _fail(source, f"{where}.{name}", value, "must be a finite number >= 0 (percent)")
        thresholds[name] = float(value)
    if not thresholds:
        _fail(source, where, spec.id, f"gives no threshold; give one or more of {list(METRICS)}")
    return Gate(spec, thresholds, _modes(entry, where, source))


def _modes(entry: dict, where: str, source: str) -> int:
    if "modes" not in entry:
        return MODE_COUNT
    value = entry["modes"]
    if "frequency" not in entry:
        _fail(source, f"{where}.modes", value, "is given without a frequency threshold")
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_MODES:
        _fail(source, f"{where}.modes", value, f"must be an integer from 1 to {MAX_MODES}")
    return value


def parse_gates(data: dict, source: str, folder: Path = Path(".")) -> GateFile:
    """Check a parsed gates file and load its scenes (nothing is run).

    Raises
    ------
    SceneError
        For a bad field (unknown field, model or metric, a scene or load case
        that does not exist), naming the field and the value.
    """
    _unknown(GATES, data, source, "")
    for name in ("reference", "scenes", "gates"):
        if name not in data:
            _fail(source, name, None, f"missing: {GATES[name].description}")
    reference = parse_model(data["reference"], source, "reference")
    scenes = tuple(_scene(s, folder, source) for s in _texts(data, "scenes", source))
    if len({s.name for s in scenes}) != len(scenes):
        _fail(source, "scenes", data["scenes"], "lists a scene twice")
    cases: dict[str, tuple[str, ...]] = {}
    wanted = _texts(data, "load_cases", source) if "load_cases" in data else None
    for scene in scenes:
        names = [c.name for c in scene.load_cases]
        for c in wanted or ():
            if c not in names:
                reason = f"scene {scene.name!r} has no such load case: it has {names}"
                _fail(source, "load_cases", c, reason)
        cases[scene.name] = tuple(wanted or names)
    raw = data["gates"]
    if not isinstance(raw, list) or not raw:
        _fail(source, "gates", raw, "must be one or more tables [[gates]]")
    gates = tuple(_gate(k, g, reference, source) for k, g in enumerate(raw))
    ids = [g.model.id for g in gates]
    if len(set(ids)) != len(ids):
        _fail(source, "gates", ids, "gates a model twice; give all its thresholds in one table")
    return GateFile(source, reference, scenes, cases, gates)


def load_gates(path: str | Path) -> GateFile:
    """Read and check the gates file ``path`` (scene paths relative to its folder).

    Raises
    ------
    SceneError
        If the file is missing or malformed, or any field is bad.
    """
    path = Path(path)
    if not path.is_file():
        _fail(str(path), "gates file", str(path), "no such file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        _fail(str(path), "toml", None, f"malformed TOML: {exc}")
    return parse_gates(data, str(path), path.parent)


_RULES = """\
Thresholds are in percent, the unit of the error metrics (see the report's
error tables): a gate holds on a load case when the model's error is at most
its threshold. Every gate is checked on every listed load case of every
scene (`frequency` once per scene: the natural frequencies at rest do not
depend on the load case). A field no table declares and an unknown model id
are refused, naming them (exit code 2).

`limit_load` compares the first critical load on each load case, a limit
point or a bifurcation point, whichever comes first, found as the report's
limit-load table finds it: a path that stops short of full load is searched
by arc length. Where neither the model nor the reference reaches one within
the full load the check passes and says so; where only one does it fails.
`frequency` compares the lowest `modes` natural frequencies at rest with the
flexure density the report uses: the scene's `material.density`, else PLA's.
"""


def field_reference(level: int = 2) -> str:
    """The gates file reference: every field of :data:`GATES` and :data:`GATE`, as Markdown."""
    h = "#" * level
    return "\n\n".join(
        [
            _RULES,
            f"{h} Top level {{#gates-top}}",
            GATES.description,
            markdown_table(GATES),
            f"{h} `[[gates]]` {{#gates-gates}}",
            GATE.description,
            markdown_table(GATE),
        ]
    )
