"""Peak outer-fibre stress from each model's own section forces.

References: a pure end moment on an arc (M uniform and equal to the applied
moment, N = 0: sigma = 6 M / (b h^2) everywhere); a cantilever arc under a
small end force (linear statics on the undeformed arc: N(s) = F . t(s),
M(s) = (x_L - x(s)) x F); a straight cantilever under a large tip force
(root moment P x_L from the Bisshopp-Drucker elastica); and the mesh
convergence of the continuum's section-resultant measure.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import cantilever, tip_force, tip_moment
from elastica import cantilever_tip_force

from flexval.geometry import Arc, Segment
from flexval.reducedmodels import run_reduced
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.sections import statics_section_forces
from flexval.validation.studies.convergence import richardson

B, H, E = 2.0, 0.5, 2100.0
ARC = Arc((0.0, 0.0), 10.0, math.radians(-30.0), math.radians(150.0))


def _run(mech, case, model: str):
    return run_reduced(mech, parse_model(model), case)


@pytest.mark.parametrize("model", ["beam:8", "beam:8[shear]", "dcmm:1", "dcmm:3", "prbm", "ee"])
def test_pure_end_moment_gives_the_uniform_bending_stress(model):
    # 40 N mm turns the 26 mm arc by M L / EI ~ 0.5 rad: a large rotation
    mech = cantilever(ARC, E=E, b=B, h=H)
    moment = 40.0
    lp = _run(mech, tip_moment(moment, levels=5), model)
    expected = 6.0 * np.asarray(lp.load) / (B * H**2)
    # at rest the internal forces are the solver's residual (~1e-11 MPa here)
    np.testing.assert_allclose(lp.peak_stress["f"], expected, rtol=1e-7, atol=1e-9)
    profile = np.asarray(lp.stress_profile["f"]["stress"])
    np.testing.assert_allclose(profile, expected[-1], rtol=1e-7)  # the same all along
    at = np.asarray(lp.stress_profile["f"]["at"])
    assert at[0] == 0.0 and at[-1] == 1.0 and np.all(np.diff(at) >= 0.0)


def _linear_statics(force: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Outer-fibre stress of the undeformed arc under the tip force, MPa."""
    s = at * ARC.length
    x, tip = ARC.point(s), ARC.end_points[1]
    angle = ARC.tangent_angle(s)
    axial = force[0] * np.cos(angle) + force[1] * np.sin(angle)
    r = tip - x
    moment = r[:, 0] * force[1] - r[:, 1] * force[0]
    return np.abs(axial) / (B * H) + 6.0 * np.abs(moment) / (B * H**2)


@pytest.mark.parametrize("model, rtol", [("beam:40", 3e-5), ("dcmm:1", 3e-5), ("ee", 1e-9)])
def test_small_end_force_gives_the_linear_statics_along_the_arc(model, rtol):
    # the nonlinear models differ from linear statics by the geometric change under load:
    # measured 1.2e-5 to 1.3e-5 (beam:40, beam:80, dcmm:1, dcmm:4), 10 times more at 10 times
    # the force; the linear ee agrees to round-off (8e-12)
    mech = cantilever(ARC, E=E, b=B, h=H)
    force = np.array([3e-6, -4e-6])
    lp = _run(mech, tip_force(mech, *force, levels=3), model)
    profile = lp.stress_profile["f"]
    expected = _linear_statics(force, np.asarray(profile["at"]))
    np.testing.assert_allclose(profile["stress"], expected, rtol=rtol, atol=rtol * expected.max())
    assert lp.peak_stress["f"][-1] == pytest.approx(expected.max(), rel=rtol)


def test_large_tip_force_root_stress_matches_the_elastica():
    # straight cantilever, P L^2 / EI = 2: tip slope ~ 37 deg; root moment P x_L
    L = 20.0
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), E=E, b=B, h=H)
    EI = E * B * H**3 / 12.0
    P = 2.0 * EI / L**2
    x_tip, _, _ = cantilever_tip_force(2.0)
    # at the root the axis stays horizontal and the dead force is vertical: N = 0 there
    expected = 6.0 * P * x_tip * L / (B * H**2)
    lp = _run(mech, tip_force(mech, 0.0, P, levels=5), "beam:64")
    assert lp.peak_stress_at["f"][-1] == 0.0
    # inextensible reference; beam:64 converges at O(1/N^2) (~1e-4 here) plus axial strain
    assert lp.peak_stress["f"][-1] == pytest.approx(expected, rel=5e-4)


