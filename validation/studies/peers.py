"""The general-purpose peer: OpenSeesPy's corotational beams on a flexval mechanism,
timed beside ``beam:N``.

Both solve the same mechanism with N two-node corotational Euler-Bernoulli
elements per flexure, nodes on the centre line at arc lengths k L / N, along
the same load levels, in one process; :func:`compare_with_opensees` gives
both wall times (model build included), their ratio and how far apart the
end values are. ``benchmarks/bench_peers.py`` prints it; ``flexval report
--peers`` puts it in the report's run times (``timings.md``).

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
which the whole path converges. Gravity is not modelled:
:func:`compare_with_opensees` refuses scenes with it (the comparison would
not be of the same problem).

Two orders are timed: interleaved (flexval, OpenSees, flexval, ...: every
run starts with caches the other code just filled, as in a study that
switches models) and back to back (all flexval runs, then all OpenSees runs,
as in a sweep of one model). flexval's few-millisecond paths take longer
interleaved (``benchmarks/bench_peers.py`` times both orders); OpenSees'
longer ones hardly change, so the interleaved ratio is the conservative one.

OpenSeesPy is an optional extra: ``pip install -e ".[peers]"`` (on Debian it
needs the system's ``libblas3`` and ``liblapack3``).

Units: mm, N, N mm, rad; times in s.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from flexval.geometry import Force, LoadCase, Mechanism, Scene
from flexval.reducedmodels import run_reduced
from flexval.reducedmodels.catalogue import parse_model

RIGID_FACTOR = 1e8  # spokes' EA, EI over the flexures': the end values move 1e-4 % from
# 1e8 to 1e10 (0.01 % from 1e6 to 1e8); 1e10 breaks the 1e-10 test
TOLERANCE = 1e-10  # OpenSees NormDispIncr bound, mm and rad
MAX_ITERATIONS = 50  # Newton iterations per OpenSees sub-step before it counts as failed
SUBSTEP_CHOICES = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32)
AGREEMENT_BAR = 0.01  # per cent: both solve the same discrete problem to 1e-10


class PeerUnavailable(Exception):
    """OpenSeesPy cannot be imported, or the scene has what the OpenSees model leaves out."""


def opensees():
    """The ``openseespy.opensees`` module, its log silenced.

    Raises
    ------
    PeerUnavailable
        Saying how to install it, when it is missing or does not load.
    """
    try:
        import openseespy.opensees as ops
    except (ImportError, RuntimeError, OSError) as exc:
        raise PeerUnavailable(
            f"OpenSeesPy is missing or does not load ({exc}); install the optional extra: "
            'pip install -e ".[peers]" (on Debian also: apt-get install libblas3 '
            "liblapack3)"
        ) from None
    ops.logFile("/dev/null", "-noEcho")  # its warnings on the sub-step search's failed tries
    return ops


class OpenSeesModel:
    """The mechanism as an OpenSees model; remembers the target's node and body hub."""

    def __init__(self, ops, mechanism: Mechanism, case: LoadCase, n: int):
        self.ops, self._next = ops, 0
        ops.wipe()
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.geomTransf("Corotational", 1)
        self._nodes: dict[str, list[tuple[np.ndarray, int]]] = {}
        self.hubs = {
            name: self._body_node(name, body.reference) for name, body in mechanism.bodies.items()
        }
        ops.fix(self.hubs[mechanism.ground], 1, 1, 1)
        material = mechanism.material
        for flexure in mechanism.flexures:
            section = flexure.section
            shape = flexure.shape
            points = shape.point(np.linspace(0.0, shape.length, n + 1))
            chain = (
                [self._body_node(flexure.start_body, points[0])]
                + [self._new_node(p) for p in points[1:-1]]
                + [self._body_node(flexure.end_body, points[-1])]
            )
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
        loads = [
            (self._body_node(c.body, c.point), *c.vector, 0.0)
            if isinstance(c, Force)
            else (self.hubs[c.body], 0.0, 0.0, c.value)
            for c in case.components
        ]
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
        return (
            ops.nodeDisp(self.target, 1),
            ops.nodeDisp(self.target, 2),
            ops.nodeDisp(self.target_hub, 3),
        )


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


