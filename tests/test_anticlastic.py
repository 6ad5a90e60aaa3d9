"""The width effect: the anticlastic stiffness ratio and the reduced models' option ``width``.

References: the two limits (narrow beam E I, plate E I / (1 - nu^2)) and the first
term of a narrow strip's excess, nu^2 beta^2 / 60, from the energy of the foundation
under the free strip's curl (derived in the test's docstring, not from the closed form);
an independent numerical solution of the strip's equation (scipy's solve_bvp, with the
moment and the energy integrated over the depth); a linear model's compliance divided by
the ratio exactly; and the option bracketed by the plain model and ``plate``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from builders import cantilever, tip_force, tip_moment
from scipy.integrate import quad, simpson, solve_bvp

from flexval.geometry import Arc, SceneError, Section, Segment, load_scene
from flexval.geometry.anticlastic import (
    SERIES_LIMIT,
    edge_parameter,
    effective_material,
    flexure_ratio,
    flexure_searle,
    searle_parameter,
    searle_parameters,
    stiffness_ratio,
)
from flexval.geometry.clampedleaf import clamped_leaf_ratio
from flexval.geometry.profiles import LinearTaper
from flexval.reducedmodels import parse_model
from flexval.reducedmodels.models import run_reduced

NU = 0.35


def solve_strip(depth: float, thickness: float, E: float, nu: float, foundation: float, kappa):
    """A strip's moment and energy per unit length across its depth, by solve_bvp.

    The strip of depth b and thickness h (mm) bent by a curvature kappa (1/mm); u(z) the
    normal displacement of its mid-surface across the depth, resisted by the fibres'
    stretching, a foundation of modulus ``foundation`` (MPa/mm):
    D u'''' + foundation u = 0, with u'' = nu kappa and u''' = 0 at the free faces,
    solved on the half depth [0, b/2] (u even: u' = u''' = 0 at z = 0). Returns the
    bending moment ∫ D (kappa - nu u'') dz (N mm) and the energy
    ∫ [D (kappa^2 - 2 nu kappa u'' + u''^2) + foundation u^2] / 2 dz (N), both by
    Simpson's rule over the solution.
    """
    D = E * thickness**3 / (12.0 * (1.0 - nu * nu))
    half = depth / 2.0

    def rhs(z, y):
        return np.vstack([y[1], y[2], y[3], -foundation / D * y[0]])

    def rhs_jac(z, y):
        jac = np.zeros((4, 4, z.size))
        jac[0, 1] = jac[1, 2] = jac[2, 3] = 1.0
        jac[3, 0] = -foundation / D
        return jac

    def bc(y0, y1):
        return np.array([y0[1], y0[3], y1[2] - nu * kappa, y1[3]])

    def bc_jac(y0, y1):
        at0, at1 = np.zeros((4, 4)), np.zeros((4, 4))
        at0[0, 1] = at0[1, 3] = at1[2, 2] = at1[3, 3] = 1.0
        return at0, at1

    z = np.linspace(0.0, half, 201)
    sol = solve_bvp(
        rhs,
        bc,
        z,
        np.zeros((4, z.size)),
        fun_jac=rhs_jac,
        bc_jac=bc_jac,
        tol=1e-8,
        max_nodes=200_000,
    )
    assert sol.success, sol.message
    fine = np.linspace(0.0, half, 40_001)
    u, _, u2, _ = sol.sol(fine)
    moment = 2.0 * simpson(D * (kappa - nu * u2), x=fine)  # both halves
    energy = simpson(D * (kappa**2 - 2 * nu * kappa * u2 + u2**2) + foundation * u**2, x=fine)
    return moment, energy


def strip_by_bvp(depth: float, thickness: float, radius: float, E: float, nu: float):
    """(moment ratio, energy ratio) of a strip of radius R (mm), without the closed form.

    The linear theory: a curvature change kappa = 1/mm stretches the fibre at u by
    u / R, a foundation E h / R^2 (:func:`solve_strip`); the moment over E I kappa and
    the energy over E I kappa^2 / 2.
    """
    moment, energy = solve_strip(depth, thickness, E, nu, E * thickness / radius**2, 1.0)
    EI = E * depth * thickness**3 / 12.0
    return moment / EI, energy / (EI / 2.0)


def straight_strip_energy(depth: float, thickness: float, E: float, nu: float, kappa: float):
    """Energy per unit length (N) of a straight strip bent to curvature kappa (1/mm).

    Ashwell's problem: the fibre at u from the mid-surface stretches by kappa u, a
    foundation E h kappa^2 (:func:`solve_strip`).
    """
    return solve_strip(depth, thickness, E, nu, E * thickness * kappa**2, kappa)[1]


def test_the_limits_are_the_narrow_beam_and_the_plate():
    for nu in (0.0, 0.2, NU, 0.5):
        assert stiffness_ratio(0.0, nu) == 1.0
        # far beyond the layers: q(phi) -> 2 / phi, to exp(-phi)
        beta = 1e4
        phi = float(edge_parameter(beta, nu))
        expected = (1.0 - nu * nu * 2.0 / phi) / (1.0 - nu * nu)
        assert stiffness_ratio(beta, nu) == pytest.approx(expected, rel=1e-14)
    assert stiffness_ratio(1e300, NU) == pytest.approx(1.0 / (1.0 - NU * NU), rel=1e-14)


@pytest.mark.parametrize("nu", [0.2, NU, 0.5])
def test_a_narrow_strip_stiffens_by_nu_squared_beta_squared_over_60(nu):
    """First-order perturbation in the foundation modulus k = E h / R^2: the narrow strip
    curls freely, u0 = nu kappa (z^2 / 2 - b^2 / 24) (its mean removed: the free membrane
    strain), and the foundation stores k ∫ u0^2 dz / 2 = k nu^2 kappa^2 b^5 / 1440, which
    over E I kappa^2 / 2 is nu^2 beta^2 / 60. The next term is of order beta^4."""
    for beta in (1e-3, 1e-2):
        excess = float(stiffness_ratio(beta, nu)) - 1.0
        assert excess == pytest.approx(nu * nu * beta * beta / 60.0, rel=beta**2)


@pytest.mark.parametrize("nu", [0.1, NU, 0.5])
def test_the_ratio_grows_monotonically_with_beta(nu):
    beta = np.concatenate([np.geomspace(1e-4, 1e4, 4001), [0.0]])
    beta.sort()
    ratio = stiffness_ratio(beta, nu)
    assert np.all(np.diff(ratio) > 0.0)
    assert ratio[0] == 1.0 and ratio[-1] < 1.0 / (1.0 - nu * nu)
    # either side of the switch from the series, the textbook form (no cancellation there)
    phi = SERIES_LIMIT * (1.0 + np.array([-1e-9, 0.0, 1e-9]))
    at = stiffness_ratio((phi / (3.0 * (1.0 - nu * nu)) ** 0.25) ** 2, nu)
    q = (2.0 / phi) * (np.cosh(phi) - np.cos(phi)) / (np.sinh(phi) + np.sin(phi))
    np.testing.assert_allclose(at, (1.0 - nu * nu * q) / (1.0 - nu * nu), rtol=1e-15)


BVP_AGREEMENT = 1e-10
"""Relative: the closed form against solve_bvp at tolerance 1e-8 (the bound of its
collocation residual); measured within 1.4e-12 for beta from 0.1 to 100 and nu up to 0.49."""


@pytest.mark.parametrize("beta", [0.1, 1.0, 3.0, 10.0, 100.0])
@pytest.mark.parametrize("nu", [0.0, NU, 0.49])
def test_the_closed_form_meets_the_strips_numerical_solution(beta, nu):
    depth, thickness = 1.0, 0.1
    radius = depth**2 / (beta * thickness)
    by_moment, by_energy = strip_by_bvp(depth, thickness, radius, 2100.0, nu)
    expected = float(stiffness_ratio(searle_parameter(depth, thickness, radius), nu))
    assert by_moment == pytest.approx(expected, rel=BVP_AGREEMENT)
    assert by_energy == pytest.approx(expected, rel=BVP_AGREEMENT)


def test_a_straight_strip_bent_to_radius_r_stores_the_same_energy():
    """Ashwell's nonlinear case: the energy at curvature kappa is E I r(beta) kappa^2 / 2
    with beta = b^2 kappa / h, so the moment dU/dkappa (by central differences of the
    numerical energies) is E I kappa (r + beta r'(beta) / 2), above the secant."""
    depth, thickness, E = 1.0, 0.1, 2100.0
    EI = E * depth * thickness**3 / 12.0
    for beta in (1.0, 3.0, 10.0):
        kappa = beta * thickness / depth**2
        energy = straight_strip_energy(depth, thickness, E, NU, kappa)
        ratio = float(stiffness_ratio(beta, NU))
        assert energy / (EI * kappa**2 / 2.0) == pytest.approx(ratio, rel=BVP_AGREEMENT)
        step = 1e-4
        up, down = (
            straight_strip_energy(depth, thickness, E, NU, kappa * (1 + s)) for s in (step, -step)
        )
        moment = (up - down) / (2.0 * step * kappa)
        change = stiffness_ratio(beta * (1 + step), NU) - stiffness_ratio(beta * (1 - step), NU)
        slope = float(change) / (2.0 * step * beta)  # dr/dbeta
        tangent = ratio + beta * slope / 2.0
        assert moment / (EI * kappa) == pytest.approx(tangent, rel=1e-7)
        assert tangent > ratio


def test_only_beta_and_nu_matter():
    """Two strips of different size, thickness and modulus with one beta: one ratio from
    the numerical solution, the closed form's; a strip scaled as a whole keeps its beta."""
    beta = 3.0
    a = strip_by_bvp(1.0, 0.1, 1.0 / (beta * 0.1), 2100.0, NU)
    b = strip_by_bvp(7.0, 0.02, 49.0 / (beta * 0.02), 7e4, NU)
    assert a == pytest.approx(b, rel=BVP_AGREEMENT)
    assert searle_parameter(3.0, 0.3, 20.0) == pytest.approx(searle_parameter(1.0, 0.1, 20 / 3))
    assert searle_parameter(1.0, 0.1, math.inf) == 0.0


def test_vectorised_with_broadcasting():
    beta = np.array([[0.5, 3.0, 40.0]])
    nu = np.array([[0.2], [0.35]])
    out = stiffness_ratio(beta, nu)
    assert out.shape == (2, 3)
    for i in range(2):
        for j in range(3):
            assert out[i, j] == stiffness_ratio(beta[0, j], nu[i, 0])


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="Searle"):
        stiffness_ratio(-1.0, NU)
    with pytest.raises(ValueError, match="Searle"):
        stiffness_ratio(np.nan, NU)
    with pytest.raises(ValueError, match="Poisson"):
        stiffness_ratio(1.0, 0.6)


