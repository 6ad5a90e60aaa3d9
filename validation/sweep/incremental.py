"""Point scenes built from the checked base scene by replacing values, without a parse.

A sweep point's scene is, by definition, the base scene's data with the axis values
written in and loaded by :func:`flexval.geometry.scene.parse_scene`, every check
included, which on the open chain costs more than its reduced models. When every
axis addresses one of the *value fields* below, a point differs from the base scene in
those values only (the same shapes, bodies, attachments and load geometry), and
:class:`IncrementalBuilder` builds its scene from the parsed base scene by replacing them
(:func:`dataclasses.replace` of the flexures' sections, the material, the loads):

- ``section.thickness`` and ``section.depth``: the flexures that take the default (a
  notch's smallest thickness, and a depth where a body's outline takes it, excepted);
- ``flexures.<name>.thickness`` (a number, not a notch's) and ``flexures.<name>.depth``;
- ``material.youngs_modulus`` and ``material.poisson_ratio``;
- ``load_cases.<name>.value`` and ``load_cases.<name>.loads.<i>.value``.

It never decides that a point is invalid: it proves points valid, and every point it
cannot prove is parsed in full, which refuses it with its own message. The proof rests on
one property of the checks that read these fields: each is monotone in each of them.
The number checks (finite, positive, not subnormal, inside the field's bounds) accept an
interval on each side of zero; a thickness must stay below twice an arc's radius or a
spline's radius of curvature, and below the gap between an arc's ends; the derived
magnitudes (:func:`flexval.geometry.magnitudes.check_magnitudes`: EI, EA, L / EI, w a^2,
...) are products of powers of the values, each between two bounds. A check monotone in
each value that holds at the 2^k corners of a box of values holds everywhere inside it;
so a box none of whose sides touches zero is proven by the full parse of its corners, and
its points are valid. A block's points outside the proven boxes are split at the median
of their widest axis until each part's box is proven or holds fewer than
:data:`MIN_BOX_POINTS` points, which are parsed one by one.

Units: those of the fields (mm, MPa, N, N mm).
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import itertools
import json
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from flexval.geometry import Scene, SceneError

MIN_BOX_POINTS = 8
"""Fewest points whose box is proven (2^k full parses, k axes); fewer are parsed one by
one, which costs no more."""
MAX_BOX_AXES = 6
"""Most axes of an incremental build: a box's proof parses its 2^k corners (64 at most)."""
MAX_BOXES = 64
"""Most proven boxes one builder keeps (a few per block at most: the values of a sweep
fill a few boxes); past it the points outside them are parsed."""
KEPT_BUILDERS = 8
"""Incremental builders a process keeps (one per sweep it works on)."""


@dataclass(frozen=True)
class _Edit:
    """Where an axis value goes in a scene: the sections of the flexures ``where`` (field
    ``attr``), the material (``attr``), or the load ``where`` = (case, component)."""

    kind: str
    where: tuple[int, ...]
    attr: str


def _named(items: Any, name: str) -> int | None:
    """Position of the first table of ``items`` named ``name`` (as the sweep's path walk)."""
    if not isinstance(items, list):
        return None
    return next(
        (k for k, x in enumerate(items) if isinstance(x, dict) and str(x.get("name")) == name),
        None,
    )


def _edit(base: dict, path: str, paths: Sequence[str]) -> _Edit | None:
    """The edit of the value field ``path`` of the base scene data ``base``, or None when
    the path is not a value field there (see the module's list)."""
    parts = path.split(".")
    flexures = base.get("flexures")
    if not isinstance(flexures, list) or not all(isinstance(f, dict) for f in flexures):
        return None
    bodies = base.get("bodies", [])
    outlines = isinstance(bodies, list) and any(
        isinstance(b, dict) and "outline" in b for b in bodies
    )
    if len(parts) == 2 and parts[0] == "section" and parts[1] in ("thickness", "depth"):
        attr = parts[1]
        own = {
            p.split(".")[1] for p in paths if p.startswith("flexures.") and p.endswith("." + attr)
        }
        taking = tuple(
            k for k, f in enumerate(flexures) if attr not in f and str(f.get("name")) not in own
        )
        if attr == "thickness" and any(flexures[k].get("shape") == "notch" for k in taking):
            return None
        if attr == "depth" and outlines:
            return None
        return _Edit("section", taking, attr)
    if len(parts) == 3 and parts[0] == "flexures" and parts[2] in ("thickness", "depth"):
        k = _named(flexures, parts[1])
        if k is None:
            return None
        f = flexures[k]
        if parts[2] == "thickness" and (
            f.get("shape") == "notch" or not isinstance(f.get("thickness", 0.0), (int, float))
        ):
            return None
        return _Edit("section", (k,), parts[2])
    if (
        len(parts) == 2
        and parts[0] == "material"
        and parts[1] in ("youngs_modulus", "poisson_ratio")
    ):
        return _Edit("material", (), parts[1])
    if parts[0] == "load_cases" and len(parts) in (3, 5) and parts[-1] == "value":
        c = _named(base.get("load_cases"), parts[1])
        if c is None:
            return None
        case = base["load_cases"][c]
        if len(parts) == 3 and "loads" not in case:
            return _Edit("load", (c, 0), "value")
        loads = case.get("loads")
        if (
            len(parts) == 5
            and parts[2] == "loads"
            and parts[3].isdigit()
            and isinstance(loads, list)
        ):
            i = int(parts[3])
            return _Edit("load", (c, i), "value") if i < len(loads) else None
    return None


