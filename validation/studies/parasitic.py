"""Parasitic motion: the target's motion in the directions its load does not push.

A stage pushed along x should move along x; its motion along y and its
rotation are *parasitic*, often a thousand times smaller, and often what a
designer must bound. The path metrics of :mod:`flexval.validation.studies.compare`
measure a model's error against the whole motion (the vector |d| and the
rotation against their own size or the mechanism's), so a model that
predicts no parasitic motion at all scores a fraction of a percent where it
is 100 % off in that component. This module measures each component apart:

* the **parasitic components** of a load case: for a single force, the
  target's translation across the force and its rotation; for a single
  moment, the target's translation (dx and dy); for a prescribed motion of
  the target point, the components it leaves free (along its frame's axes,
  and the rotation); a case of several loads has none named;
* each component's error at full load against the reference's own value of
  that component (100 % for a model that predicts 0), in percent, and its
  largest difference over the path in its own unit (mm, rad);
* a reference component smaller than :data:`ROUND_OFF_FLOOR` of the
  mechanism's motion is round-off, not motion: it is reported, never scored.

Units: mm, rad; errors in percent.
"""

from __future__ import annotations

import math

import numpy as np

from flexval.geometry import Displacement, Force, LoadCase, Moment
from flexval.reducedmodels import LoadPath

from .compare import on_reference_levels

ROUND_OFF_FLOOR = 1e-9
"""A reference component below this fraction of the mechanism's motion (the largest of the
target's translation and its rotation times the mechanism's size) is round-off: solvers'
states are converged to about 1e-10 of the size, so anything smaller is no motion at all."""


def parasitic_components(
    case: LoadCase, target: tuple[str, np.ndarray] | None = None
) -> list[tuple[str, np.ndarray | None]]:
    """The parasitic components of ``case``: (name, unit vector in the (dx, dy) plane, or None
    for the rotation). A single force along u: the translation across u (``across``, along
    u rotated by +90 deg) and the rotation; a single moment: dx and dy; a prescribed motion
    of ``target`` (its body and point, mm), those it leaves free (``dx``/``dy`` along its
    frame's axes, ``rotation``); several loads: none."""
    if len(case.components) != 1:
        return []
    load = case.components[0]
    if isinstance(load, Displacement):
        if target is None or load.body != target[0] or not np.allclose(load.point, target[1]):
            return []
        c, s = math.cos(load.angle), math.sin(load.angle)
        axes = (("dx", np.array([c, s])), ("dy", np.array([-s, c])), ("rotation", None))
        held = {k for k, _ in load.prescribed}
        return [axis for k, axis in enumerate(axes) if k not in held]
    if isinstance(load, Force):
        across = np.array([-math.sin(load.angle), math.cos(load.angle)])
        return [("across", across), ("rotation", None)]
    if isinstance(load, Moment):
        return [("dx", np.array([1.0, 0.0])), ("dy", np.array([0.0, 1.0]))]
    return []


def _component(path_dx, path_dy, rotation, direction: np.ndarray | None) -> np.ndarray:
    if direction is None:
        return np.asarray(rotation, float)
    return direction[0] * np.asarray(path_dx, float) + direction[1] * np.asarray(path_dy, float)


def motion_scale(ref: LoadPath, size: float) -> float:
    """The mechanism's motion on ``ref`` (mm): the largest of the target's translation and its
    rotation times the mechanism's ``size`` (mm), over the path."""
    d = np.hypot(np.asarray(ref.dx), np.asarray(ref.dy))
    return float(max(d.max(initial=0.0), np.abs(ref.rotation).max(initial=0.0) * size))


