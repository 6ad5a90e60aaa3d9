"""Time integration (flexval.reducedmodels.analyses.dynamics) and load time laws
(flexval.geometry.timelaw)."""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest

from flexval.geometry import MassData, RigidMass, SceneError, Segment
from flexval.geometry.scene import parse_scene
from flexval.geometry.timelaw import TimeLaw, eq15_ramp
from flexval.reducedmodels.analyses.dynamics import DynamicSettings, Rayleigh, solve_dynamic
from flexval.reducedmodels.analyses.modes import natural_modes
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.connector import Connector
from flexval.reducedmodels.core.inertia import MassModel
from flexval.reducedmodels.core.recorder import solve_path
from flexval.reducedmodels.core.system import System
from flexval.reducedmodels.models import build_system
from tests.builders import cantilever, tip_moment
from tests.test_inertia import SCENE

L, E = 10.0, 2100.0
EI = E * 0.1**3 / 12.0


def test_eq15_ramp_is_a_smooth_step():
    """0 before t0, 1 after t1, 1/2 at the middle; zero slope and curvature at both ends."""
    t0, t1 = 0.5, 2.5
    assert eq15_ramp(0.0, t0, t1) == 0.0 and eq15_ramp(3.0, t0, t1) == 1.0
    assert eq15_ramp(1.5, t0, t1) == pytest.approx(0.5, abs=1e-15)
    h = 1e-4
    for t in (t0, t1):
        slope = (eq15_ramp(t + h, t0, t1) - eq15_ramp(t - h, t0, t1)) / (2 * h)
        curvature = (
            eq15_ramp(t + h, t0, t1) - 2 * eq15_ramp(t, t0, t1) + eq15_ramp(t - h, t0, t1)
        ) / h**2
        assert abs(slope) < 1e-6 and abs(curvature) < 1e-2


class LinearSpring(Connector):
    """Springs k (N/mm, N/mm, N mm/rad) on the pose of body b from its rest pose."""

    def __init__(self, k, rest):
        self.name, self.bodies = "spring", ("g", "t")
        self.k, self.rest = np.asarray(k, float), np.asarray(rest, float)

    def evaluate(self, pose_a, pose_b, internal):
        d = pose_b - self.rest
        g = np.zeros(6)
        g[3:] = self.k * d
        H = np.zeros((6, 6))
        H[3:, 3:] = np.diag(self.k)
        return 0.5 * float(d @ (self.k * d)), g, H

    def shape(self, pose_a, pose_b, internal):
        return np.array([pose_a[:2], pose_b[:2]])


def model_system(mech, model: str) -> System:
    """The System of ``mech`` with every flexure as ``model`` (continuum:LEVEL included)."""
    if model.startswith("continuum"):
        from flexval.validation.continuum.run import build_system as continuum_system

        return continuum_system(mech, int(model.split(":")[1]))
    return build_system(mech, parse_model(model))


def spring_system():
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)))
    mech = dataclasses.replace(
        mech, inertia=MassData(bodies={"t": RigidMass(1e-6, 2e-5, np.array([L, 0.0]))})
    )
    return System(mech, [LinearSpring([1.0, 3.0, 50.0], [L, 0.0, 0.0])])


@pytest.mark.parametrize("adaptive", [False, True])
def test_energy_is_conserved_without_dissipation(adaptive):
    """Linear springs, constant mass, no damping, rho_inf = 1 (trapezoidal rule): kinetic
    plus elastic energy after 500 steps equals the initial kinetic energy to round-off
    (measured 2.4e-12); rho_inf = 0.8 dissipates (measured -7e-4)."""
    system = spring_system()
    v0 = np.array([20.0, -30.0, 5.0])
    e0 = MassModel(system).kinetic_energy(system.initial_state(), v0)
    results = {}
    for rho in (1.0, 0.8):
        lp = solve_dynamic(
            system,
            tip_moment(0.0, levels=2),
            TimeLaw("eq15", 0.0, 0.01),
            0.05,
            settings=DynamicSettings(
                rho_inf=rho, adaptive=adaptive, first_step=2e-3, max_step=2e-3
            ),
            initial_velocity=v0,
            record_poses=True,
        )
        u = np.array(lp.poses["t"][-1]) - [L, 0.0, 0.0]
        elastic = 0.5 * float(np.sum(np.array([1.0, 3.0, 50.0]) * u**2))
        results[rho] = (lp.stats["kinetic_energy"] + elastic) / e0 - 1.0
    assert abs(results[1.0]) < 1e-10
    assert results[0.8] < -1e-5