class IncrementalBuilder:
    """Scenes of a sweep's points from its parsed base scene, where every axis is a value
    field (:func:`edits_of`); see the module.

    Parameters
    ----------
    template : Scene
        The base scene, parsed (the point scenes share its shapes, bodies and loads).
    edits : list of _Edit
        Where each axis's value goes, in axis order.
    parse : callable
        The full build of the scene of some axis values (raises SceneError): the proof of
        a box parses its corners with it.
    """

    def __init__(self, template: Scene, edits: list[_Edit], parse: Callable[[tuple], Scene]):
        self.template, self.edits, self._parse = template, edits, parse
        self.boxes: list[tuple[np.ndarray, np.ndarray]] = []

    def scene(self, values: Sequence[float], source: str) -> Scene:
        """The scene of the point with the axis ``values`` (proven valid by :meth:`proven`),
        with ``source`` as its source (the label a full parse gives it)."""
        t = self.template
        mech = t.mechanism
        sections = [f.section for f in mech.flexures]
        material = mech.material
        loads = [list(lc.components) for lc in t.load_cases]
        for e, v in zip(self.edits, values):
            v = float(v)
            if e.kind == "section":
                for k in e.where:
                    sections[k] = dataclasses.replace(sections[k], **{e.attr: v})
            elif e.kind == "material":
                material = dataclasses.replace(material, **{e.attr: v})
            else:
                c, i = e.where
                loads[c][i] = dataclasses.replace(loads[c][i], value=v)
        flexures = tuple(
            f if s is f.section else dataclasses.replace(f, section=s)
            for f, s in zip(mech.flexures, sections)
        )
        mech = dataclasses.replace(mech, flexures=flexures, material=material, source=source)
        cases = tuple(
            lc
            if all(a is b for a, b in zip(comps, lc.components))
            else dataclasses.replace(lc, components=tuple(comps))
            for lc, comps in zip(t.load_cases, loads)
        )
        return dataclasses.replace(t, mechanism=mech, load_cases=cases, source=source)

    def proven(self, values: np.ndarray) -> np.ndarray:
        """Which rows of ``values`` (points x axes) lie in a proven box, proving the boxes of
        those that do not first (see the module)."""
        values = np.asarray(values, dtype=float).reshape(len(values), len(self.edits))
        inside = self._inside(values)
        if not inside.all():
            self._prove(values[~inside])
            inside = self._inside(values)
        return inside

    def _inside(self, values: np.ndarray) -> np.ndarray:
        inside = np.zeros(len(values), dtype=bool)
        for lo, hi in self.boxes:
            inside |= np.all((values >= lo) & (values <= hi), axis=1)
        return inside

    def _prove(self, values: np.ndarray) -> None:
        """Prove the box of ``values``, or split them at the median of their widest axis."""
        if len(values) < MIN_BOX_POINTS or len(self.boxes) >= MAX_BOXES:
            return
        lo, hi = values.min(axis=0), values.max(axis=0)
        if self._holds(lo, hi):
            self.boxes.append((lo, hi))
            return
        scale = np.maximum(np.maximum(np.abs(lo), np.abs(hi)), np.finfo(float).tiny)
        j = int(np.argmax((hi - lo) / scale))
        cut = np.median(values[:, j])
        below = values[:, j] <= cut
        if below.all():
            below = values[:, j] < cut
        if below.all() or not below.any():
            return  # every value of the widest axis is the same: nothing to split
        self._prove(values[below])
        self._prove(values[~below])

    def _holds(self, lo: np.ndarray, hi: np.ndarray) -> bool:
        """Whether the full parse accepts every corner of the box [lo, hi], no side of
        which touches zero."""
        if np.any(lo * hi <= 0.0):
            return False
        for corner in sorted(set(itertools.product(*zip(lo.tolist(), hi.tolist())))):
            try:
                self._parse(corner)
            except SceneError:
                return False
        return True


def edits_of(base: dict, paths: Sequence[str]) -> list[_Edit] | None:
    """Where each axis of ``paths`` goes in the scene of the base data ``base``, or None
    when an axis is not a value field (or there are too many, or the scene reads files
    relative to its source: ``measurements``)."""
    if not paths or len(paths) > MAX_BOX_AXES or "measurements" in base:
        return None
    edits = [_edit(base, p, paths) for p in paths]
    return None if any(e is None for e in edits) else edits


_KEPT: OrderedDict[str, IncrementalBuilder | None] = OrderedDict()
_LOCK = threading.Lock()


def builder_key(base: dict, paths: Sequence[str], *labels: Any) -> str:
    """A key of the base data, the axes and the labels that name the scenes: equal keys
    build equal scenes (the tasks of one sweep on a worker share one builder)."""
    text = json.dumps([base, list(paths), [str(x) for x in labels]], sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def incremental_builder(
    key: str,
    base: dict,
    paths: Sequence[str],
    template: Callable[[dict], Scene],
    parse: Callable[[tuple], Scene],
) -> IncrementalBuilder | None:
    """This process's incremental builder of ``key`` (made on first use, the base scene
    parsed by ``template`` from a copy of ``base``), or None when an axis of ``paths`` is
    not a value field of ``base``."""
    with _LOCK:  # a worker of an external cluster may run tasks in threads
        if key in _KEPT:
            _KEPT.move_to_end(key)
            return _KEPT[key]
        edits = edits_of(base, paths)
        built = None
        if edits is not None:
            built = IncrementalBuilder(template(copy.deepcopy(base)), edits, parse)
        _KEPT[key] = built
        while len(_KEPT) > KEPT_BUILDERS:
            _KEPT.popitem(last=False)
        return built