def test_statics_reports_fractions_from_the_first_end_when_reversed():
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    forward = statics_section_forces(
        pts, np.array([0.0, 0.5, 1.0]), np.array([0.0, 1.0, 0.0]), np.array([2.0, 0.0, 0.0])
    )
    backward = statics_section_forces(
        pts[::-1],
        np.array([0.0, 0.5, 1.0]),
        np.array([0.0, -1.0, 0.0]),
        np.array([0.0, 0.0, 0.0]),
        reverse=True,
    )
    # a unit transverse force at x = 2 (forward) / x = 0 (backward): |M| = distance to it
    np.testing.assert_allclose(np.abs(forward.moment), [2.0, 1.0, 1.0, 0.0])
    np.testing.assert_allclose(backward.at, [0.0, 0.5, 0.5, 1.0])
    np.testing.assert_allclose(np.abs(backward.moment), [0.0, 1.0, 1.0, 2.0])


def test_continuum_section_resultant_stress_converges_with_the_mesh():
    # a thick arc (R/h = 8) under an end force: levels 0, 1, 2 halve the element size
    from flexval.validation.continuum.run import run_continuum

    arc = Arc((0.0, 0.0), 8.0, math.radians(-30.0), math.radians(120.0))
    mech = cantilever(arc, E=E, b=B, h=1.0)
    case = tip_force(mech, 0.0, -2.0, levels=2)
    peaks = [run_continuum(mech, case, level=k).peak_stress["f"][-1] for k in (0, 1, 2)]
    conv = richardson(*peaks, 2.0)
    assert conv["order"] is not None and conv["order"] > 1.5
    assert conv["gci_percent"] < 0.05
    # measured: order 2.5, GCI 0.006 %; beam:64 lies 0.08 % below the extrapolated continuum
    # (shear and the thick arc's nonlinear strain across the section, R/h = 8)
    beam = _run(mech, case, "beam:64").peak_stress["f"][-1]
    assert beam == pytest.approx(conv["extrapolated"], rel=2e-3)


@pytest.mark.parametrize("model", ["beam:40", "dcmm:4"])
def test_self_weight_moment_follows_the_distributed_load(model):
    """A horizontal cantilever under its own weight q = rho A g: M(s) = q (L - s)^2 / 2.

    The weight acts inside the flexure, so the section forces must come from each element's
    own forces (not from the end wrench). beam:N's lumped nodal weights give the moment at
    the nodes exactly (the trapezoid rule of a linear lever arm). dcmm:N's bodies carry
    their nearest half sub-arcs as rigid pieces: the piece on the ground (length l/2,
    centre l/4 from the root) loads the ground directly, so its root moment is
    q L^2/2 - q l^2/8, the rest exactly (each piece's weight at its centre). The sag
    (1e-3 L) shortens the lever arms at second order: measured 3e-7 at the root (both
    models) and 1.7e-6 along beam:40; bound 1e-5. beam:N is checked at every node, dcmm:N
    at its root, where the peak lies (between its cuts its sub-arcs carry no load, so its
    moment is linear there).
    """
    import dataclasses

    from flexval.geometry.inertia import MassData

    L, rho, g = 10.0, 1.24e-9, 9810.0
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), E=E, b=B, h=0.1)
    mech = dataclasses.replace(mech, inertia=MassData(density=rho, gravity=np.array([0.0, -g])))
    lp = _run(mech, tip_moment(0.0, levels=2), model)
    q = rho * B * 0.1 * g
    moment = lambda s: q * (L - s) ** 2 / 2.0  # noqa: E731
    stress = lambda s: 6.0 * moment(s) / (B * 0.1**2)  # noqa: E731 (N ~ 1e-3 q L)
    assert lp.peak_stress_at["f"][-1] == 0.0
    ground_piece = 0.0 if model.startswith("beam") else (L / int(model.split(":")[1])) ** 2 / 8.0
    root = 6.0 * (moment(0.0) - q * ground_piece) / (B * 0.1**2)
    assert lp.peak_stress["f"][-1] == pytest.approx(root, rel=1e-5)
    if model.startswith("beam"):
        profile = lp.stress_profile["f"]
        at = np.asarray(profile["at"])
        np.testing.assert_allclose(
            profile["stress"], stress(at * L), rtol=1e-5, atol=1e-5 * stress(0.0)
        )