def parasitic_errors(
    model: LoadPath,
    ref: LoadPath,
    case: LoadCase,
    size: float,
    target: tuple[str, np.ndarray] | None = None,
) -> list[dict]:
    """Each parasitic component of ``case`` (:func:`parasitic_components`; ``target`` the
    mechanism's target body and point) of ``model`` against
    ``ref`` (both paths to full load, on the same case): ``component``, ``unit`` (mm or rad),
    ``reference`` and ``model`` at full load, ``end`` (percent of the reference's value, None
    where that is round-off), ``path`` (the largest difference over the path, in the unit)
    and ``scored`` (False where the reference's component is round-off)."""
    dx, dy, rot = on_reference_levels(model, ref)
    floor = ROUND_OFF_FLOOR * motion_scale(ref, size)
    rows = []
    for name, direction in parasitic_components(case, target):
        theirs = _component(ref.dx, ref.dy, ref.rotation, direction)
        ours = _component(dx, dy, rot, direction)
        unit_floor = floor if direction is not None else floor / size
        scored = bool(abs(theirs[-1]) > unit_floor)
        rows.append(
            {
                "component": name,
                "unit": "rad" if direction is None else "mm",
                "reference": float(theirs[-1]),
                "model": float(ours[-1]),
                "end": 100.0 * abs(ours[-1] - theirs[-1]) / abs(theirs[-1]) if scored else None,
                "path": float(np.abs(ours - theirs).max()),
                "scored": scored,
            }
        )
    return rows


def largest_parasitic_error(model: LoadPath, ref: LoadPath, scene, case: LoadCase) -> float | None:
    """The largest end error (percent) of the target's parasitic components of ``case`` on
    ``scene``, each against the reference's own value (:func:`parasitic_errors`); None where
    none is scored (no parasitic component, or the reference's is round-off). The gates'
    and the sweeps' ``parasitic`` metric."""
    mech = scene.mechanism
    rows = parasitic_errors(model, ref, case, mech.size(), (mech.target_body, mech.target_point))
    scored = [r["end"] for r in rows if r["scored"]]
    return max(scored) if scored else None


def section(res, reference: str) -> list[str]:
    """Markdown: the parasitic motion of every load case of a scene's results ``res``
    (:class:`flexval.validation.report.data.SceneResults`) against ``reference``: the
    reference's value of each component at full load, and each model's, with its error in
    percent of that value (a model that predicts none is 100 % off) and the largest
    difference over the path; nothing where no load case has a parasitic component."""
    mech = res.scene.mechanism
    size, target = mech.size(), (mech.target_body, mech.target_point)
    lines: list[str] = []
    for c in res.cases:
        case, ref = res.scene.load_case(c), res.converged(reference, c)
        if ref is None or not parasitic_components(case, target):
            continue
        rows = []
        for m in res.models:
            lp = res.converged(m, c)
            if m == reference or lp is None:
                continue
            for e in parasitic_errors(lp, ref, case, size, target):
                end = f"{e['end']:.2f}" if e["scored"] else "round-off"
                rows.append(
                    f"| {m} | {e['component']} ({e['unit']}) | {e['model']:.4g} | {end} | "
                    f"{e['path']:.3g} |"
                )
        if not rows:
            continue
        names = ", ".join(
            f"{e['component']} {e['reference']:.4g} {e['unit']}"
            for e in parasitic_errors(ref, ref, case, size, target)
        )
        lines += [f"`{c}` — `{reference}`: {names} at full load.", ""]
        lines += [
            "| model | component | at full load | error (% of the reference's) | "
            "largest difference over the path |",
            "|---|---|---:|---:|---:|",
            *rows,
            "",
        ]
    if not lines:
        return []
    return [
        "### Parasitic motion",
        "",
        "The target's motion across its load (a force: the translation across it and the "
        "rotation; a moment: dx and dy; a prescribed motion: the components it leaves free), "
        "each component against the reference's own value of "
        "it: the path metrics above measure it against the whole motion, where a model that "
        f"predicts none looks a fraction of a percent off. A reference component below "
        f"{ROUND_OFF_FLOOR:g} of the mechanism's motion is round-off, not scored.",
        "",
        *lines,
    ]
