"""The 3D solid reference on the paper scenes, against plane stress, plane strain and the
reduced models with and without their width options.

For every load case of each scene it traces ``continuum:L[3d]`` on the given mesh
levels (coarse to fine), the 2D continuum in plane stress and in plane strain,
and the reduced models, and measures each end-of-load error against the finest
3D level that reached full load (:func:`flexval.validation.studies.compare.errors`).
It writes, into ``--out`` (default ``reports/threed``):

- ``threed.json``: the results (format
  :data:`flexval.validation.report.threed.THREED_FORMAT`, no timings), read by
  ``flexval report --threed``;
- ``threed.md``: the full table (every level's end values and unknowns);
- ``timings.md``: the wall time of every run (s), apart so that a rerun
  changes only the timings where nothing else changed.

The 3D solves take minutes each; run it after a change to the models::

    python benchmarks/threed_study.py                       # both scenes, levels 0 1
    python benchmarks/threed_study.py --scenes open_chain --levels 0
    python benchmarks/threed_study.py --levels 0 1 --fine-cases open_chain:m+

A 3D level-1 path of the open chain takes 10-40 minutes and 6-8 GB on a 2-core
machine; level 0 takes 0.5-4 minutes and 0.8 GB.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from flexval.geometry import Scene, load_scene
from flexval.geometry.anticlastic import searle_parameters
from flexval.reducedmodels import LoadPath
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.settings import SolverError
from flexval.validation.cache import code_version
from flexval.validation.outputs import write_json, write_text
from flexval.validation.report.threed import THREED_FORMAT
from flexval.validation.run import run_model
from flexval.validation.studies.compare import errors

PLANES = {"stress": "continuum:1", "strain": "continuum:1[plane=strain]"}
"""The 2D idealisations: the report's default reference level in plane stress and strain."""
REDUCED = tuple(
    f"{base}{option}"
    for base in ("beam:100", "dcmm:3", "prbm", "ee")
    for option in ("", "[plate]", "[width]")
)
"""The reduced models compared with 3D: each paper model plain (E·I), with the plate's
constants and with the width option's effective modulus."""


def end_values(path: LoadPath) -> dict[str, float]:
    """Target displacement (mm) and rotation (rad) at full load."""
    return {"dx": float(path.dx[-1]), "dy": float(path.dy[-1]), "rot": float(path.rotation[-1])}


def trace(scene: Scene, model: str, case) -> tuple[LoadPath | None, str | None, float]:
    """The path of ``model`` on ``case``, or None and why it failed; and its wall time (s)."""
    start = time.perf_counter()
    try:
        path = run_model(scene, parse_model(model), case)
    except SolverError as exc:
        return None, str(exc), time.perf_counter() - start
    except MemoryError:
        return None, "out of memory", time.perf_counter() - start
    return path, None, time.perf_counter() - start


def study_case(scene: Scene, case, levels: list[int], reduced: list[str], seconds: dict) -> dict:
    """One load case: the 3D ``levels``, both planes and the reduced models' errors against the
    finest 3D level that reached full load."""
    threed, finest = [], None
    for level in levels:
        model = f"continuum:{level}[3d]"
        path, failure, wall = trace(scene, model, case)
        seconds[(scene.name, case.name, model)] = wall
        entry = {"model": model, "level": level, "failure": failure}
        if path is not None:
            entry |= end_values(path)
            entry["unknowns"] = int(path.stats.get("unknowns", 0)) or None
            finest = path
        threed.append(entry)
    planes, paths = {}, {}
    for key, model in PLANES.items():
        path, failure, wall = trace(scene, model, case)
        seconds[(scene.name, case.name, model)] = wall
        planes[key] = end_values(path) if path else {"failure": failure}
        paths[model] = path
    for model in reduced:
        path, failure, wall = trace(scene, model, case)
        seconds[(scene.name, case.name, model)] = wall
        paths[model] = path
    size = scene.mechanism.size()
    errs = {}
    if finest is not None:
        for model, path in paths.items():
            if path is not None and math.isclose(path.load[-1], finest.load[-1]):
                e = errors(path, finest, size)
                errs[model] = {"end_disp_vec": e["end_disp_vec"], "end_rot": e["end_rot"]}
    return {"threed": threed, "planes": planes, "errors": errs}


