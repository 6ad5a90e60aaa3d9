"""``prbm`` of the new flexures: a notch hinge's one-pivot model against the Euler-Bernoulli
integrals by quad (any rotation under a moment, small loads under a force), its exact
derivatives, mass, stress and strain limit; a tapered arc's 3R chain against the tapered
ellipse (linear exactness); the refusal of a spline."""

import dataclasses
import math

import numpy as np
import pytest
from builders import fd_check
from scipy.integrate import quad
from test_varying_linear import (
    DEPTH,
    MATERIAL,
    NOTCHES,
    clamped,
    notch_rotational_compliance,
    response,
    tip_force,
    tip_moment,
)

from flexval.geometry import Arc, SceneError, Section, Segment
from flexval.geometry.compliance import SHEAR_CORRECTION
from flexval.geometry.profiles import LinearTaper
from flexval.geometry.shapes import Spline
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.validity import MAX_STRAIN
from flexval.reducedmodels.models import run_reduced
from flexval.reducedmodels.prbm.pivot import NotchPivotConnector


def notch(contour: str, angle: float = 0.0, origin=(0.0, 0.0)):
    """The notch clamped at its start, its axis at ``angle`` (rad)."""
    profile = NOTCHES[contour]
    start = np.asarray(origin, float)
    end = start + profile.length * np.array([math.cos(angle), math.sin(angle)])
    return clamped(Segment(tuple(start), tuple(end)), Section(DEPTH, profile.t, profile))


@pytest.mark.parametrize("contour", NOTCHES)
def test_pivot_turns_by_the_euler_bernoulli_integral_at_any_rotation(contour):
    """Under a pure moment the pivot's springs carry no force: rotation M c_theta exactly,
    small (1e-3 rad) or large (0.3 rad); measured within 7e-11 (circular) and 2e-15."""
    mech = notch(contour, angle=0.6, origin=(1.0, -2.0))
    c_theta = notch_rotational_compliance(NOTCHES[contour])
    for rotation in (1e-3, 0.3):
        lp = run_reduced(mech, parse_model("prbm[eb]"), tip_moment(rotation / c_theta, levels=3))
        assert lp.converged
        assert lp.rotation[-1] == pytest.approx(rotation, rel=1e-9)


def test_pivot_under_a_transverse_force_bends_about_its_centre():
    """A force F across the axis at the free end (lever l = L/2 from the pivot): the pivot
    gives F (l^2 ∫ ds/EI + ∫ ds/(k G A)), the classic model's compliance; the exact linear
    compliance (ee) adds the hinge's own w a^2 = ∫ (s - L/2)^2 / EI and has no shear."""
    profile = NOTCHES["circular"]
    mech = notch("circular")
    L, lever = profile.length, 0.5 * profile.length
    G = MATERIAL.shear_modulus

    def integral(f):
        return quad(f, 0.0, L, points=[lever], epsabs=0.0, epsrel=1e-12, limit=400)[0]

    def EI(s):
        return MATERIAL.youngs_modulus * DEPTH * float(profile.thickness(s)) ** 3 / 12.0

    w = integral(lambda s: 1.0 / EI(s))
    shear = integral(lambda s: 1.0 / (SHEAR_CORRECTION * G * DEPTH * float(profile.thickness(s))))
    spread = integral(lambda s: (s - lever) ** 2 / EI(s))
    force = 1e-6
    uy = response(mech, "prbm[eb]", tip_force(mech, 0.0, force, levels=2))[1]
    assert uy == pytest.approx(force * (lever * lever * w + shear), rel=1e-6)
    ee = response(mech, "ee[eb]", tip_force(mech, 0.0, force, levels=2))[1]
    assert ee == pytest.approx(force * (lever * lever * w + spread), rel=1e-6)
    # the axial spring: ∫ ds / EA
    ux = response(mech, "prbm[eb]", tip_force(mech, force, 0.0, levels=2))[0]
    axial = integral(
        lambda s: 1.0 / (MATERIAL.youngs_modulus * DEPTH * float(profile.thickness(s)))
    )
    assert ux == pytest.approx(force * axial, rel=1e-6)


