"""Arc-length continuation: consistency with the core, a published limit-point
benchmark (Da Deppo & Schmidt's deep arch), an exact snap-through (the von
Mises truss), a shallow-arch snap-through, and honest failures."""

import dataclasses
import math

import numpy as np
import pytest
from test_joints import von_mises_truss

from flexval.geometry import Arc, Force, LoadCase, Material, Section, load_scene
from flexval.geometry.mechanism import Body, FlexureSpec, Pin, PinSpec, assemble
from flexval.reducedmodels import SolverError, SolverSettings, build_system, solve_path
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.continuation import limit_loads, solve_arclength

DA_DEPPO_SCHMIDT = 8.97
"""Limit load P R^2 / EI of the clamped-hinged 215 deg circular arch under a
crown point load (Da Deppo & Schmidt 1975, inextensible elastica)."""


def _arch_halves(R: float, h: float, opening_deg: float, far_body: str):
    """Two arc flexures of a symmetric arch centred at the origin, crown at (0, R):
    ground -> crown body "c" -> ``far_body``. Returns (right, left, crown, specs)."""
    half = math.radians(opening_deg / 2)
    right = Arc((0.0, 0.0), R, math.pi / 2 - half / 2, half)
    left = Arc((0.0, 0.0), R, math.pi / 2 + half / 2, half)
    specs = [
        FlexureSpec("right", right, ("g", "c"), Section(1.0, h), start_body="g"),
        FlexureSpec("left", left, ("c", far_body), Section(1.0, h), start_body="c"),
    ]
    return right, left, np.array([0.0, R]), specs


def deep_arch(n: int, R: float = 100.0, h: float = 1.0, E: float = 1000.0):
    """Da Deppo & Schmidt's arch, radius R (mm), opening 215 deg, crown at (0, R).

    Clamped at its right end (polar angle -17.5 deg), pinned at its left end
    (197.5 deg): two arc flexures ground -> crown body "c" -> hinge body "h",
    the hinge body pinned to the ground. h / R = 1/100, so EA R^2 / EI =
    12 (R / h)^2 = 1.2e5: practically inextensible. Load: unit EI / R^2,
    downward at the crown, so the load factor is P R^2 / EI.
    """
    right, left, crown, specs = _arch_halves(R, h, 215.0, "h")
    pins = [PinSpec("hinge", ("h", "g"), tuple(left.end_points[1]))]
    mech = assemble(
        specs, "g", right.end_points[0][None], Material(E, 0.3), "c", crown, pin_specs=pins
    )
    EI = E * h**3 / 12.0
    case = LoadCase("P", (Force("c", crown, -math.pi / 2, EI / R**2),))
    return build_system(mech, parse_model(f"beam:{n}")), case


def _first_limit(n: int) -> float:
    system, case = deep_arch(n)
    lp = solve_arclength(
        system,
        case,
        12.0,
        40,
        model=f"beam:{n}",
        max_growth=1.0,
        stop=lambda p: bool(p.stats["limit_points"]),
    )
    loads = np.array(lp.load) / case.magnitude
    k = lp.stats["limit_points"][0]
    assert loads[-1] < loads[k] and loads[k] == loads.max()  # traced past the maximum
    return limit_loads(lp)[0] / case.magnitude


def test_deep_arch_limit_load_matches_da_deppo_and_schmidt():
    p20, p40, p80 = (_first_limit(n) for n in (20, 40, 80))
    # beam:40 per half: 8.9816, +0.13 %: the discretisation error of straight
    # corotational elements (O(N^-2), ~ +0.01 at N = 40) plus the 3-digit rounding of the
    # published value; axial extensibility (EA R^2/EI = 1.2e5) lowers it by ~2e-4 only
    assert p40 == pytest.approx(DA_DEPPO_SCHMIDT, rel=5e-3)
    # second-order convergence towards it: successive differences shrink ~4x
    assert 3.0 < (p20 - p40) / (p40 - p80) < 5.5
    richardson = p80 - (p40 - p80) / 3.0
    assert richardson == pytest.approx(DA_DEPPO_SCHMIDT, rel=1e-3)


