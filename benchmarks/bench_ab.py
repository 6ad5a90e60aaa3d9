"""A/B speed of two versions of flexval: the same load paths in alternating processes.

A benchmark run now against one an hour ago mostly measures the machine: on
this project's 2-core VM the speed of the same code drifts by up to 2x over
minutes (two ``bench_reduced`` runs ten minutes apart read ``dcmm:1`` f+ at
1.18 and 2.38 ms). So this compares two versions of the code the only way
that survives the drift: it runs them in alternating processes (A B B A A B
...), each process timing every path ``--repeats`` times after one untimed
warm-up run (imports and compiled kernels are per-process costs), and takes
per path and version the fastest time over all its processes. A slowdown
lasting longer than a process touches both versions alike; one shorter than
the ``repeats`` runs of a path is what the minimum removes.

Each path is one ``reducedmodels.run_reduced`` (or, for the continuum,
``flexval.validation.run.run_model``) of a built-in scene's load case, timed as the
model times itself (``LoadPath.seconds``: model build included). Next to the
times it prints whether the two versions agree (Newton iterations and end
values), so a speed-up is always read next to what it changed.

Usage::

    python benchmarks/bench_ab.py BASE [NEW] [--models ee dcmm:1 ...]
        [--scenes open_chain closed_chain] [--cases f+ f-]
        [--rounds 3] [--repeats 8] [--json out.json]

``BASE`` and ``NEW`` are git revisions of this repository (exported with
``git archive`` into a temporary directory, removed at the end) or
directories holding a flexval checkout (e.g. another git worktree). ``NEW``
defaults to this checkout's files as they are. Both versions run with the
same Python and installed packages: each process imports the project from its
version's directory (``PYTHONPATH``), and says which one it imported.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODELS = ("ee", "dcmm:1", "dcmm:2", "prbm", "beam:20", "beam:100")
PACKAGES = ("__init__.py", "geometry", "reducedmodels", "validation")
"""What a checkout holds of the ``flexval`` package (its root is the package)."""
AGREEMENT = 1e-9
"""Relative difference of end values (mm, rad) below which two versions agree."""

WORKER = r"""
import json, sys
import flexval.reducedmodels, flexval.geometry
from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.run import run_model

scenes, cases, models, repeats = json.loads(sys.argv[1])
rows = []
for name in scenes:
    scene = load_scene(name)
    for case in scene.load_cases:
        if cases and case.name not in cases:
            continue
        for model in models:
            spec = parse_model(model)
            run_model(scene, spec, case)                    # warm-up: imports, kernels
            seconds = []
            for _ in range(repeats):
                lp = run_model(scene, spec, case)
                seconds.append(lp.seconds)
            rows.append({"path": f"{name} {case.name} {model}", "seconds": min(seconds),
                         "newton": lp.stats.get("newton_iterations"),
                         "end": [lp.displacement[-1], lp.rotation[-1]]})
print(json.dumps({"imported": [flexval.reducedmodels.__file__, flexval.geometry.__file__],
                  "rows": rows}))