def test_open_chain_flexures_take_their_own_ratio():
    scene = load_scene("open_chain")
    mech = scene.mechanism
    nu = mech.material.poisson_ratio
    for f in mech.flexures:
        beta = searle_parameter(f.section.depth, f.section.thickness, f.shape.radius)
        assert 2.0 < beta < 5.0  # the paper's arcs: R = 25-35 h, b = 10 h
        ratio = flexure_ratio(f, nu)
        assert ratio == stiffness_ratio(beta, nu)
        assert searle_parameters(mech)[f.name] == beta
        assert 1.0 < ratio < 1.0 / (1.0 - nu * nu)


def test_a_straight_uniform_flexure_has_no_searle_parameter():
    f = cantilever(Segment((0.0, 0.0), (10.0, 0.0)), b=5.0, h=0.1).flexures[0]
    assert flexure_searle(f) == 0.0


def test_a_varying_flexure_keeps_its_rotational_compliance():
    """A tapered arc: 1 / r_mean against scipy's quad of ∫ ds / (r(s) h^3) / ∫ ds / h^3."""
    arc = Arc((0.0, 0.0), 3.0, 0.4, math.radians(200))
    taper = LinearTaper(0.2, 0.05, arc.length)
    f = cantilever(arc, b=1.0, h=0.05).flexures[0]
    f = dataclasses.replace(f, section=Section(1.0, 0.05, taper))

    def r(s: float) -> float:
        return float(stiffness_ratio(1.0 / (arc.radius * taper.thickness(s)), NU))

    top = quad(lambda s: 1.0 / (r(s) * taper.thickness(s) ** 3), 0.0, arc.length, epsabs=0)[0]
    bottom = quad(lambda s: 1.0 / taper.thickness(s) ** 3, 0.0, arc.length, epsabs=0)[0]
    assert flexure_ratio(f, NU) == pytest.approx(bottom / top, rel=1e-12)
    beta = quad(lambda s: 1.0 / (arc.radius * taper.thickness(s) ** 4), 0.0, arc.length)[0]
    assert flexure_searle(f) == pytest.approx(beta / bottom, rel=1e-12)
    # the thin end weighs most
    assert flexure_ratio(f, NU) > 0.5 * (r(0.0) + r(arc.length))