def test_load_vector_is_the_load_derivative_of_the_gradient():
    for name, case_name in (("open_chain", "f+"), ("open_chain", "m+"), ("closed_chain", "f-")):
        scene = load_scene(name)
        system = build_system(scene.mechanism, parse_model("dcmm:2"))
        loads = system.loads(scene.load_case(case_name))
        rng = np.random.default_rng(5)
        q = system.initial_state() + rng.normal(0.0, 0.3, system.n_dofs)
        _, g0, _ = system.assemble(q, loads, 0.0)
        _, g1, _ = system.assemble(q, loads, 1.0)
        # the gradient is affine in the load factor: exact up to the round-off of g
        np.testing.assert_allclose(loads.vector(q), g0 - g1, rtol=0, atol=1e-12 * np.abs(g0).max())


def test_without_limit_point_arclength_ends_on_the_load_controlled_state():
    scene = load_scene("closed_chain")
    case = scene.load_case("f-")
    system = build_system(scene.mechanism, parse_model("dcmm:2"))
    arc = solve_arclength(system, case, 1.0, 8, model="dcmm:2")
    ref = solve_path(system, case)
    assert arc.model == "dcmm:2:arclength" and arc.converged
    assert arc.load[-1] == case.magnitude and arc.stats["limit_points"] == []
    # both converge to force_tol = 1e-10: the same equilibrium to ~1e-10 of the motion
    scale = np.hypot(ref.dx[-1], ref.dy[-1])
    assert abs(arc.dx[-1] - ref.dx[-1]) < 1e-8 * scale
    assert abs(arc.dy[-1] - ref.dy[-1]) < 1e-8 * scale
    assert arc.rotation[-1] == pytest.approx(ref.rotation[-1], rel=1e-8)


def test_von_mises_truss_snaps_through_on_the_exact_path():
    mech, load = von_mises_truss()
    a, h0, L0 = 100.0, 20.0, math.hypot(100.0, 20.0)
    L = (a * a * L0) ** (1.0 / 3.0)  # dP/dw = 0 where L^3 = a^2 L0
    p_max = float(load(h0 - math.sqrt(L * L - a * a)))
    case = LoadCase("P", (Force("c", mech.target_point, -math.pi / 2, 1.5 * p_max),))
    system = build_system(mech, parse_model("beam:1"), SolverSettings(max_translation_step=0.01))
    lp = solve_arclength(system, case, 1.0, 20, model="beam:1")
    w = -np.array(lp.dy)
    # every traced point is an exact equilibrium (to the solver tolerance, 1e-10 of the load)
    np.testing.assert_allclose(load(w), lp.load, rtol=0, atol=1e-8 * p_max)
    # through the maximum, down through the inverted minimum, up to 1.5 P_max beyond
    assert len(lp.stats["limit_points"]) == 2 and w[-1] > 2 * h0
    assert lp.load[-1] == 1.5 * p_max
    # parabolic refinement over steps of <= 2 mm: about 2e-4 of P_max
    np.testing.assert_allclose(limit_loads(lp), [p_max, -p_max], rtol=1e-3)


def _shallow_arch():
    """Clamped shallow arch: R = 100 mm, 20 deg opening (rise 1.52 mm), h = 0.1 mm, beam:16."""
    R, h, E = 100.0, 0.1, 1000.0
    right, left, crown, specs = _arch_halves(R, h, 20.0, "g")
    mech = assemble(
        specs,
        "g",
        np.array([right.end_points[0], left.end_points[1]]),
        Material(E, 0.3),
        "c",
        crown,
    )
    p0 = E * h**3 / 12.0 / R**2
    return mech, LoadCase("P", (Force("c", crown, -math.pi / 2, 200.0 * p0),))