@pytest.mark.parametrize("r_over_h", [2.0, 8.3, 30.0])
def test_curved_beam_factor_is_the_winkler_bach_inner_fibre_stress(r_over_h):
    """sigma(r) = M (r_n - r) / (A e r) carries no net force and the moment M about the
    centroid (checked by quadrature), and its inner-fibre value over 6 M / (b h^2) is the
    factor; for r >> h it tends to 1 + h / (3 r)."""
    from scipy.integrate import quad

    from flexval.validation.report.strength import curved_beam_factor

    h, b, M = 1.0, 1.0, 1.0
    r = r_over_h * h
    r_i, r_o = r - h / 2, r + h / 2
    r_n = h / math.log(r_o / r_i)
    e = r - r_n
    sigma = lambda x: M * (r_n - x) / (b * h * e * x)  # noqa: E731
    assert abs(quad(sigma, r_i, r_o, epsabs=1e-13)[0] * b) < 1e-9
    assert quad(lambda x: sigma(x) * (r - x), r_i, r_o)[0] * b == pytest.approx(M, rel=1e-9)
    factor = curved_beam_factor(r, h)
    assert factor == pytest.approx(sigma(r_i) / (6 * M / (b * h**2)), rel=1e-12)
    assert factor == pytest.approx(1 + h / (3 * r), rel=0.2 * (h / r) ** 2)
    assert curved_beam_factor(math.inf, h) == 1.0


def test_continuum_fibre_stress_of_a_thick_arc_is_the_curved_beam_value():
    """Small pure moment on a thick arc (r/h = 4): away from the clamped faces the continuum's
    own fibre stress is Winkler-Bach's inner-fibre value, 9.0 % above the beam formula the
    section resultants give (exact elasticity, Golovin: 9.14 %, tests/test_stress_recovery.py).
    Measured (levels 0, 1, 2): 1.0857, 1.0920, 1.0915 times 6 M / (b h^2) against 1.0905;
    bound 0.2 % at level 2, and the differences shrink."""
    from flexval.validation.continuum.run import run_continuum
    from flexval.validation.report.strength import curved_beam_factor

    R, h, moment = 4.0, 1.0, 1e-3
    mech = cantilever(Arc((0.0, 0.0), R, math.radians(-60.0), math.radians(120.0)), E=E, b=1.0, h=h)
    straight = 6.0 * moment / (1.0 * h**2)
    ratios = []
    for level in (0, 1, 2):
        lp = run_continuum(mech, tip_moment(moment, levels=2), level=level)
        assert lp.peak_stress["f"][-1] == pytest.approx(straight, rel=1e-8)
        fibre = lp.fibre_stress["f"]
        assert fibre["layer"] == 2.0 * h and 0.1 < fibre["at"] < 0.9
        ratios.append(fibre["stress"] / straight)
    assert abs(ratios[2] - ratios[1]) < abs(ratios[1] - ratios[0])
    assert ratios[2] == pytest.approx(curved_beam_factor(R, h), rel=2e-3)


def test_a_quantity_converged_to_round_off_gets_no_observed_order():
    """Changes of 1e-8 of the value are the solver's tolerance: no order is computed from them."""
    from flexval.validation.studies.convergence import ROUND_OFF_CHANGE, order_text

    exact = richardson(3.0, 3.0 + 4.8e-8, 3.0 + 7.2e-8, 2.0)  # m+'s uniform peak stress
    assert exact["order"] is None and exact["extrapolated"] == 3.0 + 7.2e-8
    assert order_text(exact).startswith("n/a (converged to round-off")
    converging = richardson(14.715042, 14.718397, 14.719104, 2.0)  # m+ displacement, levels 0-2
    assert converging["order"] == pytest.approx(2.246, abs=1e-3)
    assert abs(14.719104 - 14.718397) > 10 * ROUND_OFF_CHANGE * 14.719104
    assert order_text(converging) == f"{converging['order']:.2f}"
    assert (
        order_text(richardson(1.0, 2.0, 1.5, 2.0))
        == "n/a (the changes do not shrink monotonically)"
    )


def test_the_report_and_the_cli_print_why_there_is_no_order(tmp_path):
    """Both printers of a convergence study say "converged to round-off" instead of an order."""
    from types import SimpleNamespace

    from flexval.validation.report.writer import _convergence_lines
    from flexval.validation.studies.convergence import ConvergenceStudy, format_study

    st = ConvergenceStudy("continuum", "m+", 2.0)
    st.summary = {
        "peak_stress": richardson(3.0, 3.0 + 4.8e-8, 3.0 + 7.2e-8, 2.0),
        "displacement": richardson(14.715042, 14.718397, 14.719104, 2.0),
    }
    res = SimpleNamespace(scene=SimpleNamespace(name="open_chain"), convergence=[st])
    report = "\n".join(_convergence_lines(res, tmp_path, draw=None))
    assert "peak_stress: observed order n/a (converged to round-off" in report
    assert "displacement: observed order 2.25," in report
    assert "peak_stress: observed order n/a (converged to round-off" in format_study(st)