def test_rayleigh_ratio_is_exact_at_both_frequencies():
    d = Rayleigh.from_ratio(0.05, 10.0, 80.0)
    for f in (10.0, 80.0):
        w = 2 * math.pi * f
        assert d.alpha / (2 * w) + d.beta * w / 2 == pytest.approx(0.05, rel=1e-14)


@pytest.mark.parametrize("model", ["dcmm:1", "beam:10", "prbm", "continuum:0"])
def test_slow_damped_ramp_follows_the_static_path(model):
    """A moment ramped by Eq. 15 over 30000 periods of the first mode, damping ratio 1 at
    the two lowest modes, step error tolerance 1e-4: the target rotation, interpolated at
    each level's load factor during the ramp, is within 0.1 % of the static path
    (largest lag measured: prbm 0.010 %, beam:10 0.019 %, dcmm:1 0.026 %, continuum:0
    0.046 %; it scales as 1 / ramp time: 0.137 % for the continuum over 10000 periods),
    and equal at the end (measured 9e-9; bound 1e-6)."""
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)))
    mech = dataclasses.replace(
        mech,
        inertia=MassData(
            density=1.24e-9, bodies={"t": RigidMass(1e-9, 1e-8, np.array([L + 1.0, 0.0]))}
        ),
    )
    case = tip_moment(0.5 * EI / L, levels=11)  # about 1 rad at full load
    system = model_system(mech, model)
    f = natural_modes(system, count=2).frequencies_hz
    static = solve_path(system, case)
    ramp = 30000.0 / f[0]
    lp = solve_dynamic(
        system,
        case,
        TimeLaw("eq15", 0.0, ramp),
        1.5 * ramp,
        Rayleigh.from_ratio(1.0, f[0], f[1]),
        DynamicSettings(error_tol=1e-4),
    )
    t, lam = np.array(lp.time), np.array(lp.load) / case.magnitude
    during = t <= ramp
    rotation = np.interp(
        static.load[1:-1] / np.float64(case.magnitude), lam[during], np.array(lp.rotation)[during]
    )
    np.testing.assert_allclose(rotation, static.rotation[1:-1], rtol=1e-3)
    assert lp.rotation[-1] == pytest.approx(static.rotation[-1], rel=1e-6)


def test_dynamic_run_refuses_a_massless_body():
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)))
    system = build_system(mech, parse_model("beam:4"))
    with pytest.raises(SceneError, match="dynamic run"):
        solve_dynamic(system, tip_moment(1e-3), TimeLaw(), 1.0)


@pytest.mark.parametrize(
    "fields, field",
    [
        ({"ramp": "cubic", "t1": 1.0}, "ramp"),
        ({"t0": 1.0, "t1": 0.5}, "t1"),
        ({"ramp": "eq15"}, "t1"),
        ({"t1": 1.0, "end_time": -2.0}, "end_time"),
    ],
)
def test_bad_time_law_names_the_field(fields, field):
    data = tomllib.loads(SCENE)
    data["load_cases"][0].update(fields)
    with pytest.raises(SceneError) as info:
        parse_scene(data, "<test>")
    assert info.value.field == f"load_cases.m.{field}"