@pytest.mark.parametrize("scene", ["tapered_leaf", "notch_fourbar", "spline_flexure"])
def test_the_built_in_varying_flexures_have_a_ratio(scene):
    mech = load_scene(scene).mechanism
    nu = mech.material.poisson_ratio
    for f in mech.flexures:
        ratio = flexure_ratio(f, nu)
        straight = not np.any(f.shape.curvature_at(np.linspace(0.0, f.shape.length, 9)))
        if straight:
            assert ratio == 1.0 and flexure_searle(f) == 0.0
        else:
            assert 1.0 < ratio < 1.0 / (1.0 - nu * nu)


def test_the_effective_material_keeps_the_shear_modulus():
    m = load_scene("open_chain").mechanism.material
    assert effective_material(m, 1.0) is m
    stiffer = effective_material(m, 1.05)
    assert stiffer.youngs_modulus == pytest.approx(1.05 * m.youngs_modulus, rel=1e-15)
    assert stiffer.shear_modulus == pytest.approx(m.shear_modulus, rel=1e-14)
    nu = m.poisson_ratio
    plate, wide = effective_material(m, 1.0 / (1.0 - nu * nu)), m.plane_strain()
    assert plate.youngs_modulus == pytest.approx(wide.youngs_modulus, rel=1e-15)
    assert plate.poisson_ratio == pytest.approx(wide.poisson_ratio, rel=1e-14)


