"""Speed of the dynamic runs: wall time per simulated second, and what it buys.

Run: ``python benchmarks/bench_dynamics.py [--repeats 3] [--models ...]
[--scenes ...] [--cases ...]`` (``--models continuum:0`` for the continuum). Both built-in
scenes with PLA flexures (density 1.24e-9 t/mm^3) and massless links, so
the bodies carry the flexures' end pieces; each load case ramped by the
paper's Eq. 15 over 40 periods of the first natural mode and held for 10
more, damping ratio 1 at the two lowest modes (the paper's "damping that
minimises dynamic effects"), rho_inf = 0.9. Prints per model the first
natural frequency (Hz), the simulated seconds, the median wall seconds per
simulated second, accepted and rejected steps, Newton iterations and the
end rotation next to the static one (their relative difference: the lag
left by the ramp).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import flexval.validation  # noqa: F401  (registers the continuum family: --models continuum:0)
from flexval.geometry import MassData, load_scene
from flexval.geometry.inertia import PLA_DENSITY
from flexval.geometry.timelaw import TimeLaw
from flexval.reducedmodels.analyses.dynamics import DynamicSettings, Rayleigh, solve_dynamic
from flexval.reducedmodels.analyses.modes import natural_modes
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.recorder import solve_path
from flexval.reducedmodels.models import build_system

MODELS = ("dcmm:1", "dcmm:2", "prbm", "beam:20", "beam:100")
RAMP_PERIODS, HOLD_PERIODS = 40.0, 10.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    ap.add_argument("--scenes", nargs="*", default=["open_chain", "closed_chain"])
    ap.add_argument("--cases", nargs="*", help="load cases (default: every case of a scene)")
    args = ap.parse_args()
    print(
        f"{'scene':<13} {'case':<5} {'model':<9} {'f1 Hz':>8} {'sim s':>8} {'wall/sim':>9} "
        f"{'steps':>6} {'rejected':>8} {'newton':>7} {'rot end':>10} {'vs static':>10}"
    )
    for name in args.scenes:
        scene = load_scene(name)
        mech = dataclasses.replace(scene.mechanism, inertia=MassData(density=PLA_DENSITY))
        for case in scene.load_cases:
            if args.cases and case.name not in args.cases:
                continue
            for m in args.models:
                system = build_system(mech, parse_model(m))
                f = natural_modes(system, count=2).frequencies_hz
                ramp = RAMP_PERIODS / f[0]
                end = ramp + HOLD_PERIODS / f[0]
                static = solve_path(system, case)
                walls = []
                for _ in range(args.repeats):
                    t0 = time.perf_counter()
                    lp = solve_dynamic(
                        system,
                        case,
                        TimeLaw("eq15", 0.0, ramp),
                        end,
                        Rayleigh.from_ratio(1.0, f[0], f[1]),
                        DynamicSettings(rho_inf=0.9),
                    )
                    walls.append(time.perf_counter() - t0)
                lag = lp.rotation[-1] / static.rotation[-1] - 1.0
                print(
                    f"{name:<13} {case.name:<5} {m:<9} {f[0]:>8.2f} {end:>8.4f} "
                    f"{statistics.median(walls) / end:>9.2f} {lp.stats['steps']:>6} "
                    f"{lp.stats['rejected_steps']:>8} {lp.stats['newton_iterations']:>7} "
                    f"{lp.rotation[-1]:>10.5f} {lag:>10.2e}"
                )


if __name__ == "__main__":
    main()
