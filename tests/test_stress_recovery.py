"""The continuum's recovered stress against exact plane elasticity, and its convergence.

References: Golovin's curved bar in pure bending, derived here from an Airy
stress function (phi = A ln r + B r^2 ln r + C r^2) with its boundary
conditions solved numerically, checked against Timoshenko's closed form,
equilibrium and compatibility; the patch recovery's reproduction of the
polynomials it fits; the geometry of the fibres of an arc mesh.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import cantilever, tip_moment
from scipy.integrate import quad

from flexval.geometry import Arc, Segment

pytestmark = pytest.mark.usefixtures("private_mesh_cache")


def _airy_stresses(r, A: float, B: float, C: float) -> tuple[np.ndarray, np.ndarray]:
    """sigma_r and sigma_theta (MPa) of phi = A ln r + B r^2 ln r + C r^2 (r in mm)."""
    r = np.asarray(r, float)
    radial = A / r**2 + B * (1.0 + 2.0 * np.log(r)) + 2.0 * C
    hoop = -A / r**2 + B * (3.0 + 2.0 * np.log(r)) + 2.0 * C
    return radial, hoop


def curved_bar_hoop(a: float, b: float, moment: float):
    """sigma_theta(r) (MPa) of a curved bar of radii a < b (mm) under end moments (N mm per
    mm of depth): free faces sigma_r(a) = sigma_r(b) = 0 and int sigma_theta r dr = -M,
    solved for the Airy coefficients by quadrature."""

    def conditions(coef):
        return [
            _airy_stresses(a, *coef)[0],
            _airy_stresses(b, *coef)[0],
            quad(lambda r: _airy_stresses(r, *coef)[1] * r, a, b, epsabs=1e-14)[0],
        ]

    matrix = np.array([conditions(e) for e in np.eye(3)]).T  # linear in the coefficients
    coef = np.linalg.solve(matrix, [0.0, 0.0, -moment])
    return (lambda r: _airy_stresses(r, *coef)[1]), (lambda r: _airy_stresses(r, *coef)[0])


def timoshenko_hoop(a: float, b: float, moment: float, r: float) -> float:
    """Timoshenko's closed form of the same sigma_theta(r), MPa."""
    n = (b * b - a * a) ** 2 - 4.0 * a * a * b * b * math.log(b / a) ** 2
    return -(4.0 * moment / n) * (
        -a * a * b * b / r**2 * math.log(b / a)
        + b * b * math.log(r / b)
        + a * a * math.log(a / r)
        + b * b
        - a * a
    )


@pytest.mark.parametrize("r_over_h", [4.0, 10.0, 30.0])
def test_the_curved_bar_solution_is_exact_plane_elasticity(r_over_h):
    """The Airy solution meets the free faces, carries the moment and no net force, is in
    equilibrium (d sigma_r/dr + (sigma_r - sigma_theta)/r = 0) and compatible (sigma_r +
    sigma_theta harmonic: the same condition in plane stress and plane strain, so the
    stresses hold for both); it is Timoshenko's closed form, and tends to the beam formula
    with Winkler-Bach's 1 + h/(3 r) at the inner fibre (measured: exact - (1 + h/(3 r)) =
    0.12 (h/r)^2 at r/h = 10 and 30)."""
    h, moment = 1.0, 1.0
    a, b = r_over_h * h - h / 2, r_over_h * h + h / 2
    hoop, radial = curved_bar_hoop(a, b, moment)
    scale = 6.0 * moment / h**2
    assert abs(radial(a)) < 1e-12 * scale and abs(radial(b)) < 1e-12 * scale
    assert abs(quad(hoop, a, b, epsabs=1e-12)[0]) < 1e-10 * scale * h
    r = np.linspace(a, b, 7)
    np.testing.assert_allclose(
        hoop(r), [timoshenko_hoop(a, b, moment, x) for x in r], rtol=1e-9, atol=1e-9 * scale
    )
    d = 1e-4 * h
    equilibrium = (radial(r + d) - radial(r - d)) / (2 * d) + (radial(r) - hoop(r)) / r
    assert np.max(np.abs(equilibrium)) < 1e-6 * scale / h
    trace = lambda x: radial(x) + hoop(x)  # noqa: E731
    laplacian = (trace(r + d) - 2 * trace(r) + trace(r - d)) / d**2 + (
        trace(r + d) - trace(r - d)
    ) / (2 * d * r)
    assert np.max(np.abs(laplacian)) < 1e-4 * scale / h**2
    factor = abs(hoop(a)) / scale
    assert factor == pytest.approx(1 + h / (3 * r_over_h * h), rel=0.2 * (1 / r_over_h) ** 2)


def test_continuum_inner_fibre_stress_of_a_curved_bar_is_golovins():
    """A 90 deg bar of r/h = 10 under a small end moment: away from the clamped faces the
    recovered fibre stress is the exact inner-fibre stress, 3.455 % above M h/(2I).
    Measured (levels 0, 1, 2): 3.352, 3.462, 3.456 % above it, errors -0.099, +0.0076,
    +0.0012 % of the exact value (ratios 13 and 6); bound 0.2 % at every level, each
    error at most a third of the level's below."""
    from flexval.validation.continuum.run import run_continuum

    R, h, moment = 10.0, 1.0, 1e-3
    mech = cantilever(Arc((0.0, 0.0), R, math.radians(-45.0), math.radians(90.0)), E=2100.0, h=h)
    hoop, _ = curved_bar_hoop(R - h / 2, R + h / 2, moment)
    exact = abs(hoop(R - h / 2))
    assert exact / (6.0 * moment / h**2) - 1.0 == pytest.approx(0.034546, abs=1e-6)
    errors = []
    for level in (0, 1, 2):
        lp = run_continuum(mech, tip_moment(moment, levels=2), level=level)
        fibre = lp.fibre_stress["f"]
        assert 0.1 < fibre["at"] < 0.9
        errors.append(fibre["stress"] / exact - 1.0)
    assert max(abs(e) for e in errors) < 2e-3
    assert abs(errors[1]) < abs(errors[0]) / 3 and abs(errors[2]) < abs(errors[1]) / 3