@pytest.mark.parametrize("contour", NOTCHES)
@pytest.mark.parametrize("model", ["prbm", "dcmm:1", "dcmm:2", "dcmm:3"])
def test_calibrated_models_bend_as_the_hinge_under_a_moment(contour, model):
    """Under a pure moment every section carries M, so the hinge bends to the angle
    theta W(s) at s, W = ∫_0^s ds/EI over ∫_0^L ds/EI (by quad), and its end lies at
    ∫_0^L (cos, sin)(theta W(s)) ds: the calibrated pivot's end, and DCMM's of any number of
    sub-arcs, within 1e-8 of L at 0.1 and 0.4 rad (measured 2.5e-9 L at 0.4 rad on the deep
    circular notch: the trapezoidal moments of W), where the classic pivot and the paper's
    sub-arc (eb), turning about a centre, are off by up to 1e-2 L at 0.4 rad."""
    profile = NOTCHES[contour]
    mech = notch(contour)
    L = profile.length
    breaks = [b for b in profile.breakpoints if 0.0 < b < L]

    def inverse_cube(s):
        return 1.0 / float(profile.thickness(s)) ** 3

    total = quad(inverse_cube, 0.0, L, points=breaks, epsabs=0.0, epsrel=1e-13, limit=400)[0]

    def W(s):
        inside = [b for b in breaks if b < s]
        return quad(inverse_cube, 0.0, s, points=inside or None, epsrel=1e-13, limit=400)[0] / total

    c_theta = notch_rotational_compliance(profile)
    for rotation in (0.1, 0.4):
        lp = run_reduced(mech, parse_model(model), tip_moment(rotation / c_theta, levels=2))
        theta = lp.rotation[-1]
        x, y = (
            quad(lambda s, f=f, a=theta: f(a * W(s)), 0.0, L, points=breaks, epsrel=1e-12)[0]
            for f in (math.cos, math.sin)
        )
        assert lp.dx[-1] == pytest.approx(x - L, abs=1e-8 * L), rotation
        assert lp.dy[-1] == pytest.approx(y, abs=1e-8 * L), rotation


def test_pivot_gradient_and_hessian_match_differences():
    mech = notch("elliptical", angle=0.4, origin=(0.5, 0.2))
    connector = NotchPivotConnector(mech.flexures[0], mech)
    calibrated = NotchPivotConnector(
        mech.flexures[0],
        dataclasses.replace(mech, material=dataclasses.replace(MATERIAL, shear_flexible=True)),
    )
    assert connector.parting(0.3) == (0.0, 0.0, 0.0) and calibrated.parting(0.3)[0] > 0.0
    rng = np.random.default_rng(3)
    for _ in range(3):
        pose_a = np.concatenate([rng.normal(0.0, 0.01, 2), rng.normal(0.0, 0.3, 1)])
        end = mech.bodies["t"].reference
        pose_b = np.concatenate([end + rng.normal(0.0, 0.01, 2), rng.normal(0.0, 0.3, 1)])
        for pivot in (connector, calibrated):
            g_err, h_err, asym = fd_check(pivot, pose_a, pose_b, np.zeros(0))
            assert g_err < 1e-7 and h_err < 1e-7 and asym < 1e-14