def levels_of(scene: str, case: str, levels: list[int], fine: list[str] | None) -> list[int]:
    """The 3D levels of one case: all of ``levels`` when ``fine`` is None or names the case
    (``CASE`` or ``SCENE:CASE``), else only the coarsest."""
    if fine is None or case in fine or f"{scene}:{case}" in fine:
        return levels
    return levels[:1]


def study(
    scenes: list[str],
    levels: list[int],
    reduced: list[str],
    cases: list[str] | None,
    fine: list[str] | None = None,
):
    """The document and the wall times of every run (keyed by scene, case, model)."""
    code = code_version()  # the code the results come from, not the code at the end
    seconds: dict = {}
    out = {}
    for name in scenes:
        scene = load_scene(name)
        mech = scene.mechanism
        chosen = [c for c in scene.load_cases if cases is None or c.name in cases]
        out[name] = {
            "depth": mech.flexures[0].section.depth,
            "thickness": mech.flexures[0].section.thickness,
            "searle": searle_parameters(mech),
            "cases": {
                c.name: study_case(
                    scene, c, levels_of(name, c.name, levels, fine), reduced, seconds
                )
                for c in chosen
            },
        }
        print(f"{name}: done", flush=True)
    doc = {"format": THREED_FORMAT, "code_version": code, "planes": PLANES, "scenes": out}
    return doc, seconds


def _value(entry: dict, key: str) -> str:
    return "–" if entry.get(key) is None else f"{entry[key]:.6g}"


def markdown(doc: dict) -> str:
    """The full table: every run's end values, the 3D levels' unknowns, the errors."""
    lines = ["# The 3D solid reference against the 2D idealisations", ""]
    for scene, data in doc["scenes"].items():
        lines += [f"## {scene}", "", "| case | model | unknowns | dx (mm) | dy (mm) | rot (rad) |"]
        lines += ["|---|---|---:|---:|---:|---:|"]
        for case, c in data["cases"].items():
            for r in c["threed"]:
                if r.get("failure"):
                    lines.append(f"| {case} | {r['model']} | | failed: {r['failure']} | | |")
                else:
                    lines.append(
                        f"| {case} | {r['model']} | {r.get('unknowns') or '–'} | "
                        f"{_value(r, 'dx')} | {_value(r, 'dy')} | {_value(r, 'rot')} |"
                    )
            for key, model in doc["planes"].items():
                p = c["planes"][key]
                lines.append(
                    f"| {case} | {model} | | {_value(p, 'dx')} | {_value(p, 'dy')} | "
                    f"{_value(p, 'rot')} |"
                )
        lines += ["", "End errors against the finest 3D level (percent):", ""]
        lines += ["| case | model | disp. vector | rotation |", "|---|---|---:|---:|"]
        for case, c in data["cases"].items():
            for model, e in c["errors"].items():
                lines.append(f"| {case} | {model} | {e['end_disp_vec']:.3f} | {e['end_rot']:.3f} |")
        lines.append("")
    return "\n".join(lines) + "\n"


def timings(seconds: dict) -> str:
    lines = ["# Wall times of the 3D study (s)", "", "| scene | case | model | s |"]
    lines += ["|---|---|---|---:|"]
    lines += [f"| {s} | {c} | {m} | {t:.2f} |" for (s, c, m), t in seconds.items()]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=["open_chain", "closed_chain"])
    ap.add_argument("--levels", nargs="+", type=int, default=[0, 1])
    ap.add_argument("--cases", nargs="+", default=None, help="default: every load case")
    ap.add_argument(
        "--fine-cases",
        nargs="+",
        default=None,
        help="cases (CASE or SCENE:CASE) that run every level; the others run only the "
        "coarsest (default: every case runs every level)",
    )
    ap.add_argument("--models", nargs="+", default=list(REDUCED))
    ap.add_argument("--out", type=Path, default=Path("reports/threed"))
    args = ap.parse_args()
    for m in args.models:
        parse_model(m)  # a bad id fails before any work
    doc, seconds = study(args.scenes, sorted(args.levels), args.models, args.cases, args.fine_cases)
    args.out.mkdir(parents=True, exist_ok=True)
    write_json(args.out / "threed.json", doc)
    write_text(args.out / "threed.md", markdown(doc))
    write_text(args.out / "timings.md", timings(seconds))
    print((args.out / "threed.md").read_text())


if __name__ == "__main__":
    main()