# ---- the reduced models' option


def arc_cantilever(depth: float = 1.0):
    return cantilever(Arc((0.0, 0.0), 3.0, 0.4, math.radians(240)), b=depth, h=0.1, nu=NU)


def test_a_linear_models_compliance_is_divided_by_the_ratio():
    mech = arc_cantilever()
    ratio = flexure_ratio(mech.flexures[0], NU)
    assert ratio > 1.01
    for case in (tip_force(mech, 0.01, -0.02), tip_moment(0.005)):
        plain = run_reduced(mech, parse_model("ee"), case)
        deep = run_reduced(mech, parse_model("ee[width]"), case)
        for key in ("dx", "dy", "rotation"):
            np.testing.assert_allclose(
                getattr(deep, key), np.asarray(getattr(plain, key)) / ratio, rtol=1e-12, atol=0
            )


@pytest.mark.parametrize("model", ["beam:20", "beam:10[shear]", "dcmm:2", "prbm", "ee"])
def test_the_option_is_the_model_with_the_flexures_own_material(model):
    mech = arc_cantilever()
    own = effective_material(mech.material, flexure_ratio(mech.flexures[0], NU))
    deep = dataclasses.replace(mech, material=own)
    case = tip_force(mech, 0.01, -0.02, levels=3)
    with_option = parse_model(f"{model[:-1]},width]" if model.endswith("]") else f"{model}[width]")
    a, b = run_reduced(mech, with_option, case), run_reduced(deep, parse_model(model), case)
    assert a.dx == b.dx and a.dy == b.dy and a.rotation == b.rotation


def test_a_shallow_depth_gives_the_plain_model_and_a_deep_one_the_plate():
    case = tip_moment(0.005)
    shallow = arc_cantilever(depth=1e-4)  # beta ~ 3e-8
    plain = run_reduced(shallow, parse_model("ee"), case)
    option = run_reduced(shallow, parse_model("ee[width]"), case)
    np.testing.assert_allclose(option.rotation, plain.rotation, rtol=4e-16, atol=0)
    deep = arc_cantilever(depth=1e4)  # beta ~ 3e8
    ratio = flexure_ratio(deep.flexures[0], NU)
    plate = run_reduced(deep, parse_model("ee[plate]"), case)
    option = run_reduced(deep, parse_model("ee[width]"), case)
    np.testing.assert_allclose(
        option.rotation, np.asarray(plate.rotation) / (ratio * (1 - NU * NU)), rtol=1e-12
    )
    assert ratio * (1 - NU * NU) == pytest.approx(1.0, abs=1e-4)