def test_pivot_strain_limit_flags_rotations_beyond_it():
    """The limit is the rotation at which 6 M / (E b t^2) = MAX_STRAIN with M = rotation / w."""
    mech = notch("circular")
    connector = NotchPivotConnector(mech.flexures[0], mech)
    profile = NOTCHES["circular"]
    w = notch_rotational_compliance(profile)
    limit = MAX_STRAIN * MATERIAL.youngs_modulus * DEPTH * profile.t**2 / 6.0 * w
    assert connector.rotation_limit == pytest.approx(limit, rel=1e-12)
    lp = run_reduced(mech, parse_model("prbm[eb]"), tip_moment(1.2 * limit / w, levels=4))
    assert lp.valid == [True, True, True, False]
    assert "strain limit" in lp.validity[-1]
    # DCMM knows the same limit per sub-arc: dcmm:1 is the whole hinge
    lp = run_reduced(mech, parse_model("dcmm:1[eb]"), tip_moment(1.2 * limit / w, levels=4))
    assert lp.valid == [True, True, True, False]


def test_pivot_stress_peaks_at_the_thinnest_section_and_mass_is_the_integral():
    mech = notch("power")
    profile = NOTCHES["power"]
    moment = 1e-3
    lp = run_reduced(mech, parse_model("prbm"), tip_moment(moment, levels=2))
    assert lp.peak_stress["f"][-1] == pytest.approx(6.0 * moment / (DEPTH * profile.t**2))
    assert lp.peak_stress_at["f"][-1] == pytest.approx(0.5)
    density = 2.7e-9
    points = NotchPivotConnector(mech.flexures[0], mech).mass_points(density)
    area = quad(
        lambda s: DEPTH * float(profile.thickness(s)),
        0.0,
        profile.length,
        points=[1.0],
        epsrel=1e-13,
    )[0]
    assert points.mass.sum() == pytest.approx(density * area, rel=1e-12)
    np.testing.assert_allclose(points.mass, 0.5 * density * area, rtol=1e-12)  # symmetric


@pytest.mark.parametrize("model", ["prbm", "dcmm:1", "dcmm:3", "ee"])
@pytest.mark.parametrize("contour", NOTCHES)
def test_notch_stress_under_a_force_peaks_where_beam_statics_puts_it(contour, model):
    """A small force F across the hinge at its end: the moment F (L - s) grows towards the
    clamp while the section thickens, and the largest 6 M / (b h^2) lies off the waist
    (inside the fillet, on a corner-filleted hinge: its flat ends are stations). The peak
    and where it lies against that maximum found by scipy on the contour's h(s), for the
    PRBM's pivot and DCMM's sub-arcs (256 segments over a hinge): measured within 1.1e-4 in
    stress (the stations' spacing) and 1/256 of the length in place."""
    from scipy.optimize import minimize_scalar

    profile = NOTCHES[contour]
    mech = notch(contour)
    force, L = 1e-4, profile.length

    def stress(s: float) -> float:
        return 6.0 * force * (L - s) / (DEPTH * float(profile.thickness(s)) ** 2)

    grid = np.linspace(0.0, L, 2001)
    start = grid[np.argmax([stress(s) for s in grid])]
    best = minimize_scalar(
        lambda s: -stress(s),
        bounds=(max(0.0, start - L / 1000), min(L, start + L / 1000)),
        method="bounded",
        options={"xatol": 1e-12},
    )
    lp = run_reduced(mech, parse_model(model), tip_force(mech, 0.0, force, levels=2))
    assert len(lp.stress_profile["f"]["at"]) >= 257
    assert lp.peak_stress["f"][-1] == pytest.approx(-best.fun, rel=2e-4)
    assert lp.peak_stress_at["f"][-1] == pytest.approx(best.x / L, abs=1.0 / 256)
    assert lp.peak_stress_at["f"][-1] < 0.5  # off the waist, towards the clamp


