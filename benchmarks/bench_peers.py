"""flexval ``beam:N`` side by side with OpenSeesPy's corotational beams, in one process.

Both solve the same mechanism with N two-node corotational Euler-Bernoulli
elements per flexure, nodes on the centre line at arc lengths k L / N, along
the same load levels; the table gives both median wall times (model build
included), their ratio and how far apart the end values are.

The OpenSees model: ``elasticBeamColumn`` elements with a ``Corotational``
transformation for the flexures (A = b h, Iz = b h^3 / 12, E of the scene);
every rigid body is a hub node (its reference point) joined to its other
points (flexure ends, pins, the target and load points) by corotational beams
``RIGID_FACTOR`` times stiffer than the flexures -- OpenSees' ``rigidLink``
is linearised and wrong at large rotation. Pins are ``equalDOF`` on the two
translations. The ground's hub is fixed. Loads are dead (``Plain`` pattern,
``Linear`` series) on the hub (moments) or the load point's node (forces).
Newton with ``BandGeneral`` storage under an RCM numbering, convergence on
the displacement increment (``TOLERANCE`` mm or rad). Load control takes,
per load level, the fewest equal sub-steps (searched before timing) with
which the whole path converges.

Two orders are timed (see :func:`time_both`): interleaved (flexval, OpenSees,
flexval, ... : every run starts with caches the other code just filled) and
back to back ("b2b" columns: all flexval runs, then all OpenSees runs, as in a
sweep of one model). On this VM flexval's few-millisecond paths take about
1.5x longer interleaved (session 6: 7-8 ms against 4-6 ms), OpenSees' longer
ones hardly change; the interleaved ratio is the conservative one.

The "CPU ratio" column is the ratio of the fastest interleaved CPU times (this process's,
``time.process_time``) of the repeats: on a shared machine the wall times
also count the time the process waited for a core, the CPU times do not.

Agreement: |Delta d| / |d| of the target's end displacement vector and
|Delta theta| / |theta| of the target body's end rotation, the larger one, in
per cent (the bar: 0.01 %).

OpenSeesPy is an optional extra: ``pip install -e ".[peers]"`` (on Debian
it needs the system's ``libblas3`` and ``liblapack3``).

Usage: ``python benchmarks/bench_peers.py [SCENE ...] [--n 100] [--repeats 5]``
(default: both built-in scenes, all their load cases).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import numpy as np

from geometry import Force, LoadCase, Mechanism, Moment, load_scene
from reducedmodels import run_reduced
from reducedmodels.catalogue import parse_model

RIGID_FACTOR = 1e8      # spokes' EA, EI over the flexures': the end values move 1e-4 % from
                        # 1e8 to 1e10 (0.01 % from 1e6 to 1e8); 1e10 breaks the 1e-10 test
TOLERANCE = 1e-10       # OpenSees NormDispIncr bound, mm and rad
MAX_ITERATIONS = 50     # Newton iterations per OpenSees sub-step before it counts as failed
SUBSTEP_CHOICES = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32)


def opensees():
    """The ``openseespy.opensees`` module, or exit with how to install it."""
    try:
        import openseespy.opensees as ops
    except (ImportError, RuntimeError) as exc:
        sys.exit(f"OpenSeesPy is missing or does not load ({exc}).\n"
                 "Install the optional extra: pip install -e \".[peers]\" "
                 "(on Debian also: apt-get install libblas3 liblapack3).")
    ops.logFile("/dev/null", "-noEcho")     # its warnings on the sub-step search's failed tries
    return ops


class OpenSeesModel:
    """The mechanism as an OpenSees model; remembers the target's node and body hub."""

    def __init__(self, ops, mechanism: Mechanism, case: LoadCase, n: int):
        self.ops, self._next = ops, 0
        ops.wipe()
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.geomTransf("Corotational", 1)
        self._nodes: dict[str, list[tuple[np.ndarray, int]]] = {}
        self.hubs = {name: self._body_node(name, body.reference)
                     for name, body in mechanism.bodies.items()}
        ops.fix(self.hubs[mechanism.ground], 1, 1, 1)
        material = mechanism.material
        for flexure in mechanism.flexures:
            section = flexure.section
            shape = flexure.shape
            points = shape.point(np.linspace(0.0, shape.length, n + 1))
            chain = ([self._body_node(flexure.start_body, points[0])]
                     + [self._new_node(p) for p in points[1:-1]]
                     + [self._body_node(flexure.end_body, points[-1])])
            for i, j in zip(chain[:-1], chain[1:]):
                self._element(i, j, section.area, material.youngs_modulus, section.inertia)
        for pin in mechanism.pins:
            a, b = (self._body_node(body, pin.point) for body in pin.bodies)
            ops.equalDOF(a, b, 1, 2)
        self.target = self._body_node(mechanism.target_body, mechanism.target_point)
        self.target_hub = self.hubs[mechanism.target_body]
        # spokes: every body point to its hub, as stiff as the stiffest flexure times RIGID_FACTOR
        area = max(f.section.area for f in mechanism.flexures) * RIGID_FACTOR
        inertia = max(f.section.inertia for f in mechanism.flexures) * RIGID_FACTOR
        loads = [(self._body_node(c.body, c.point), *c.vector, 0.0) if isinstance(c, Force)
                 else (self.hubs[c.body], 0.0, 0.0, c.value) for c in case.components
                 if isinstance(c, (Force, Moment))]
        for name, nodes in self._nodes.items():
            for _, tag in nodes:
                if tag != self.hubs[name]:
                    self._element(self.hubs[name], tag, area, material.youngs_modulus, inertia)
        ops.timeSeries("Linear", 1)
        ops.pattern("Plain", 1, 1)
        for tag, fx, fy, m in loads:
            ops.load(tag, fx, fy, m)
        ops.system("BandGeneral")
        ops.numberer("RCM")
        ops.constraints("Transformation" if mechanism.pins else "Plain")
        ops.test("NormDispIncr", TOLERANCE, MAX_ITERATIONS)
        ops.algorithm("Newton")

    def _new_node(self, point: np.ndarray) -> int:
        self._next += 1
        self.ops.node(self._next, float(point[0]), float(point[1]))
        return self._next

    def _body_node(self, body: str, point: np.ndarray) -> int:
        """The node of ``body`` at ``point`` (made on first use; the first one is the hub)."""
        nodes = self._nodes.setdefault(body, [])
        for p, tag in nodes:
            if np.allclose(p, point, rtol=0.0, atol=1e-9):
                return tag
        nodes.append((np.asarray(point, float), self._new_node(point)))
        return nodes[-1][1]

    def _element(self, i: int, j: int, area: float, modulus: float, inertia: float) -> None:
        self._next += 1
        self.ops.element("elasticBeamColumn", self._next, i, j, area, modulus, inertia, 1)

    def trace(self, levels: int, substeps: int) -> tuple[float, float, float] | None:
        """Load control to full load; the target's end (dx, dy, rotation), None if it fails."""
        ops = self.ops
        ops.integrator("LoadControl", 1.0 / ((levels - 1) * substeps))
        ops.analysis("Static")
        for _ in range(levels - 1):
            if ops.analyze(substeps) != 0:
                return None
        return (ops.nodeDisp(self.target, 1), ops.nodeDisp(self.target, 2),
                ops.nodeDisp(self.target_hub, 3))


