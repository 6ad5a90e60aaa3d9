"""The 3D continuum (``continuum:LEVEL[3d]``) against the 2D plane-stress and plane-strain ones.

``table``: the open chain's load cases at the given mesh levels, each model
in its own process (``flexval``'s own runner): target displacement (dx, dy,
magnitude, mm) and rotation (deg) at full load, Newton iterations, wall time
of the path (s), unknowns and the process's peak resident memory (VmHWM),
with the load average of the machine.

``convergence``: the linear end compliance of one of the open chain's strips
(an arc of radius 3 mm, h = 0.1 mm, b = 1 mm, 30 degrees, clamped at its
start, rotation per end moment and deflection per end force) refined in all
three directions (mesh levels 0, 1, 2: in-plane elements and layers through
the depth halved together), in plane only (4 layers) and through the depth
only (level 1 in plane): observed order, Richardson extrapolation and GCI
(:func:`flexval.validation.studies.convergence.richardson`).

Usage: ``python benchmarks/bench_continuum3d.py table [--levels 0 1] [--cases m+ m- f+ f-]
[--json out.json]`` or ``python benchmarks/bench_continuum3d.py convergence``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np

CHILD = """
import json, time
import flexval.validation
from flexval.geometry import load_scene
from flexval.reducedmodels import parse_model
from flexval.validation.continuum.cost import size, size_3d
scene = load_scene("open_chain")
spec = parse_model({model!r})
case = next(c for c in scene.load_cases if c.name == {case!r})
lp = spec.model_family.run(scene.mechanism, spec, case, scene="open_chain")
level = spec.resolution
n = (size_3d if spec.kwargs.get("three_d") else size)(scene.mechanism, level)[0]
peak = int(next(l.split()[1] for l in open("/proc/self/status") if l.startswith("VmHWM:")))
print("RESULT", json.dumps(dict(dx=lp.dx[-1], dy=lp.dy[-1], rot=lp.rotation[-1],
      seconds=lp.seconds, iterations=lp.stats["newton_iterations"], unknowns=n, peak_kb=peak)))
"""


def run_one(model: str, case: str) -> dict:
    """One load path in a fresh process (its own peak memory)."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    out = subprocess.run(
        [sys.executable, "-c", CHILD.format(model=model, case=case)],
        capture_output=True,
        text=True,
        env=env,
    )
    line = next((x for x in out.stdout.splitlines() if x.startswith("RESULT")), None)
    if line is None:
        return {"error": out.stderr.strip().splitlines()[-1] if out.stderr else "no result"}
    return json.loads(line[7:])


def table(levels: list[int], cases: list[str], json_path: str | None) -> None:
    rows = []
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    header = (
        f"{'model':28s} {'case':4s} {'dx mm':>9s} {'dy mm':>9s} {'|d| mm':>9s} "
        f"{'rot deg':>9s} {'iters':>5s} {'path s':>7s} {'unknowns':>9s} {'peak MB':>8s}"
    )
    print(header)
    for level in levels:
        for case in cases:
            for model in (
                f"continuum:{level}",
                f"continuum:{level}[plane=strain]",
                f"continuum:{level}[3d]",
            ):
                r = run_one(model, case)
                r.update(model=model, case=case, load_average=os.getloadavg()[0])
                rows.append(r)
                if "error" in r:
                    print(f"{model:28s} {case:4s} failed: {r['error']}")
                    continue
                print(
                    f"{model:28s} {case:4s} {r['dx']:9.4f} {r['dy']:9.4f} "
                    f"{math.hypot(r['dx'], r['dy']):9.4f} {math.degrees(r['rot']):9.3f} "
                    f"{r['iterations']:5d} {r['seconds']:7.1f} {r['unknowns']:9,d} "
                    f"{r['peak_kb'] / 1024:8.0f}",
                    flush=True,
                )
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    if json_path:
        with open(json_path, "w") as fh:
            json.dump(rows, fh, indent=1)


def convergence() -> None:
    import scipy.sparse.linalg as spla

    from flexval.geometry import Arc, Material, Section
    from flexval.geometry.extrude import boundary_layer, extrude, layer_bounds, layers
    from flexval.geometry.mechanism import FlexureSpec, assemble
    from flexval.geometry.outline import flexure_mesh
    from flexval.reducedmodels.core.system import local_hessian
    from flexval.validation.continuum.connector3d import Continuum3DConnector
    from flexval.validation.studies.convergence import richardson

    arc = Arc((0.0, 0.0), 3.0, math.radians(90.0), math.radians(30.0))
    h, b = 0.1, 1.0
    section = Section(b, h)
    mech = assemble(
        [FlexureSpec("e", arc, ("1", "2"), section)],
        "1",
        arc.end_points[0:1],
        Material(2100.0, 0.35),
        "2",
        arc.end_points[1],
    )
    flexure = mech.flexures[0]
    delta = boundary_layer(arc.radius, h, b)
    rest = (
        np.array([*mech.bodies["1"].reference, 0.0]),
        np.array([*mech.bodies["2"].reference, 0.0]),
    )

    def compliance(level: int, count: int) -> tuple[float, float, int]:
        mesh = extrude(flexure_mesh(arc, section, level), layer_bounds(b / 2, delta, count))
        c = Continuum3DConnector(flexure, mech, level, mesh=mesh)
        _, _, hess = c.evaluate(*rest, c.initial_internal())
        K = local_hessian(c, hess)[3:, 3:].tocsc()
        rhs = np.zeros((K.shape[0], 2))
        rhs[1, 0] = rhs[2, 1] = 1.0
        u = spla.spsolve(K, rhs)
        return u[1, 0], u[2, 1], K.shape[0]

    studies = {
        "all three directions (level 0, 1, 2)": [(lv, layers(lv)) for lv in (0, 1, 2)],
        "in plane (level 0, 1, 2; 4 layers)": [(lv, 4) for lv in (0, 1, 2)],
        "through the depth (level 1; 2, 4, 8 layers)": [(1, n) for n in (2, 4, 8)],
    }
    print(f"load average: {os.getloadavg()[0]:.2f}")
    for name, grid in studies.items():
        values = [compliance(*g) for g in grid]
        print(name)
        for (level, count), (dy, rot, n) in zip(grid, values):
            print(
                f"  level {level} layers {count:2d}: {n:7d} unknowns  dy/Fy {dy:.8e} mm/N  "
                f"rot/M {rot:.8e} 1/(N mm)"
            )
        for k, what in ((0, "dy/Fy"), (1, "rot/M")):
            s = richardson(*(v[k] for v in values), 2.0)
            order = "n/a" if s["order"] is None else f"{s['order']:.2f}"
            gci = "n/a" if s["gci_percent"] is None else f"{s['gci_percent']:.3g} %"
            print(
                f"  {what}: observed order {order}, extrapolated {s['extrapolated']:.8e}, "
                f"GCI {gci}" + (f" ({s['note']})" if s["note"] else "")
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="what", required=True)
    t = sub.add_parser("table")
    t.add_argument("--levels", type=int, nargs="+", default=[0])
    t.add_argument("--cases", nargs="+", default=["m+", "m-", "f+", "f-"])
    t.add_argument("--json")
    sub.add_parser("convergence")
    args = parser.parse_args()
    if args.what == "table":
        table(args.levels, args.cases, args.json)
    else:
        convergence()


if __name__ == "__main__":
    main()