"""


def version_directory(version: str, scratch: Path) -> Path:
    """The directory a version's processes put on ``PYTHONPATH``.

    It holds one entry, ``flexval``: a link to a checkout given as a
    directory (this checkout for ``""``), or a git revision of this
    repository exported there.
    """
    target = scratch / (version.replace("/", "_") or "this-checkout")
    target.mkdir()
    if version == "" or Path(version).is_dir():
        path = ROOT if version == "" else Path(version).resolve()
        missing = [p for p in PACKAGES if not (path / p).exists()]
        if missing:
            sys.exit(
                f"bench_ab: directory {version!r} is not a flexval checkout "
                f"(no {', '.join(missing)})"
            )
        (target / "flexval").symlink_to(path, target_is_directory=True)
        return target
    (target / "flexval").mkdir()
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", "--format=tar", version, *PACKAGES], capture_output=True
    )
    if archive.returncode != 0:
        sys.exit(
            f"bench_ab: {version!r} is neither a directory nor a git revision of a "
            f"flexval with the flexval namespace ({archive.stderr.decode().strip()})"
        )
    subprocess.run(["tar", "-x", "-C", str(target / "flexval")], input=archive.stdout, check=True)
    return target


def run_version(directory: Path, work: list) -> dict:
    """One process of a version: its rows, checked to come from ``directory``."""
    env = {**os.environ, "PYTHONPATH": str(directory), "OPENBLAS_NUM_THREADS": "1"}
    done = subprocess.run(
        [sys.executable, "-c", WORKER, json.dumps(work)],
        env=env,
        capture_output=True,
        text=True,
        cwd=directory,
    )
    if done.returncode != 0:
        sys.exit(f"bench_ab: the process of {directory} failed:\n{done.stderr.strip()}")
    out = json.loads(done.stdout.strip().splitlines()[-1])
    code = (directory / "flexval").resolve()
    for module in out["imported"]:
        if not Path(module).resolve().is_relative_to(code):
            sys.exit(f"bench_ab: a process meant for {directory} imported {module}")
    return out


def fastest(runs: list[dict]) -> dict[str, dict]:
    """Per path, the row of the run with the smallest time."""
    best: dict[str, dict] = {}
    for run in runs:
        for row in run["rows"]:
            if row["path"] not in best or row["seconds"] < best[row["path"]]["seconds"]:
                best[row["path"]] = row
    return best


def agreement(a: dict, b: dict) -> str:
    """'same', or what differs between two versions' rows of one path."""
    notes = []
    if a["newton"] != b["newton"]:
        notes.append(f"newton {a['newton']} -> {b['newton']}")
    scale = max(1.0, *map(abs, a["end"]))
    change = max(abs(x - y) for x, y in zip(a["end"], b["end"]))
    if change > AGREEMENT * scale:
        notes.append(f"end values differ by {change:.2g}")
    return "; ".join(notes) or "same"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base", help="git revision or flexval directory (version A)")
    ap.add_argument(
        "new",
        nargs="?",
        default="",
        help="git revision or flexval directory (version B; default: this checkout)",
    )
    ap.add_argument("--models", nargs="+", default=list(MODELS))
    ap.add_argument("--scenes", nargs="+", default=["open_chain", "closed_chain"])
    ap.add_argument("--cases", nargs="*", default=[], help="load case names (default: all)")
    ap.add_argument("--rounds", type=int, default=3, help="processes per version")
    ap.add_argument("--repeats", type=int, default=8, help="timed runs per path and process")
    ap.add_argument("--json", help="also write the per-path rows to this file")
    args = ap.parse_args()
    for name in ("rounds", "repeats"):
        if getattr(args, name) < 1:
            sys.exit(f"bench_ab: --{name} must be >= 1, got {getattr(args, name)}")
    work = [args.scenes, args.cases, args.models, args.repeats]
    with tempfile.TemporaryDirectory(prefix="flexval-ab-") as scratch:
        dirs = [version_directory(v, Path(scratch)) for v in (args.base, args.new)]
        runs: list[list[dict]] = [[], []]
        for r in range(args.rounds):
            for side in (0, 1) if r % 2 == 0 else (1, 0):
                runs[side].append(run_version(dirs[side], work))
                print(f"round {r + 1}/{args.rounds}: {'AB'[side]} done", file=sys.stderr)
    a, b = fastest(runs[0]), fastest(runs[1])
    print(
        f"A = {args.base}, B = {args.new or 'this checkout'}; fastest of {args.rounds} "
        f"processes x {args.repeats} runs per path, ms"
    )
    print(f"{'path':<32} {'A ms':>8} {'B ms':>8} {'A/B':>6}  results")
    ratios: dict[str, list[float]] = {}
    rows = []
    for path in a:
        ratio = a[path]["seconds"] / b[path]["seconds"]
        ratios.setdefault(path.split()[-1], []).append(ratio)
        same = agreement(a[path], b[path])
        rows.append(
            {
                "path": path,
                "a_ms": 1e3 * a[path]["seconds"],
                "b_ms": 1e3 * b[path]["seconds"],
                "speedup": ratio,
                "results": same,
            }
        )
        print(
            f"{path:<32} {1e3 * a[path]['seconds']:>8.3f} {1e3 * b[path]['seconds']:>8.3f} "
            f"{ratio:>6.2f}  {same}"
        )
    print(
        "geometric mean speed-up A/B per model: "
        + ", ".join(
            f"{m} {math.exp(sum(map(math.log, r)) / len(r)):.2f}x" for m, r in ratios.items()
        )
    )
    if args.json:
        Path(args.json).write_text(
            json.dumps({"a": args.base, "b": args.new or "checkout", "rows": rows}, indent=1) + "\n"
        )


if __name__ == "__main__":
    main()