def test_cli_dynamic_run_writes_time_histories(tmp_path):
    from flexval.validation.cli import main

    data = SCENE + 'ramp = "eq15"\nt1 = 0.05\nend_time = 0.08\n'
    scene = tmp_path / "dyn.toml"
    scene.write_text(data, encoding="utf-8")
    out = tmp_path / "dyn.json"
    assert (
        main(
            [
                "run",
                str(scene),
                "--dynamic",
                "--model",
                "dcmm:1",
                "--damping-ratio",
                "1",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    result = json.loads(out.read_text())["results"][0]
    assert result["time"][-1] == pytest.approx(0.08)
    assert len(result["time"]) == len(result["rotation"]) > 2
    assert (
        main(
            [
                "run",
                str(scene),
                "--dynamic",
                "--model",
                "dcmm:1",
                "--damping-ratio",
                "1",
                "--error-tol",
                "1e-7",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    finer = json.loads(out.read_text())["results"][0]
    assert finer["settings"]["error_tol"] == 1e-7 and result["settings"]["error_tol"] == 1e-5
    assert len(finer["time"]) > len(result["time"])  # a tighter bound takes more steps
    assert (
        main(
            [
                "run",
                str(scene),
                "--dynamic",
                "--model",
                "continuum:0",
                "--damping-ratio",
                "1",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    result = json.loads(out.read_text())["results"][0]
    assert result["time"][-1] == pytest.approx(0.08) and result["model"] == "continuum:0"


@pytest.mark.parametrize("tip_body_mass", [True, False])
def test_continuum_conserves_energy_without_dissipation(tip_body_mass):
    """continuum:0 cantilever, started in its first mode shape (velocity, tip amplitude
    1e-4 of the length; no load, no damping, rho_inf = 1, 20 fixed steps over 4 periods):
    its consistent mass with the end faces' convective forces keeps kinetic plus strain
    energy constant, up to the motion's nonlinearity: measured drift 1.2e-9 relative with
    a tip body mass; bound 1e-7. rho_inf = 0.8 dissipates (measured -6 %). Without mass
    data for the tip body every mass is the continuum's consistent matrix (no lumped
    points at all: the case a numpy quirk once turned into a dtype error)."""
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)))
    bodies = {"t": RigidMass(1e-9, 1e-9, np.array([L + 0.5, 0.0]))} if tip_body_mass else {}
    mech = dataclasses.replace(mech, inertia=MassData(density=1.24e-9, bodies=bodies))
    system = model_system(mech, "continuum:0")
    mode = natural_modes(system, count=1)
    f1, shape = mode.frequencies_hz[0], mode.shapes[0]
    v0 = shape * (2 * math.pi * f1 * 1e-4 * L / np.abs(shape[system.pose_dofs("t")[:2]]).max())
    e0 = MassModel(system).kinetic_energy(system.initial_state(), v0)
    drift = {}
    for rho in (1.0, 0.8):
        lp = solve_dynamic(
            system,
            tip_moment(0.0, levels=2),
            TimeLaw("eq15", 0.0, 1.0 / f1),
            4.0 / f1,
            settings=DynamicSettings(rho_inf=rho, adaptive=False, first_step=0.05, max_step=0.05),
            initial_velocity=v0,
        )
        assert lp.stats["steps"] == 20
        drift[rho] = (lp.stats["kinetic_energy"] + lp.stats["potential_change"]) / e0 - 1.0
    assert abs(drift[1.0]) < 1e-7
    assert drift[0.8] < -1e-2


def test_stiffness_proportional_damping_converges_at_second_order():
    """Generalised-alpha is second order, and so must be its damping force beta K(q) v.
    A cantilever (beam:4) swung to about 0.5 rad within 3 first periods, damped by
    beta K only (ratio 0.3 at f1), fixed steps: the end rotation's change from 50 to 100
    steps is at least 3 times the change from 100 to 200 (second order: 4; measured
    4.5, changes 4.5e-4 and 1.0e-4 rad). With K frozen at the start of each step the
    ratio was 1.8 and the changes 0.054 and 0.031 rad."""
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)))
    mech = dataclasses.replace(
        mech,
        inertia=MassData(
            density=1.24e-9, bodies={"t": RigidMass(1e-9, 1e-8, np.array([L + 1.0, 0.0]))}
        ),
    )
    case = tip_moment(0.5 * EI / L, levels=11)
    system = build_system(mech, parse_model("beam:4"))
    f1 = natural_modes(system, count=1).frequencies_hz[0]
    end = 3.0 / f1
    damping = Rayleigh(0.0, 2.0 * 0.3 / (2.0 * math.pi * f1))
    ends = []
    for steps in (50, 100, 200):
        lp = solve_dynamic(
            system,
            case,
            TimeLaw("eq15", 0.0, end),
            end,
            damping,
            DynamicSettings(adaptive=False, first_step=1.0 / steps, max_step=1.0 / steps),
        )
        assert lp.stats["steps"] == steps
        ends.append(lp.rotation[-1])
    coarse, fine = abs(ends[1] - ends[0]), abs(ends[2] - ends[1])
    assert coarse > 3.0 * fine


def _swinging_cantilever_step(beta: float):
    """A beam:4 cantilever moving between two static states, and one generalised-alpha step.

    The tip body's mass sits on the flexure's end node (as do the nodes'
    lumped masses), so M is constant and the convective forces vanish: the
    step's residual then has no term the effective tangent leaves out.
    """
    from flexval.reducedmodels.analyses.dynamics import DynamicStep, GeneralizedAlpha
    from flexval.reducedmodels.core.tracer import LoadControl, trace

    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)))
    mech = dataclasses.replace(
        mech,
        inertia=MassData(density=1.24e-9, bodies={"t": RigidMass(1e-9, 1e-8, np.array([L, 0.0]))}),
    )
    case = tip_moment(EI / L, levels=11)
    system = build_system(mech, parse_model("beam:4"))
    loads = system.loads(case)
    states = [p.state for p in trace(system, loads, LoadControl(case.factors()))]
    h = 1e-3
    moving = (
        states[4],
        (states[6] - states[4]) / (2 * h),
        np.zeros_like(states[4]),
        np.zeros_like(states[4]),
    )
    step = DynamicStep(
        system,
        loads,
        0.55,
        MassModel(system),
        moving,
        h,
        GeneralizedAlpha(0.9),
        Rayleigh(0.0, beta),
    )
    return system, step, states[5]


