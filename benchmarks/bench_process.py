"""What a whole ``flexval`` process costs, start-up included, and where its imports go.

Each command runs ``--repeats`` times in a fresh interpreter after one
warm-up run (which fills a private mesh cache, numba's on-disk cache and the
bytecode cache, as any second call on a user's machine finds them). Per
command: the minimum and the median of the wall time and of the user CPU
time, and the minimum system CPU time (children's ``getrusage``). On a shared
machine the minimum and the CPU times are the figures to compare: the median
wall time includes waiting for the cores.

Two reference rows give the floor no flexval change can lower: the
interpreter alone, and importing numpy and the scipy parts every model uses.
``--imports`` then breaks one command's import time down by package
(``python -X importtime``, each module's self time, minimum over the
repeats), and names the numpy sub-packages that scipy's vendored
array-api-compat imports (it lists ``dir(numpy)``, which loads numpy's lazy
sub-packages: f2py, testing, ma, random, ...).

Bytecode: by default the processes cache compiled bytecode in a private
folder, as an installed flexval does. ``--no-bytecode`` sets
``PYTHONDONTWRITEBYTECODE=1`` with no cache: flexval's own sources are then
compiled at every start, as in an editable checkout run that way.

Usage::

    python benchmarks/bench_process.py [--repeats 7] [--command "run closed_chain ..."]...
                                       [--imports "run closed_chain ..."] [--no-bytecode]
"""

from __future__ import annotations

import argparse
import os
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

COMMANDS = (
    "--help",
    "info closed_chain",
    "run closed_chain --model dcmm:1 --load-case f+",
    "run closed_chain --model prbm --load-case f+",
    "run closed_chain --model beam:20 --load-case f+",
    "run closed_chain --model continuum:1 --load-case f+",
)
ENTRY = "import sys; from flexval.validation.cli import main; sys.exit(main())"
"""What the ``flexval`` console script runs."""
FLOOR = (
    ("interpreter alone", "pass"),
    ("numpy + scipy.linalg + scipy.sparse", "import numpy, scipy.linalg, scipy.sparse"),
)
SCIPY_COMPAT = "scipy._lib.array_api_compat.numpy"


def _environment(cache: Path, pycache: Path | None) -> dict[str, str]:
    env = {
        **os.environ,
        "FLEXVAL_CACHE": str(cache),
        "PYTHONPATH": os.pathsep.join(filter(None, (str(ROOT), os.environ.get("PYTHONPATH")))),
    }
    env.pop("PYTHONPYCACHEPREFIX", None)
    if pycache is None:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    else:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(pycache)
    return env