def test_a_straight_leaf_takes_its_clamps_plate_stiffening():
    # the strip theory leaves a straight leaf at r = 1; its clamps hold the end faces flat,
    # so the ratio runs from the narrow beam (b/L -> 0) to the plate (b/L -> inf), rising
    mech = cantilever(Segment((0.0, 0.0), (10.0, 0.0)), b=5.0, h=0.1, nu=NU)
    assert flexure_ratio(mech.flexures[0], NU) == clamped_leaf_ratio(5.0, 10.0, NU)
    # narrow: r - 1 in proportion to b/L (the clamps' boundary layers, c b long)
    narrow = clamped_leaf_ratio(1e-3, 10.0, NU) - 1
    assert 0 < narrow < 1e-4
    assert clamped_leaf_ratio(1e-2, 10.0, NU) - 1 == pytest.approx(10 * narrow, rel=1e-2)
    assert clamped_leaf_ratio(1e5, 10.0, NU) == pytest.approx(1 / (1 - NU * NU), rel=1e-9)
    ratios = [clamped_leaf_ratio(b, 10.0, NU) for b in (0.1, 1.0, 5.0, 20.0, 100.0)]
    assert all(
        a < b for a, b in zip(ratios[:3], ratios[1:3])
    )  # the plate from b / L = 1 / (2 c ln 2)
    assert ratios[-1] == ratios[-2] == pytest.approx(1 / (1 - NU * NU), rel=1e-12)
    with pytest.raises(ValueError, match="positive"):
        clamped_leaf_ratio(0.0, 10.0, NU)


PURE_MOMENT_BEAM = 1e-6
"""Relative: beam:100's rotation ratio under a pure moment against the closed form
(measured 1e-7: the elements' axial stretch, which the option stiffens too; 2.4e-6 at
beam:20)."""


@pytest.mark.parametrize("model", ["ee", "dcmm:3", "prbm", "beam:100"])
def test_each_flexure_takes_its_own_ratio_under_a_pure_moment(model):
    """A moment M on the open chain's last link bends every arc by M / (E r I) whatever the
    deflection, so the rotation is M sum(L / r) / (E I): with the option it is the plain
    model's times sum(L / r) / sum(L), the arcs' ratios differing (R = 2.5 to 3.5 mm)."""
    scene = load_scene("open_chain")
    mech = scene.mechanism
    nu = mech.material.poisson_ratio
    length = np.array([f.shape.length for f in mech.flexures])
    ratio = np.array([flexure_ratio(f, nu) for f in mech.flexures])
    expected = (length / ratio).sum() / length.sum()
    tolerance = PURE_MOMENT_BEAM if model.startswith("beam") else 1e-10
    case = scene.load_case("m-")
    plain = run_reduced(mech, parse_model(model), case)
    deep = run_reduced(mech, parse_model(f"{model}[width]"), case)
    np.testing.assert_allclose(
        np.asarray(deep.rotation[1:]) / np.asarray(plain.rotation[1:]), expected, rtol=tolerance
    )


def test_beam_with_the_option_lies_between_the_narrow_beam_and_the_plate():
    scene = load_scene("open_chain")
    case = scene.load_case("m+")
    rot = {
        m: abs(run_reduced(scene.mechanism, parse_model(m), case).rotation[-1])
        for m in ("beam:100", "beam:100[width]", "beam:100[plate]")
    }
    assert rot["beam:100[plate]"] < rot["beam:100[width]"] < rot["beam:100"]


@pytest.mark.parametrize(
    "text, canonical",
    [
        ("beam:100[width]", "beam:100[width]"),
        ("beam:100[shear, width=true]", "beam:100[shear,width]"),
        ("dcmm:2[width,frame=follower]", "dcmm:2[frame=follower,width]"),
        ("prbm[width]", "prbm[width]"),
        ("ee[width=false]", "ee"),
    ],
)
def test_the_option_id_round_trips(text, canonical):
    spec = parse_model(text)
    assert spec.id == canonical
    assert parse_model(spec.id) == spec
    assert spec.kwargs.get("width", False) == ("width" in canonical)


@pytest.mark.parametrize("model", ["ee[plate,width]", "beam:10[width,plate]"])
def test_the_option_excludes_plate(model):
    with pytest.raises(SceneError) as err:
        parse_model(model)  # refused with the id, before any work
    assert err.value.field == "model"
    assert "option 'plate'" in str(err.value) and "means nothing with 'width'" in str(err.value)
