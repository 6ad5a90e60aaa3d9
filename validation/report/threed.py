"""The report's section "2D idealisation against 3D", read from ``threed.json``.

Every reduced model uses E·I, the narrow-beam (plane-stress) idealisation,
and the report's continuum reference is plane stress by default. A flexure
several thicknesses wide lies between plane stress and plane strain, by how
much its anticlastic curvature is suppressed (Searle's parameter b²/(R h)).
``benchmarks/threed_study.py`` runs the 3D solid reference
``continuum:L[3d]`` on the paper scenes' load cases, next to both 2D
idealisations and the reduced models with and without their width options;
the 3D solves take minutes, too long for ``flexval report``. It writes
``threed.json`` (format :data:`THREED_FORMAT`, no timings) and its full
table ``threed.md``; :func:`threed_section` renders one scene's section from
the file: where the 3D answer lies between the two idealisations on each
case, how much it changed between the two finest 3D levels, and each reduced
model's error against it, with the option closest to it.

File contents (lengths mm, rotations rad, errors percent)::

    {"format": "flexval-threed/1", "code_version": "<hash>",
     "planes": {"stress": "continuum:1", "strain": "continuum:1[plane=strain]"},
     "scenes": {"open_chain": {
        "depth": 1.0, "thickness": 0.1, "searle": {"e12": 3.33, ...},
        "cases": {"m+": {
            "threed": [{"model": "continuum:0[3d]", "level": 0, "unknowns": 51234,
                        "dx": ..., "dy": ..., "rot": ..., "failure": null}, ...],
            "planes": {"stress": {"dx": ..., "dy": ..., "rot": ...},
                       "strain": {...}},
            "errors": {"continuum:1": {"end_disp_vec": ..., "end_rot": ...},
                       "beam:100[plate]": {...}, ...}}}}}}

``threed`` lists the levels coarse to fine; the finest that reached full
load is the reference of ``errors`` (every 2D and reduced model's end-of-load
error against it, :func:`flexval.validation.studies.compare.errors`); a failed run
has null values and its ``failure``.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..studies.studyfile import read_study, stale_lines

THREED_FORMAT = "flexval-threed/1"
"""Format tag of ``threed.json``."""
REQUIRED = ("code_version", "planes", "scenes")
"""Fields the section reads."""
REFRESH = "python benchmarks/threed_study.py"
PRODUCE = (
    f"`{REFRESH}` (writes `reports/threed/threed.json`; tens of minutes), then "
    "`flexval report --threed reports/threed/threed.json`"
)
"""How to produce the file the section is rendered from."""
SAME_SPREAD = 1e-9
"""Relative spread of the two idealisations below which the 3D answer's position between
them is not stated (they coincide: a case without bending)."""


def read_threed(path: Path) -> tuple[dict | None, str | None]:
    """The 3D study document at ``path``, or None and the reason it cannot be used."""
    doc, why = read_study(path, THREED_FORMAT, REQUIRED)
    if doc is None:
        return None, why
    try:
        for scene in doc["scenes"].values():
            for case in scene["cases"].values():
                _finest(case)
                _end(case["planes"]["stress"])
                _end(case["planes"]["strain"])
                for e in case["errors"].values():
                    float(e["end_disp_vec"]), float(e["end_rot"])
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        return None, f"`{path.as_posix()}` has a malformed entry ({type(exc).__name__}: {exc})"
    return doc, None


def _end(values: dict) -> tuple[float, float]:
    """(|d| mm, rotation rad) of an end-of-load entry."""
    return math.hypot(float(values["dx"]), float(values["dy"])), float(values["rot"])


def _finest(case: dict) -> tuple[dict | None, dict | None]:
    """The finest and the next finer 3D runs that reached full load (None where absent)."""
    done = [r for r in case["threed"] if r.get("failure") is None and r.get("dx") is not None]
    done.sort(key=lambda r: int(r["level"]))
    return (done[-1] if done else None), (done[-2] if len(done) > 1 else None)


def position(value: float, stress: float, strain: float) -> float | None:
    """Where ``value`` lies between the plane-stress and plane-strain values: 0 at plane
    stress, 1 at plane strain (outside [0, 1]: beyond them); None when the two coincide."""
    if abs(strain - stress) <= SAME_SPREAD * max(abs(stress), abs(strain)):
        return None
    return (value - stress) / (strain - stress)


def _closer(t: float | None) -> str:
    if t is None:
        return "either (they coincide)"
    return "plane stress" if t < 0.5 else "plane strain"


def _fmt(t: float | None) -> str:
    return "–" if t is None else f"{t:.2f}"


def _change(fine: dict, coarse: dict | None) -> str:
    """Percent change of |d| from the coarser to the finer 3D level ("–" without two)."""
    if coarse is None:
        return "–"
    d_f, d_c = _end(fine)[0], _end(coarse)[0]
    return f"{100 * abs(d_f - d_c) / d_f:.3f}"


def _bracket_rows(cases: dict) -> tuple[list[str], dict[str, str]]:
    """Table rows of the 3D answer between the idealisations, and the closer one by case."""
    rows, closer = [], {}
    for name, case in cases.items():
        fine, coarse = _finest(case)
        if fine is None:
            why = "; ".join(str(r.get("failure")) for r in case["threed"]) or "not run"
            rows.append(f"| {name} | failed: {why} | | | | | | | |")
            continue
        d3, r3 = _end(fine)
        ds, rs = _end(case["planes"]["stress"])
        dp, rp = _end(case["planes"]["strain"])
        t_d, t_r = position(d3, ds, dp), position(r3, rs, rp)
        closer[name] = _closer(t_d)
        rows.append(
            f"| {name} | {int(fine['level'])} | {d3:.6g} | {_change(fine, coarse)} | {ds:.6g} | "
            f"{dp:.6g} | "
            f"{_fmt(t_d)} | {_fmt(t_r)} | {closer[name]} |"
        )
    return rows, closer


def _verdict(cases: dict, closer: dict[str, str]) -> str:
    """One sentence: the range of the 3D answer's position and the closer idealisation."""
    where = []
    for case in cases.values():
        fine, _ = _finest(case)
        stress, strain = _end(case["planes"]["stress"]), _end(case["planes"]["strain"])
        t = position(_end(fine)[0], stress[0], strain[0])
        if t is not None:
            where.append(t)
    sides = sorted(set(closer.values()))
    span = f"{min(where):.2f}–{max(where):.2f}" if where else "–"
    side = (
        f"closer to {sides[0]} on every case"
        if len(sides) == 1
        else "closer to " + ", ".join(f"{v} on {k}" for k, v in closer.items())
    )
    return f"The 3D target |d| lies {span} of the way from plane stress to plane strain: {side}."


