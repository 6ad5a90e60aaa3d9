"""Benchmark of the continuum reference on the built-in scenes.

For open chain f+ and f- and closed chain f+ (11 load levels, default mesh
level) it reports the unknowns, Newton iterations, wall seconds, seconds
per Newton iteration, the process's CPU seconds over the same run (the
figure to compare on a shared machine, where wall time mostly measures
the other processes) and where the time goes: set-up (Gmsh mesh or cache,
scikit-fem basis), the element kernels (``ElementKernel.evaluate``), the
rest of the assembly (the connector group's scatter into the band storage
and the core's), the banded factorisation and solves of the tangent
(``flexval.reducedmodels.core.tangent``), the section-wise predictor and Newton update
(``ContinuumGroup.predict_internal`` / ``update_internal``) and the rest.
The breakdown comes from cProfile over the same run (its overhead is a few
per cent: few, heavy calls).

Usage: ``python benchmarks/bench_continuum.py [--level N] [--json out.json]``
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from flexval.geometry import SceneError, load_scene
from flexval.reducedmodels import System
from flexval.reducedmodels.core.tangent import BandedTangent, SparseTangent
from flexval.validation.continuum import DEFAULT_LEVEL, run_continuum
from flexval.validation.continuum.group import ContinuumGroup
from flexval.validation.continuum.run import build_system
from flexval.validation.continuum.solid import ElementKernel
from flexval.validation.outputs import check_file, write_json

CASES = (("open_chain", "f+"), ("open_chain", "f-"), ("closed_chain", "f+"))


def _cumulative(stats: pstats.Stats, function) -> float:
    """Cumulative seconds of ``function`` (matched by its code's file and first line)."""
    code = function.__code__
    return sum(
        v[3]
        for (path, line, name), v in stats.stats.items()
        if path == code.co_filename and line == code.co_firstlineno
    )


def bench(scene_name: str, case_name: str, level: int) -> dict:
    """Run one load case under cProfile; return its statistics."""
    scene = load_scene(scene_name)
    case = scene.load_case(case_name)
    prof = cProfile.Profile()
    t0, cpu0 = time.perf_counter(), time.process_time()
    prof.enable()
    lp = run_continuum(scene.mechanism, case, level=level, scene=scene_name)
    prof.disable()
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    st = pstats.Stats(prof)
    kernels = _cumulative(st, ElementKernel.evaluate)
    assemble = _cumulative(st, System.assemble)
    solve = _cumulative(st, BandedTangent.solve) + _cumulative(st, SparseTangent.solve)
    update = _cumulative(st, ContinuumGroup.update_internal) + _cumulative(
        st, ContinuumGroup.predict_internal
    )
    setup = _cumulative(st, build_system)
    its = lp.stats["newton_iterations"]
    return {
        "scene": scene_name,
        "load_case": case_name,
        "model": lp.model,
        "unknowns": lp.stats["unknowns"],
        "newton_iterations": its,
        "substeps": lp.stats["substeps"],
        "step_cuts": lp.stats["step_cuts"],
        "seconds": wall,
        "cpu_seconds": cpu,
        "seconds_per_iteration": (wall - setup) / max(its, 1),
        "setup_s": setup,
        "element_kernels_s": kernels,
        "global_assembly_s": assemble - kernels,
        "factorisation_s": solve,
        "predictor_update_s": update,
        "other_s": wall - setup - assemble - solve - update,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--level", type=int, default=DEFAULT_LEVEL, help="mesh level")
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()
    try:
        if args.json:
            check_file(args.json, "--json")  # before the minutes of work, not after
    except SceneError as exc:
        parser.error(str(exc))
    rows = [bench(s, c, args.level) for s, c in CASES]
    head = (
        f"{'scene':<13}{'case':<5}{'model':<13}{'unknowns':>9}{'iters':>6}{'s':>7}"
        f"{'cpu s':>7}"
        f"{'s/iter':>8}{'setup':>7}{'kernel':>8}{'assem':>7}{'LU':>7}{'update':>8}"
        f"{'other':>7}"
    )
    print(head)
    for r in rows:
        print(
            f"{r['scene']:<13}{r['load_case']:<5}{r['model']:<13}{r['unknowns']:>9}"
            f"{r['newton_iterations']:>6}{r['seconds']:>7.2f}{r['cpu_seconds']:>7.2f}"
            f"{r['seconds_per_iteration']:>8.3f}"
            f"{r['setup_s']:>7.2f}{r['element_kernels_s']:>8.2f}{r['global_assembly_s']:>7.2f}"
            f"{r['factorisation_s']:>7.2f}{r['predictor_update_s']:>8.2f}{r['other_s']:>7.2f}"
        )
    if args.json:
        write_json(args.json, rows)


if __name__ == "__main__":
    main()
