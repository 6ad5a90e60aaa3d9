"""The report's first-yield tables of a scene whose material has a yield strength.

Per model and load case: the load at first yield, its fraction of the full
load, the target's displacement and rotation there, and the error of the yield
load against the reference's (:func:`flexval.validation.studies.yieldpoint.path_yield`
on each path); then the safety factors at full load. Scenes without a yield
strength get no section, so their report does not change.

Units: N or N mm, mm, degrees (printed), MPa.
"""

from __future__ import annotations

import math

from flexval.geometry import Scene
from flexval.reducedmodels import LoadPath

from ..studies.yieldpoint import scene_yield


def yield_data(
    scene: Scene,
    paths: dict[tuple[str, str], LoadPath],
    models: list[str],
    cases: list[str],
    reference: str,
) -> dict[str, dict[str, dict]]:
    """{model: {case: path_yield + "unit", "error_percent"}} of every path of ``scene``.

    ``error_percent``: (model - reference) / reference yield load in percent,
    None when either has no first yield. Empty when the scene's material has no
    yield strength.
    """
    if scene.mechanism.material.yield_strength is None:
        return {}
    found = {
        (m, c): {**scene_yield(scene, paths[(m, c)]), "unit": paths[(m, c)].load_unit}
        for m in models
        for c in cases
        if (m, c) in paths
    }
    out: dict[str, dict[str, dict]] = {}
    for (m, c), v in found.items():
        ref = found.get((reference, c), {}).get("first_yield")
        fy = v["first_yield"]
        v["error_percent"] = (
            100.0 * (fy["load"] - ref["load"]) / ref["load"]
            if fy and ref and m != reference
            else None
        )
        out.setdefault(m, {})[c] = v
    return out


def _yield_cell(v: dict | None) -> str:
    if v is None:
        return "—"
    fy = v["first_yield"]
    if fy is None:
        return f"— ({v['yield_note']})" if v["yield_note"] else "none"
    text = (
        f"{fy['load']:.4g} {v['unit']} ({100 * fy['fraction']:.1f} %), "
        f"{math.hypot(fy['dx'], fy['dy']):.4g} mm, {math.degrees(fy['rotation']):.3g}°"
    )
    err = v.get("error_percent")
    return text if err is None else f"{text}; load {err:+.2f} %"


def _safety_cell(v: dict | None) -> str:
    if v is None or v["safety_factor"]["yield"] is None:
        return "—"
    f = v["safety_factor"]
    return f"{f['yield']:.3g}" + ("" if f["fatigue"] is None else f" / {f['fatigue']:.3g}")


def yield_section(
    scene: Scene,
    paths: dict[tuple[str, str], LoadPath],
    models: list[str],
    cases: list[str],
    reference: str,
) -> list[str]:
    """Markdown: the first-yield table and the safety factors (empty without a yield strength)."""
    data = yield_data(scene, paths, models, cases, reference)
    if not data:
        return []
    material = scene.mechanism.material
    fatigue = material.fatigue_strength
    head = ["| model | " + " | ".join(cases) + " |", "|---|" + "---:|" * len(cases)]
    lines = [
        f"### Load and target displacement at first yield against `{reference}`",
        "",
        f"Yield strength {material.yield_strength:g} MPa"
        + (f", fatigue strength {fatigue:g} MPa" if fatigue is not None else "")
        + ". First yield: where the peak stress above (each model's own section forces "
        "through the beam formula) first reaches the yield strength, interpolated linearly "
        "between load levels; the load, its percent of the full load, the target's "
        "displacement magnitude and rotation there, and the load's error against the "
        "reference's (none: the full load stays below the yield strength).",
        "",
        *head,
    ]
    for m, row in data.items():
        lines.append(f"| `{m}` | " + " | ".join(_yield_cell(row.get(c)) for c in cases) + " |")
    lines += [
        "",
        "Safety factor at full load: yield strength over the peak stress"
        + (" (and fatigue strength over it)" if fatigue is not None else "")
        + ".",
        "",
        *head,
    ]
    for m, row in data.items():
        lines.append(f"| `{m}` | " + " | ".join(_safety_cell(row.get(c)) for c in cases) + " |")
    return lines + [""]