def run_opensees(ops, mechanism: Mechanism, case: LoadCase, n: int, substeps: int):
    """Build and trace once: (wall seconds, CPU seconds, end values or None)."""
    t0, c0 = time.perf_counter(), time.process_time()
    end = OpenSeesModel(ops, mechanism, case, n).trace(case.levels, substeps)
    return time.perf_counter() - t0, time.process_time() - c0, end


def fewest_substeps(ops, mechanism: Mechanism, case: LoadCase, n: int) -> int | None:
    """The fewest sub-steps per load level with which OpenSees reaches full load."""
    for k in SUBSTEP_CHOICES:
        if run_opensees(ops, mechanism, case, n, k)[2] is not None:
            return k
    return None


def agreement(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    """Larger relative difference (per cent) of end displacement vector and end rotation."""
    d = np.hypot(a[0] - b[0], a[1] - b[1]) / max(np.hypot(a[0], a[1]), 1e-300)
    r = abs(a[2] - b[2]) / max(abs(a[2]), 1e-300)
    return 100.0 * max(d, r)


def time_both(order: str, repeats: int, mechanism: Mechanism, spec, case: LoadCase, ops, n: int,
              substeps: int):
    """Time ``repeats`` flexval and OpenSees paths in one order.

    ``"interleaved"`` alternates them (each run starts with caches the other
    code just used: the situation of a study that switches models);
    ``"blocks"`` runs flexval's repeats back to back, then OpenSees' (each
    run starts warm: a sweep of one model). Returns ((flexval wall, OpenSees
    wall, flexval CPU, OpenSees CPU) seconds per run, flexval's end values,
    OpenSees' end values).
    """
    ours, theirs, ours_cpu, theirs_cpu = [], [], [], []
    end = lp = None

    def flexval():
        nonlocal lp
        c0 = time.process_time()
        lp = run_reduced(mechanism, spec, case)
        ours_cpu.append(time.process_time() - c0)
        ours.append(lp.seconds)

    def peer():
        nonlocal end
        seconds, cpu, end = run_opensees(ops, mechanism, case, n, substeps)
        theirs.append(seconds)
        theirs_cpu.append(cpu)

    if order == "interleaved":
        for _ in range(repeats):
            flexval()
            peer()
    else:
        for run in [flexval] * repeats + [peer] * repeats:
            run()
    return (ours, theirs, ours_cpu, theirs_cpu), (lp.dx[-1], lp.dy[-1], lp.rotation[-1]), end


def geometric_mean(values: list[float]) -> float:
    """exp(mean(log(values)))."""
    return float(np.exp(np.mean(np.log(values))))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="*", default=["open_chain", "closed_chain"],
                        help="built-in scene names or scene TOML files")
    parser.add_argument("--n", type=int, default=100, help="elements per flexure (default 100)")
    parser.add_argument("--repeats", type=int, default=5, help="timing repeats (median)")
    args = parser.parse_args()
    ops = opensees()
    spec = parse_model(f"beam:{args.n}", "<command line>", "--n")
    print(f"beam:{args.n} against OpenSeesPy, {args.n} corotational elements per flexure; "
          f"median of {args.repeats}, model build included")
    print(f"{'scene':<13}{'case':<5}{'flexval ms':>11}{'OpenSees ms':>12}{'substeps':>9}"
          f"{'OpenSees/flexval':>17}{'agree %':>10}{'CPU ratio':>10}"
          f"{'b2b ours':>10}{'b2b OS':>10}{'b2b':>9}")
    ratios, cpu_ratios, block_ratios = [], [], []
    for name in args.scene:
        scene = load_scene(name)
        for case in scene.load_cases:
            k = fewest_substeps(ops, scene.mechanism, case, args.n)
            if k is None:
                print(f"{scene.name:<13}{case.name:<5} OpenSees does not converge with up to "
                      f"{SUBSTEP_CHOICES[-1]} sub-steps per level")
                continue
            (ours, theirs, ours_cpu, theirs_cpu), mine, end = time_both(
                "interleaved", args.repeats, scene.mechanism, spec, case, ops, args.n, k)
            back, _, _ = time_both("blocks", args.repeats, scene.mechanism, spec, case, ops,
                                   args.n, k)
            t_ours, t_theirs = statistics.median(ours), statistics.median(theirs)
            b_ours, b_theirs = statistics.median(back[0]), statistics.median(back[1])
            ratios.append(t_theirs / t_ours)
            block_ratios.append(b_theirs / b_ours)
            cpu_ratios.append(min(theirs_cpu) / min(ours_cpu))
            print(f"{scene.name:<13}{case.name:<5}{1e3 * t_ours:>11.1f}{1e3 * t_theirs:>12.1f}"
                  f"{k:>9}{t_theirs / t_ours:>16.2f}x{agreement(end, mine):>10.4f}"
                  f"{cpu_ratios[-1]:>9.2f}x{1e3 * b_ours:>10.1f}{1e3 * b_theirs:>10.1f}"
                  f"{b_theirs / b_ours:>8.2f}x")
    if ratios:
        print(f"geometric mean OpenSees/flexval: {geometric_mean(ratios):.2f}x interleaved "
              f"(fastest CPU times: {geometric_mean(cpu_ratios):.2f}x), "
              f"{geometric_mean(block_ratios):.2f}x back to back")


if __name__ == "__main__":
    main()
