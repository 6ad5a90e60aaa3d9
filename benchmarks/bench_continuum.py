"""Benchmark of the continuum reference on the built-in scenes.

For one load case of each scene (11 load levels, default mesh level) it
reports the unknowns, Newton iterations, wall seconds, seconds per Newton
iteration and where the time goes: set-up (Gmsh mesh or cache, scikit-fem
basis), element kernels and chain rule (ContinuumConnector.evaluate), the
core's global assembly (System.assemble minus the connectors) and the LU
factorisation and solve of the tangent (``reducedmodels.tangent``: banded
LAPACK for the default level, SuperLU for wide bands). The breakdown comes from
cProfile over the same run (its overhead is below 2 %: few, heavy calls).

Usage: ``python benchmarks/bench_continuum.py [--level N] [--json out.json]``
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from geometry import SceneError, load_scene
from validation.continuum import DEFAULT_LEVEL, run_continuum
from validation.outputs import check_file, write_json

CASES = {"open_chain": "f+", "closed_chain": "f+"}


def _cumulative(stats: pstats.Stats, file_part: str, function: str) -> float:
    """Cumulative seconds of the functions named ``function`` in files containing ``file_part``."""
    return sum(v[3] for (path, _, name), v in stats.stats.items()
               if name == function and file_part in path)


def bench(scene_name: str, case_name: str, level: int) -> dict:
    """Run one load case under cProfile; return its statistics."""
    scene = load_scene(scene_name)
    case = scene.load_case(case_name)
    prof = cProfile.Profile()
    t0 = time.perf_counter()
    prof.enable()
    lp = run_continuum(scene.mechanism, case, level=level, scene=scene_name)
    prof.disable()
    wall = time.perf_counter() - t0
    st = pstats.Stats(prof)
    connectors = _cumulative(st, "continuum/connector.py", "evaluate")
    assemble = _cumulative(st, "reducedmodels/core.py", "assemble")
    solve = _cumulative(st, "reducedmodels/tangent.py", "solve")
    setup = _cumulative(st, "continuum/run.py", "build_system")
    its = lp.stats["newton_iterations"]
    return {"scene": scene_name, "load_case": case_name, "model": lp.model,
            "unknowns": lp.stats["unknowns"], "newton_iterations": its,
            "substeps": lp.stats["substeps"], "step_cuts": lp.stats["step_cuts"],
            "seconds": wall, "seconds_per_iteration": (wall - setup) / max(its, 1),
            "setup_s": setup, "element_kernels_s": connectors,
            "global_assembly_s": assemble - connectors, "factorisation_s": solve,
            "other_s": wall - setup - assemble - solve}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--level", type=int, default=DEFAULT_LEVEL, help="mesh level")
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()
    try:
        if args.json:
            check_file(args.json, "--json")      # before the minutes of work, not after
    except SceneError as exc:
        parser.error(str(exc))
    rows = [bench(s, c, args.level) for s, c in CASES.items()]
    head = (f"{'scene':<13}{'case':<5}{'model':<13}{'unknowns':>9}{'iters':>6}{'s':>7}"
            f"{'s/iter':>8}{'setup':>7}{'kernel':>8}{'assem':>7}{'LU':>7}{'other':>7}")
    print(head)
    for r in rows:
        print(f"{r['scene']:<13}{r['load_case']:<5}{r['model']:<13}{r['unknowns']:>9}"
              f"{r['newton_iterations']:>6}{r['seconds']:>7.2f}{r['seconds_per_iteration']:>8.3f}"
              f"{r['setup_s']:>7.2f}{r['element_kernels_s']:>8.2f}{r['global_assembly_s']:>7.2f}"
              f"{r['factorisation_s']:>7.2f}{r['other_s']:>7.2f}")
    if args.json:
        write_json(args.json, rows)


if __name__ == "__main__":
    main()