def _run(argv: list[str], env: dict[str, str]) -> tuple[float, float, float]:
    """Wall, user CPU and system CPU seconds of one process (it must exit with 0)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(
        argv, env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(
            f"bench_process: {shlex.join(argv)} exited with {proc.returncode}:\n{proc.stderr}"
        )
    return wall, after.ru_utime - before.ru_utime, after.ru_stime - before.ru_stime


def time_process(argv: list[str], env: dict[str, str], repeats: int) -> dict[str, float]:
    """One warm-up run, then ``repeats`` timed runs of ``argv``."""
    _run(argv, env)
    walls, users, systems = zip(*(_run(argv, env) for _ in range(repeats)))
    return {
        "wall_min": min(walls),
        "wall_median": statistics.median(walls),
        "user_min": min(users),
        "user_median": statistics.median(users),
        "sys_min": min(systems),
    }


def import_times(
    argv: list[str], env: dict[str, str], repeats: int
) -> tuple[dict[str, int], dict[str, str]]:
    """Each module's smallest self time (us) over ``repeats`` runs, and its importer."""
    best: dict[str, int] = {}
    parent: dict[str, str] = {}
    for _ in range(repeats):
        proc = subprocess.run(
            [sys.executable, "-X", "importtime", *argv[1:]],
            env=env,
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        rows = []
        for line in proc.stderr.splitlines():
            if not line.startswith("import time:") or "self [us]" in line:
                continue
            self_us, _, name = line[len("import time:") :].split("|")
            rows.append(((len(name) - len(name.lstrip())) // 2, name.strip(), int(self_us)))
            best[rows[-1][1]] = min(best.get(rows[-1][1], rows[-1][2]), rows[-1][2])
        # -X importtime prints a module after everything it imported, one level deeper
        for k, (depth, name, _) in enumerate(rows):
            owner = next((r[1] for r in rows[k + 1 :] if r[0] == depth - 1), "")
            parent.setdefault(name, owner)
    return best, parent


def _group(name: str, parent: dict[str, str]) -> str:
    """Which part of the start-up a module belongs to."""
    chain, seen = name, set()
    while chain and chain not in seen:
        if chain == SCIPY_COMPAT:
            return (
                "numpy sub-packages loaded by scipy's array-api-compat"
                if name.split(".")[0] == "numpy"
                else "stdlib/other loaded by those"
            )
        seen.add(chain)
        chain = parent.get(chain, "")
    top = name.split(".")[0]
    if top == "flexval":
        return "flexval (geometry, reducedmodels, validation)"
    if top in ("numpy", "scipy", "skfem", "numba", "llvmlite", "threadpoolctl"):
        return top
    return "stdlib/other"


def print_imports(command: str, env: dict[str, str], repeats: int) -> None:
    argv = [sys.executable, "-c", ENTRY, *shlex.split(command)]
    _run(argv, env)
    best, parent = import_times(argv, env, repeats)
    groups: Counter[str] = Counter()
    for name, us in best.items():
        groups[_group(name, parent)] += us
    total = sum(groups.values())
    print(
        f"\n## imports of `flexval {command}`: {len(best)} modules, {total / 1000:.0f} ms "
        f"self time (python -X importtime, each module's minimum over {repeats} runs)"
    )
    for group, us in groups.most_common():
        print(f"{us / 1000:8.1f} ms  {100 * us / total:5.1f} %  {group}")


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=7, help="timed runs per command (default 7)")
    p.add_argument(
        "--command",
        action="append",
        metavar="ARGS",
        help="flexval arguments to time (repeatable; default: a set of common calls)",
    )
    p.add_argument(
        "--imports",
        metavar="ARGS",
        default=COMMANDS[-1],
        help=f"command whose imports are broken down (default: {COMMANDS[-1]!r}; '' for none)",
    )
    p.add_argument(
        "--no-bytecode",
        action="store_true",
        help="PYTHONDONTWRITEBYTECODE=1: compile flexval's sources at every start",
    )
    args = p.parse_args(argv)
    if args.repeats < 1:
        p.error("--repeats must be at least 1")
    with tempfile.TemporaryDirectory(prefix="flexval-bench-process-") as tmp:
        pycache = None if args.no_bytecode else Path(tmp) / "pycache"
        env = _environment(Path(tmp) / "cache", pycache)
        print(
            f"# whole processes: one warm-up run, then {args.repeats} runs each; seconds; "
            f"bytecode {'not cached' if pycache is None else 'cached'}; load average before: "
            f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs"
        )
        print(
            f"{'command':<58} {'wall min':>8} {'median':>8} {'user min':>8} {'median':>8} "
            f"{'sys min':>8}"
        )
        rows = [(label, [sys.executable, "-c", code]) for label, code in FLOOR]
        rows += [
            (f"flexval {c}", [sys.executable, "-c", ENTRY, *shlex.split(c)])
            for c in (args.command or COMMANDS)
        ]
        for label, cmd in rows:
            t = time_process(cmd, env, args.repeats)
            print(
                f"{label:<58} {t['wall_min']:>8.3f} {t['wall_median']:>8.3f} "
                f"{t['user_min']:>8.3f} {t['user_median']:>8.3f} {t['sys_min']:>8.3f}",
                flush=True,
            )
        if args.imports:
            print_imports(args.imports, env, args.repeats)


if __name__ == "__main__":
    main()