def _straight_connector(level: int):
    from flexval.validation.continuum.connector import ContinuumConnector

    mech = cantilever(Segment((0.0, 0.0), (3.0, 0.0)), h=0.5)
    return ContinuumConnector(mech.flexures[0], mech, level)


@pytest.mark.parametrize("level", [0, 1, 2])
def test_patch_recovery_reproduces_the_polynomials_it_fits(level):
    """Sampled at the Barlow points, a biquadratic in the mesh's logical coordinates (linear
    across with one element across, level 0) comes back exactly at every node, boundary
    nodes included; a cubic does not (the test can fail)."""
    rec = _straight_connector(level).recovery
    across_degree = 1 if level == 0 else 2

    def field(k, m, cubic=0.0):
        u, v = 0.3 * k, 0.7 * m
        out = 1.5 - 0.4 * u + 0.2 * u * u + cubic * u**3
        return out + v * (0.8 - 0.1 * u + 0.05 * u * u) + (across_degree == 2) * v * v * (0.3 + u)

    exact = field(rec.node_along, rec.node_across)
    recovered = rec.recover(field(rec.along, rec.across))
    np.testing.assert_allclose(recovered, exact, rtol=0, atol=1e-10 * np.abs(exact).max())
    wrong = rec.recover(field(rec.along, rec.across, cubic=0.01))
    assert np.abs(wrong - field(rec.node_along, rec.node_across, cubic=0.01)).max() > 1e-4


def test_fibres_of_an_arc_mesh_are_its_circles():
    """On an arc the fibres are the concentric circles: tangent normal to the radius, length
    per logical unit r times the angle per logical unit (isoparametric geometry: to 1e-6)."""
    from flexval.validation.continuum.connector import ContinuumConnector

    arc = Arc((1.0, -2.0), 5.0, math.radians(30.0), math.radians(100.0))
    mech = cantilever(arc, h=0.5)
    conn = ContinuumConnector(mech.flexures[0], mech, 1)
    rec = conn.recovery
    X = np.asarray(rec.basis.global_coordinates()).transpose(1, 2, 0)  # Barlow points
    radius = X - np.asarray(arc.center)
    r = np.hypot(radius[..., 0], radius[..., 1])
    assert np.abs(np.einsum("eqj,eqj->eq", rec.fibre, radius) / r).max() < 1e-6
    per_unit = arc.width / (2 * conn.mesh.n_l)
    np.testing.assert_allclose(rec.fibre_length, r * per_unit, rtol=1e-6)


def test_fibre_stress_is_a_converged_quantity_of_the_convergence_study(tmp_path):
    """The study analyses the continuum's fibre stress like the displacement: on the r/h = 10
    bar (levels 1, 2, 3) its observed order is about 2 (measured 2.14), its Richardson
    value is the exact stress (measured -0.0006 %) and its GCI 0.0005 %; the CLI's table, the
    report's convergence table and the fibre-stress table print it with its order and GCI."""
    from types import SimpleNamespace

    from flexval.reducedmodels.catalogue import parse_model
    from flexval.validation.continuum.run import run_continuum
    from flexval.validation.report.strength import fibre_table
    from flexval.validation.report.writer import _convergence_lines
    from flexval.validation.studies.convergence import format_study, study

    R, h, moment = 10.0, 1.0, 1e-3
    mech = cantilever(Arc((0.0, 0.0), R, math.radians(-45.0), math.radians(90.0)), E=2100.0, h=h)
    case = tip_moment(moment, levels=2)
    paths = {}

    def run(spec):
        paths[spec.id] = run_continuum(mech, case, level=spec.resolution, model=spec.id)
        return paths[spec.id]

    st = study(None, parse_model("continuum:1"), [1, 2, 3], case, run=run)
    assert [r["fibre_stress"] for r in st.rows] == [
        paths[f"continuum:{n}"].fibre_stress["f"]["stress"] for n in (1, 2, 3)
    ]
    summary = st.summary["fibre_stress"]
    hoop, _ = curved_bar_hoop(R - h / 2, R + h / 2, moment)
    assert 1.5 < summary["order"] < 3.5
    assert summary["extrapolated"] == pytest.approx(abs(hoop(R - h / 2)), rel=5e-5)
    assert 0 < summary["gci_percent"] < 0.01
    text = format_study(st)
    assert "fibre MPa" in text and "fibre_stress: observed order" in text
    res = SimpleNamespace(scene=SimpleNamespace(name="bar"), convergence=[st])
    lines = "\n".join(_convergence_lines(res, tmp_path, lambda *args: None))
    assert "fibre stress (MPa) |" in lines and "\nfibre_stress: observed order" in lines
    scene = SimpleNamespace(mechanism=mech)
    table = fibre_table(
        scene, {("continuum:1", "M"): paths["continuum:1"]}, "continuum:1", ["M"], [st]
    )
    assert table[-2].startswith("Mesh convergence of the continuum's fibre stress on M")
    assert f"observed order {summary['order']:.2f}" in table[-2]