def test_shallow_arch_snap_through_is_traced_past_the_limit_point():
    mech, case = _shallow_arch()
    settings = SolverSettings(max_translation_step=0.01, max_cuts=20, max_iterations=12)
    system = build_system(mech, parse_model("beam:16"), settings)
    lp = solve_arclength(system, case, 1.0, 40, model="beam:16")
    load = np.array(lp.load)
    top, bottom = lp.stats["limit_points"][:2]
    # up to the limit, down to less than half of it, then up again on the inverted branch
    # (crown below the chord: deflection beyond the rise R (1 - cos 10 deg) = 1.52 mm)
    assert 0 < top < bottom and load[bottom] < 0.5 * load[top]
    assert load[-1] == case.magnitude > load[top]
    assert lp.dy[-1] < -100.0 * (1.0 - math.cos(math.radians(10.0)))
    peak = limit_loads(lp)[0]
    # load control stops at the same limit: the last load it converges is just below it
    with pytest.raises(SolverError) as info:
        solve_path(system, case)
    reached = info.value.load_factor * case.magnitude
    assert "step cutting failed" in str(info.value)
    # sampling of the arc-length path (refined by a parabola) limits the match to ~1e-4
    assert reached == pytest.approx(peak, rel=1e-3)


def test_arclength_failures_are_solver_errors_with_the_load_reached():
    system, case = deep_arch(10)
    with pytest.raises(SolverError) as info:
        solve_arclength(system, case, 12.0, 20, model="beam:10", max_steps=5)
    err = info.value
    assert "not reached in 5 steps" in str(err) and "beam:10:arclength" in str(err)
    assert len(err.path.load) == 6 and not err.path.converged
    assert err.load_factor == pytest.approx(err.path.load[-1] / case.magnitude, rel=1e-14)
    with pytest.raises(ValueError, match="max_load_factor"):
        solve_arclength(system, case, -1.0, 20)


def test_a_free_mechanism_is_a_solver_error_not_a_crash():
    # body "x" hangs from body "t" by one pin and may turn freely: singular tangent.
    # assemble refuses such a mechanism (tests/test_scene_errors.py); built past it, the
    # solvers must still report the singular tangent rather than crash
    arc = Arc((0.0, 0.0), 5.0, 0.0, math.radians(90))
    end = arc.end_points[1]
    spec = FlexureSpec("f", arc, ("g", "t"), Section(1.0, 0.2), start_body="g")
    held = assemble([spec], "g", arc.end_points[0][None], Material(2000.0, 0.3), "t", end)
    mech = dataclasses.replace(
        held,
        bodies={**held.bodies, "x": Body("x", end[None])},
        pins=(Pin("p", ("t", "x"), end),),
        target_body="x",
        target_point=end + [3.0, 0.0],
    )
    case = LoadCase("F", (Force("t", end, 0.0, 1e-3),))
    system = build_system(mech, parse_model("dcmm:1"))
    for solve in (
        lambda: solve_path(system, case),
        lambda: solve_arclength(system, case, 1.0, 10, model="dcmm:1"),
    ):
        with pytest.raises(SolverError, match="singular"):
            solve()


def test_arclength_drives_the_continuum_solver_too():
    """The continuum is a connector on the same core, so arc-length continuation
    traces it unchanged: on a monotone path it must reach the load-control end state
    (both are exact equilibria of the same discrete system; gate 1e-6 relative)."""
    from flexval.geometry import Segment
    from flexval.validation.continuum.run import build_system as continuum_system

    seg = Segment((0.0, 0.0), (20.0, 0.0))
    spec = FlexureSpec("s", seg, ("g", "t"), Section(1.0, 1.0), start_body="g")
    mech = assemble(
        [spec], "g", np.array([[0.0, 0.0]]), Material(2000.0, 0.3), "t", np.array([20.0, 0.0])
    )
    EI = 2000.0 / 12.0
    case = LoadCase("P", (Force("t", mech.target_point, math.pi / 2, 1.5 * EI / 400.0),), 5)
    ref = solve_path(continuum_system(mech, 0), case)
    arc = solve_arclength(continuum_system(mech, 0), case, 1.0, 6, model="continuum:0")
    assert arc.load[-1] == pytest.approx(ref.load[-1], rel=1e-12)
    assert arc.dy[-1] == pytest.approx(ref.dy[-1], rel=1e-6)
    assert arc.rotation[-1] == pytest.approx(ref.rotation[-1], rel=1e-6)