@dataclass(frozen=True)
class PeerRow:
    """One load case timed with flexval ``beam:N`` and OpenSees (seconds per run).

    ``substeps`` is None when OpenSees could not follow the case (then
    there are no times, and ``reason`` says why: no convergence with up to
    ``SUBSTEP_CHOICES[-1]`` sub-steps per level, or OpenSees' own error).
    ``ours``/``theirs`` are wall times of the interleaved runs, ``*_cpu``
    their process CPU times, ``*_b2b`` wall times of the back-to-back runs;
    ``agreement`` in per cent (:func:`agreement`).
    """

    case: str
    substeps: int | None
    ours: tuple[float, ...] = ()
    theirs: tuple[float, ...] = ()
    ours_cpu: tuple[float, ...] = ()
    theirs_cpu: tuple[float, ...] = ()
    ours_b2b: tuple[float, ...] = ()
    theirs_b2b: tuple[float, ...] = ()
    agreement: float = float("nan")
    reason: str = ""

    @property
    def ratio(self) -> float:
        """OpenSees' median interleaved wall time over flexval's."""
        return statistics.median(self.theirs) / statistics.median(self.ours)

    @property
    def cpu_ratio(self) -> float:
        """OpenSees' fastest interleaved CPU time over flexval's."""
        return min(self.theirs_cpu) / min(self.ours_cpu)

    @property
    def b2b_ratio(self) -> float:
        """OpenSees' median back-to-back wall time over flexval's."""
        return statistics.median(self.theirs_b2b) / statistics.median(self.ours_b2b)

    def to_dict(self) -> dict:
        """JSON-ready (seconds; the ratios included)."""
        out = {"load_case": self.case, "substeps": self.substeps}
        if self.substeps is None:
            out["reason"] = self.reason
        else:
            out.update(
                flexval=list(self.ours),
                opensees=list(self.theirs),
                flexval_cpu=list(self.ours_cpu),
                opensees_cpu=list(self.theirs_cpu),
                flexval_b2b=list(self.ours_b2b),
                opensees_b2b=list(self.theirs_b2b),
                agreement_percent=self.agreement,
                ratio=self.ratio,
                cpu_ratio=self.cpu_ratio,
                b2b_ratio=self.b2b_ratio,
            )
        return out


def _time_case(
    ops, mechanism: Mechanism, spec, case: LoadCase, n: int, substeps: int, repeats: int
) -> PeerRow:
    """Interleaved, then back-to-back runs of both codes on one load case."""
    walls: dict[str, list[float]] = {
        k: [] for k in ("ours", "theirs", "ours_cpu", "theirs_cpu", "ours_b2b", "theirs_b2b")
    }
    ends: dict[str, tuple[float, float, float]] = {}

    def flexval(key: str) -> Callable[[], None]:
        def run() -> None:
            c0 = time.process_time()
            lp = run_reduced(mechanism, spec, case)
            if key == "ours":
                walls["ours_cpu"].append(time.process_time() - c0)
            walls[key].append(lp.seconds)
            ends["ours"] = (lp.dx[-1], lp.dy[-1], lp.rotation[-1])

        return run

    def peer(key: str) -> Callable[[], None]:
        def run() -> None:
            seconds, cpu, end = run_opensees(ops, mechanism, case, n, substeps)
            if key == "theirs":
                walls["theirs_cpu"].append(cpu)
            walls[key].append(seconds)
            ends["theirs"] = end

        return run

    for _ in range(repeats):
        flexval("ours")()
        peer("theirs")()
    for run in [flexval("ours_b2b")] * repeats + [peer("theirs_b2b")] * repeats:
        run()
    return PeerRow(
        case.name,
        substeps,
        *(tuple(walls[k]) for k in walls),
        agreement(ends["theirs"], ends["ours"]),
    )


def compare_with_opensees(scene: Scene, n: int = 100, repeats: int = 5) -> list[PeerRow]:
    """flexval ``beam:n`` and OpenSees on every load case of ``scene``, timed in this process.

    Raises
    ------
    PeerUnavailable
        When OpenSeesPy cannot be imported, or the scene has gravity (not in
        the OpenSees model).

    A flexure whose section varies along it (a taper, a notch) has no
    counterpart in the model's uniform ``elasticBeamColumn`` elements (and
    ``beam:n`` grades its elements there): every case is then a row whose
    ``reason`` says so.
    """
    mech = scene.mechanism
    if mech.inertia.gravity is not None:
        raise PeerUnavailable(
            f"scene {scene.name!r} has gravity, which the OpenSees model leaves out"
        )
    varying = [f for f in mech.flexures if not f.section.is_uniform]
    if varying:  # a row per case saying why, like a failure: the report goes on
        f = varying[0]
        reason = (
            f"the OpenSees model has uniform sections only; flexure {f.name!r} has a "
            f"{f.section.profile.kind} thickness profile"
        )
        return [PeerRow(case.name, None, reason=reason) for case in scene.load_cases]
    ops = opensees()
    spec = parse_model(f"beam:{n}", "<peers>", "n")
    rows = []
    for case in scene.load_cases:
        try:
            k = fewest_substeps(ops, mech, case, n)
            rows.append(
                PeerRow(
                    case.name,
                    None,
                    reason="OpenSees did not converge with up to "
                    f"{SUBSTEP_CHOICES[-1]} sub-steps per level",
                )
                if k is None
                else _time_case(ops, mech, spec, case, n, k, repeats)
            )
        except ops.OpenSeesError as exc:  # the peer's failure is a result, not a crash
            rows.append(PeerRow(case.name, None, reason=f"OpenSees failed ({exc})"))
    return rows


def geometric_mean(values: list[float]) -> float:
    """exp(mean(log(values))) of positive ratios."""
    return float(np.exp(np.mean(np.log(values))))
