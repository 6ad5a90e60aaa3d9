"""Natural frequencies against closed forms (flexval.reducedmodels.analyses.modes,
flexval.reducedmodels.core.inertia)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from flexval.geometry import Arc, MassData, RigidMass, SceneError, Segment
from flexval.reducedmodels.analyses.modes import natural_modes, sparse_modes, sparse_tangent
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.inertia import MassModel
from flexval.reducedmodels.models import build_system
from tests.builders import cantilever, tip_force

L, B, H, E, NU, RHO = 10.0, 1.0, 0.1, 2100.0, 0.3, 1.24e-9
EI, MU = E * B * H**3 / 12.0, RHO * B * H
BETA_L = (1.8751040687, 4.6940911330)  # clamped-free Euler-Bernoulli roots
ARC = Arc((0.0, 3.0), 3.0, math.radians(150.0), math.radians(240.0))


def straight(**inertia) -> object:
    """A straight cantilever of PLA-like density; ``inertia``: MassData fields."""
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), E=E, b=B, h=H, nu=NU)
    return dataclasses.replace(mech, inertia=MassData(**inertia))


def beam_theory(beta_l) -> np.ndarray:
    """Euler-Bernoulli frequencies (Hz) of the clamped-free beam for roots beta L."""
    return np.asarray(beta_l) ** 2 / L**2 * math.sqrt(EI / MU) / (2.0 * math.pi)


@pytest.mark.parametrize("n", [10, 20, 40])
def test_beam_cantilever_converges_to_euler_bernoulli(n):
    """HRZ-lumped beam:N: second order from below (measured: error x N^2 = 0.52, 2.0 for
    modes 1, 2 at N = 10..100); checked as error within 10 % of 0.52/N^2, 2.0/N^2."""
    f = natural_modes(
        build_system(straight(density=RHO), parse_model(f"beam:{n}")), count=2
    ).frequencies_hz
    error = f / beam_theory(BETA_L) - 1.0
    assert np.all(error < 0.0)
    assert error * n**2 == pytest.approx([-0.52, -2.0], rel=0.1)


def tip_mass_roots(ratio: float) -> list[float]:
    """The two lowest beta L of a cantilever with a tip point mass M = ratio mu L: roots of
    1 + cos cosh + (M / mu L) bL (cos sinh - sin cosh) = 0."""

    def equation(x):
        return (
            1.0
            + math.cos(x) * math.cosh(x)
            + ratio * x * (math.cos(x) * math.sinh(x) - math.sin(x) * math.cosh(x))
        )

    grid = np.linspace(0.1, 8.0, 400)
    return [
        brentq(equation, a, b)
        for a, b in zip(grid[:-1], grid[1:])
        if equation(a) * equation(b) < 0.0
    ][:2]


def test_tip_mass_frequency_equation():
    """Cantilever with a tip point mass M = 2 mu L against the frequency equation; beam:40
    within 0.02 % (measured 0.004 % and 0.015 %, the lumping's O(1/N^2))."""
    ratio = 2.0
    mech = straight(density=RHO, bodies={"t": RigidMass(ratio * MU * L, 0.0, np.array([L, 0.0]))})
    f = natural_modes(build_system(mech, parse_model("beam:40")), count=2).frequencies_hz
    np.testing.assert_allclose(f, beam_theory(tip_mass_roots(ratio)), rtol=2e-4)


@pytest.mark.parametrize("n", [1, 2, 4, 8])
def test_dcmm_rigid_pieces_on_a_cantilever(n):
    """dcmm:n with each body carrying its nearest half sub-arcs as rigid pieces: f1 above
    Euler-Bernoulli by 2.0, 3.2, 3.5, 3.55 %/n^2 at n = 1, 2, 4, 8 (3.57 %/n^2 at n = 16),
    checked as 0 < error < 3.6 %/n^2. The self-weight sag is -1/(6 n^2) exactly in the
    linear limit (the tip piece's weight acts l/4 inside the tip, the consistent load
    l/6: a tip moment rho A g l^2 / 24 too many); measured within 2.3e-4 of it (the
    geometric nonlinearity), bound 1e-3."""
    from flexval.geometry import Scene
    from flexval.validation.run import run_model

    f = natural_modes(
        build_system(straight(density=RHO), parse_model(f"dcmm:{n}")), count=1
    ).frequencies_hz[0]
    error = f / beam_theory(BETA_L[0]) - 1.0
    assert 0.0 < error < 0.036 / n**2
    mech = straight(density=RHO, gravity=np.array([0.0, -9810.0]))
    scene = Scene("sag", "", mech, (tip_force(mech, 0.0, 0.0, levels=2),), (), frozenset(), "<sag>")
    sag = run_model(scene, parse_model(f"dcmm:{n}"), scene.load_cases[0]).dy[0]
    expected = -MU * 9810.0 * L**4 / (8.0 * EI)
    assert (sag / expected - 1.0) * n**2 == pytest.approx(-1.0 / 6.0, rel=1e-3)


def test_prbm_pieces_on_links_match_a_cantilever():
    """prbm with the flexure's pieces on its end bodies and pseudo-links: f1 of the bare
    cantilever +0.022 % from Euler-Bernoulli and -0.003 % with a tip mass of twice the
    beam's (bounds 0.05 % and 0.01 %). Its sag is exact in the linear limit: the tip
    deflection under a uniform load weighs the compliance with (L - x)^3, and the
    symmetric chain matches the beam's compliance moments up to the third (measured
    -6e-7, the geometric nonlinearity; bound 1e-5)."""
    from flexval.geometry import Scene
    from flexval.validation.run import run_model

    ratio = 2.0
    bare = natural_modes(
        build_system(straight(density=RHO), parse_model("prbm")), count=1
    ).frequencies_hz[0]
    assert bare / beam_theory(BETA_L[0]) - 1.0 == pytest.approx(0.0, abs=5e-4)
    tip = straight(density=RHO, bodies={"t": RigidMass(ratio * MU * L, 0.0, np.array([L, 0.0]))})
    loaded = natural_modes(build_system(tip, parse_model("prbm")), count=1).frequencies_hz[0]
    assert loaded / beam_theory(tip_mass_roots(ratio)[0]) - 1.0 == pytest.approx(0.0, abs=1e-4)
    mech = straight(density=RHO, gravity=np.array([0.0, -9810.0]))
    scene = Scene("sag", "", mech, (tip_force(mech, 0.0, 0.0, levels=2),), (), frozenset(), "<sag>")
    sag = run_model(scene, parse_model("prbm"), scene.load_cases[0]).dy[0]
    assert sag == pytest.approx(-MU * 9810.0 * L**4 / (8.0 * EI), rel=1e-5)


@pytest.mark.parametrize(
    "model, low, high",
    [
        ("dcmm:1", 0.040, 0.047),
        ("dcmm:4", 0.040, 0.047),
        ("dcmm:8", 0.040, 0.047),
        ("prbm", -0.0040, -0.0030),
    ],
)
def test_lumped_models_on_a_cantilever_arc(model, low, high):
    """A 240-degree arc clamped at one end, against beam:400 (itself converged to 2e-5):
    dcmm:n's f1 error times n^2 measured 4.34, 4.37, 4.46 % at n = 1, 4, 8 (bounds
    4.0-4.7 %), prbm's -0.35 % (bounds -0.40..-0.30 %)."""
    mech = dataclasses.replace(cantilever(ARC, E=E, b=B, h=H), inertia=MassData(density=RHO))
    reference = natural_modes(build_system(mech, parse_model("beam:400")), count=1)
    f = natural_modes(build_system(mech, parse_model(model)), count=1).frequencies_hz[0]
    n = int(model.split(":")[1]) if ":" in model else 1
    assert low < (f / reference.frequencies_hz[0] - 1.0) * n**2 < high


@pytest.mark.parametrize("level", [0, 1])
def test_continuum_cantilever_against_beam_theory(level):
    """Plane-stress quad9 continuum (consistent mass) against Euler-Bernoulli with the
    Timoshenko-Rayleigh correction -(beta r)^2 (1 + E/(kappa G)) / 2 (r^2 = h^2/12:
    -0.006 % and -0.038 % at h/L = 0.01). Measured residuals: level 0 +0.025 %, +0.016 %;
    level 1 +0.015 %, +0.001 % (mesh and clamped-root effects); bound 0.05 %."""
    from flexval.validation.continuum.run import build_system as continuum_system

    f = natural_modes(continuum_system(straight(density=RHO), level), count=2).frequencies_hz
    beta = np.asarray(BETA_L) / L
    shear = 1.0 + E / ((5.0 / 6.0) * E / (2.0 * (1.0 + NU)))
    corrected = beam_theory(BETA_L) * (1.0 - 0.5 * beta**2 * H**2 / 12.0 * shear)
    np.testing.assert_allclose(f, corrected, rtol=5e-4)


@pytest.mark.parametrize("model", ["dcmm:1", "dcmm:4", "prbm", "ee"])
def test_rigid_body_on_one_arc_matches_ellipse_of_elasticity(model):
    """A body with its centre of mass at the arc's elastic centre on a massless arc: the
    ellipse's axes decouple the three one-dof oscillators sqrt(k_i / m_i) with
    k = 1/(w b^2), 1/(w a^2), 1/w. DCMM and PRBM reproduce the EE exactly at rest (the
    PRBM's pseudo-links are massless and condensed); round-off bound 1e-9."""
    arc = Arc((0.0, 3.0), 3.0, math.radians(150.0), math.radians(240.0))
    ellipse = arc.ellipse(EI)
    mass, inertia = 1e-6, 3e-5
    mech = dataclasses.replace(
        cantilever(arc, E=E, b=B, h=H),
        inertia=MassData(bodies={"t": RigidMass(mass, inertia, ellipse.center)}),
    )
    stiffness = 1.0 / np.diag(ellipse.compliance())
    exact = np.sort(np.sqrt(stiffness / np.array([mass, mass, inertia]))) / (2.0 * math.pi)
    f = natural_modes(build_system(mech, parse_model(model)), count=3).frequencies_hz
    np.testing.assert_allclose(f, exact, rtol=1e-9)


def test_beam_rigid_body_converges_to_ellipse():
    """beam:N on the same body tends to the EE frequencies at O(1/N^2)
    (measured 0.45 % at N = 20, 0.014 % at N = 100)."""
    arc = Arc((0.0, 3.0), 3.0, math.radians(150.0), math.radians(240.0))
    ellipse = arc.ellipse(EI)
    mech = dataclasses.replace(
        cantilever(arc, E=E, b=B, h=H),
        inertia=MassData(bodies={"t": RigidMass(1e-6, 3e-5, ellipse.center)}),
    )
    stiffness = 1.0 / np.diag(ellipse.compliance())
    exact = np.sort(np.sqrt(stiffness / np.array([1e-6, 1e-6, 3e-5]))) / (2.0 * math.pi)
    errors = [
        np.abs(
            natural_modes(build_system(mech, parse_model(f"beam:{n}")), count=3).frequencies_hz
            / exact
            - 1.0
        ).max()
        for n in (20, 40)
    ]
    assert errors[1] < 2e-4 * 25 and errors[0] / errors[1] == pytest.approx(4.0, rel=0.1)


def test_compression_lowers_the_first_frequency_to_zero_at_buckling():
    """A dead axial tip load: tension stiffens, compression softens, and the first
    frequency tends to zero at the Euler load P = pi^2 EI / 4 L^2 (beam:40's own
    critical load is within 0.1 % of it): (f/f0)^2 below 0.02 at 0.99 P_cr, the value
    of the Galef line 1 - P/P_cr (0.01) plus the model's O(1/N^2) error."""
    mech = straight(density=RHO)
    system = build_system(mech, parse_model("beam:40"))
    p_cr = math.pi**2 * EI / (4.0 * L**2)
    f0 = natural_modes(system, count=1).frequencies_hz[0]
    compression = tip_force(mech, -p_cr, 0.0)
    ratios = [
        natural_modes(system, compression, a, count=1).frequencies_hz[0] / f0
        for a in (0.25, 0.5, 0.9, 0.99)
    ]
    tension = natural_modes(system, tip_force(mech, p_cr, 0.0), 0.5, count=1).frequencies_hz[0]
    assert tension > f0
    assert np.all(np.diff(ratios) < 0.0) and ratios[0] < 1.0
    assert ratios[-1] ** 2 < 0.02


def test_sparse_and_dense_modes_agree_with_pins_and_multipliers():
    """The closed chain (pins' and PRBM closure multipliers, massless pseudo-links):
    the dense null-space reduction and shift-invert Lanczos on the bordered problem give
    the same frequencies (1e-6: the dense solver's round-off on the lowest eigenvalues
    of a pencil whose stiffness spans ~10 decades)."""
    from flexval.geometry import load_scene

    scene = load_scene("closed_chain")
    masses = {
        b: RigidMass(1e-6, 1e-5, scene.mechanism.bodies[b].reference + 1.0)
        for b in scene.mechanism.moving_bodies
    }
    mech = dataclasses.replace(scene.mechanism, inertia=MassData(density=RHO, bodies=masses))
    for model in ("prbm", "beam:10"):
        system = build_system(mech, parse_model(model))
        dense = natural_modes(system, count=4)
        q = system.initial_state()
        loads = system.loads(scene.load_cases[0])
        sparse = sparse_modes(
            system, MassModel(system), q, sparse_tangent(system, q, loads, 0.0), 4
        )
        np.testing.assert_allclose(sparse.frequencies_hz, dense.frequencies_hz, rtol=1e-6)
        M = MassModel(system).matrix(q).toarray()
        np.testing.assert_allclose(dense.shapes @ M @ dense.shapes.T, np.eye(4), atol=1e-8)


def test_massless_body_is_refused_by_name():
    """No density and no body mass: the tip body's coordinates have no mass."""
    system = build_system(straight(), parse_model("beam:4"))
    with pytest.raises(SceneError, match=r"bodies\.t\.mass.*body 't' \(x\)"):
        natural_modes(system)