def _reference_note(cases: dict, reference: str) -> str:
    """One sentence: how far the plane-stress continuum itself is from 3D (empty without)."""
    errs = [
        c["errors"][reference]["end_disp_vec"] for c in cases.values() if reference in c["errors"]
    ]
    if not errs:
        return ""
    return (
        f" The plane-stress continuum `{reference}`, the report's reference, is itself "
        f"{min(errs):.2f}–{max(errs):.2f} % from 3D in the target displacement: reduced-model "
        "errors against it below that size measure agreement within the idealisation."
    )


def _model_rows(cases: dict, planes: set[str]) -> tuple[list[str], list[str]]:
    """Each 2D or reduced model's end errors against 3D by case, and the lines naming the
    closest option of each base model (the id before ``[``) per case, the 2D ``planes``
    left out of the latter (the bracket table compares them)."""
    models = list(dict.fromkeys(m for c in cases.values() for m in c["errors"]))
    rows = []
    for m in models:
        cells = []
        for c in cases.values():
            e = c["errors"].get(m)
            cells.append("–" if e is None else f"{e['end_disp_vec']:.2f} / {e['end_rot']:.2f}")
        rows.append(f"| `{m}` | " + " | ".join(cells) + " |")
    best = []
    bases = dict.fromkeys(m.split("[")[0] for m in models)
    for base in bases:
        variants = [m for m in models if m.split("[")[0] == base and m not in planes]
        if len(variants) < 2:
            continue
        picks = []
        for name, c in cases.items():
            have = [m for m in variants if m in c["errors"]]
            if have:
                top = min(have, key=lambda m: max(c["errors"][m].values()))
                picks.append(f"{name}: `{top}`")
        best.append(f"- `{base}`: " + ", ".join(picks) + ".")
    return rows, best


def threed_section(path: Path | None, scene: str, code: str) -> list[str]:
    """Markdown lines of ``scene``'s section from ``path`` (None: not given; no lines when the
    file does not hold the scene) for a report by code version ``code``."""
    head = [
        "### 2D idealisation against 3D",
        "",
        "Every reduced model uses E·I (a narrow beam: plane stress); a flexure several "
        "thicknesses wide is stiffer, up to the plate's E·I/(1 − ν²) (plane strain), by "
        "how much its anticlastic curvature is suppressed. The 3D solid reference "
        "`continuum:L[3d]` settles where this mechanism lies.",
        "",
    ]
    if path is None:
        return head + [f"Not included (no `--threed` file). Produce it with {PRODUCE}.", ""]
    doc, why = read_threed(path)
    if doc is None:
        return head + [f"Not available: {why}. Produce it with {PRODUCE}.", ""]
    data = doc["scenes"].get(scene)
    if data is None:
        return []
    lines = head + stale_lines(doc, code, REFRESH)
    searle = ", ".join(f"{k} {float(v):.2g}" for k, v in data.get("searle", {}).items())
    planes = doc["planes"]
    lines += [
        f"Depth b = {float(data['depth']):g} mm, thickness h = {float(data['thickness']):g} mm; "
        f"Searle's parameter b²/(R h) by flexure: {searle or '–'}. "
        f"Target |d| at full load (mm): the finest 3D level run, its change from the level "
        f"below where both ran (percent), `{planes['stress']}` and `{planes['strain']}`; the "
        "3D answer's "
        "position between them (0: plane stress, 1: plane strain) for |d| and the rotation.",
        "",
        "| case | 3D level | 3D disp. (mm) | change from level below (%) | plane stress | "
        "plane strain | position disp. | position rot. | closer |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    rows, closer = _bracket_rows(data["cases"])
    lines += rows
    cases = {k: v for k, v in data["cases"].items() if k in closer}
    if not cases:
        return lines + ["", "No 3D run reached full load.", ""]
    lines += ["", _verdict(cases, closer) + _reference_note(cases, doc["planes"]["stress"])]
    model_rows, best = _model_rows(cases, set(planes.values()))
    lines += [
        "",
        "End errors against the finest 3D level (displacement vector / rotation, percent):",
        "",
        "| model | " + " | ".join(cases) + " |",
        "|---|" + "---:|" * len(cases),
        *model_rows,
        "",
    ]
    if best:
        lines += ["Closest to 3D (the larger of the two errors) by case:", "", *best, ""]
    return lines