def test_tapered_arc_chain_is_exact_in_the_linear_limit():
    """The 3R chain on the tapered ellipse: its small-load 3x3 tip compliance differs from
    ee's in proportion to the load (measured 6.5e-6, 6.5e-7 at loads 1e-6, 1e-7 N), i.e.
    only by the geometric nonlinearity: exact in the limit, like a uniform arc's chain
    (2.7e-5, 2.7e-6 on the same arc uniform)."""
    arc = Arc((0.0, 0.0), 8.0, math.radians(80.0), math.radians(140.0))
    mech = clamped(arc, Section(DEPTH, 0.2, LinearTaper(0.5, 0.2, arc.length)))
    gaps = []
    for load in (1e-6, 1e-7):
        matrices = []
        for model in ("ee", "prbm"):
            columns = [
                response(mech, model, tip_force(mech, load, 0.0, levels=2)),
                response(mech, model, tip_force(mech, 0.0, load, levels=2)),
                response(mech, model, tip_moment(load, levels=2)),
            ]
            matrices.append(np.array(columns).T / load)
        gaps.append(np.abs(matrices[1] - matrices[0]).max() / np.abs(matrices[0]).max())
    assert gaps[1] < 1e-5
    assert gaps[0] / gaps[1] == pytest.approx(10.0, rel=0.05)


def test_a_spline_has_no_prbm():
    spline = Spline(((0.0, 0.0), (3.0, 1.0), (6.0, 0.0)))
    mech = clamped(spline, Section(DEPTH, 0.2))
    with pytest.raises(SceneError) as info:
        run_reduced(mech, parse_model("prbm"), tip_moment(1e-3, levels=2))
    assert info.value.field == "flexures.f"
    assert "beam, dcmm or continuum" in str(info.value)


def test_a_closed_chain_of_notch_hinges_and_a_pin():
    """Two levers on notch hinges, pinned to each other (pins scale by ∫ ds / EI where the
    section varies): dcmm:3 and ee agree at a small load (both exact in the linear
    limit; measured 5e-8 apart), and the pivot model runs the chain. The two pivots and
    the pin form a triangle, a rigid truss: only the pivots' elastic translations and
    the hinges' bending about their centres let body a turn, so the pivot model, which
    leaves out the hinges' transverse bending compliance w a^2, is stiffer (measured
    1.5e-8 rad against ee's 7.5e-8) by plain Euler-Bernoulli (``[eb]``)."""
    from flexval.geometry import LoadCase, Material, Moment
    from flexval.geometry.mechanism import FlexureSpec, PinSpec, assemble

    profile = NOTCHES["circular"]
    section = Section(DEPTH, profile.t, profile)
    specs = [
        FlexureSpec("left", Segment((0.0, 0.0), (0.0, 2.0)), ("g", "a"), section, "g"),
        FlexureSpec("right", Segment((10.0, 0.0), (10.0, 2.0)), ("g", "b"), section, "g"),
    ]
    mech = assemble(
        specs,
        "g",
        np.array([[0.0, 0.0], [10.0, 0.0]]),
        Material(MATERIAL.youngs_modulus, MATERIAL.poisson_ratio),
        "a",
        np.array([0.0, 2.0]),
        body_points={"a": np.array([[0.0, 2.0], [5.0, 8.0]]), "b": np.array([[10.0, 2.0]])},
        pin_specs=[PinSpec("p", ("a", "b"), (5.0, 8.0))],
    )
    case = LoadCase("M", (Moment("a", 1e-4),), 2)
    ee = run_reduced(mech, parse_model("ee[eb]"), case)
    dcmm = run_reduced(mech, parse_model("dcmm:3[eb]"), case)
    prbm = run_reduced(mech, parse_model("prbm[eb]"), case)
    assert dcmm.rotation[-1] == pytest.approx(ee.rotation[-1], rel=1e-4)
    assert prbm.converged and 0.0 < prbm.rotation[-1] <= ee.rotation[-1] * (1 + 1e-6)
    # calibrated (the default), the pivot takes the hinge's w a^2 and its linear compliance
    # is the hinge's: the three agree
    ee, dcmm, prbm = (run_reduced(mech, parse_model(m), case) for m in ("ee", "dcmm:3", "prbm"))
    assert dcmm.rotation[-1] == pytest.approx(ee.rotation[-1], rel=1e-4)
    assert prbm.rotation[-1] == pytest.approx(ee.rotation[-1], rel=1e-4)