@pytest.mark.parametrize("beta", [0.0, 1e-3])
def test_effective_tangent_is_the_jacobian_of_the_step_residual(beta):
    """Central differences of the dynamic step's residual give its tangent to 2e-9 (measured
    3.8e-11 undamped, 1.9e-9 with beta = 1e-3 s); leaving out the damping force's derivative
    beta dK(q)[v], as the integrator did before, is off by 1.9e-2 of the tangent here."""
    system, step, q = _swinging_cantilever_step(beta)
    _, tangent = step.assemble(q)
    effective = tangent.toarray()
    scale = np.where(system.is_rotation, 1.0, system.size)
    jacobian = np.empty_like(effective)
    for k in range(q.size):
        dq = np.zeros(q.size)
        dq[k] = 1e-6 * scale[k]
        jacobian[:, k] = (step.assemble(q + dq)[0] - step.assemble(q - dq)[0]) / (2 * dq[k])
    assert np.abs(jacobian - effective).max() < 1e-8 * np.abs(effective).max()


def test_mass_outside_the_tangent_storage_gives_the_same_step(monkeypatch):
    """A mass matrix the tangent's storage cannot hold (a user connector coupling fewer
    coordinates than its masses do) takes a scipy matrix instead: the same residual and
    the same Newton correction to round-off."""
    system, step, q = _swinging_cantilever_step(1e-3)
    r, tangent = step.assemble(q)
    monkeypatch.setattr(type(system.layout), "slots_of", lambda self, rows, cols: None)
    r_scipy, tangent_scipy = step.assemble(q)
    np.testing.assert_allclose(r_scipy, r, rtol=0, atol=1e-12 * np.abs(r).max())
    du = tangent.solve(-r)
    np.testing.assert_allclose(tangent_scipy.solve(-r), du, rtol=0, atol=1e-10 * np.abs(du).max())


@pytest.mark.parametrize("value", ["0", "-1e-5", "nan", "0.5"])
def test_bad_error_tol_names_the_option(tmp_path, capsys, value):
    from flexval.validation.cli import main

    scene = tmp_path / "dyn.toml"
    scene.write_text(SCENE + 'ramp = "eq15"\nt1 = 0.05\n', encoding="utf-8")
    assert main(["run", str(scene), "--dynamic", "--model", "dcmm:1", f"--error-tol={value}"]) == 2
    err = capsys.readouterr().err
    assert "--error-tol" in err and repr(float(value)) in err


def test_without_a_time_law_the_default_duration_is_that_of_t1_1s(tmp_path, capsys):
    """The help's default: a load case without a time law ramps by Eq. 15 from 0 to
    t1 = 1 s and runs 1.25 t1, exactly as the time law ``t1 = 1`` and as ``--duration 1.25``."""
    from flexval.validation.cli import main

    bare, ramped = tmp_path / "bare.toml", tmp_path / "ramped.toml"
    bare.write_text(SCENE, encoding="utf-8")
    ramped.write_text(SCENE + "t1 = 1.0\n", encoding="utf-8")
    args = ["--dynamic", "--model", "dcmm:1", "--damping-ratio", "1"]
    runs = []
    for scene, extra in ((bare, []), (bare, ["--duration", "1.25"]), (ramped, [])):
        out = tmp_path / f"r{len(runs)}.json"
        assert main(["run", str(scene), *args, *extra, "--json", str(out)]) == 0
        (result,) = json.loads(out.read_text())["results"]
        runs.append({k: result[k] for k in ("time", "load", "dx", "dy", "rotation")})
    assert runs[0]["time"][-1] == pytest.approx(1.25, rel=1e-12)
    full = tomllib.loads(SCENE)["load_cases"][0]["value"]
    assert runs[0]["load"][-1] == pytest.approx(full, rel=1e-12)
    assert runs[0] == runs[1] == runs[2]
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    assert "t1 = 1 s, a run of 1.25 s" in " ".join(capsys.readouterr().out.split())
