"""Load control's sub-step control: no Newton solve starts from a prediction beyond the bounds.

:class:`flexval.reducedmodels.core.tracer.LoadControl` halves a sub-step before solving
it when the predictor itself already moves a body further than the step
bounds (such a step is refused after its Newton solve anyway, or its
iterates leave the bounds; on the open chain's f- soft stretch that cost
4 to 17 iterations per attempt). These tests check the invariant on the
path where it matters, that the pre-cut does act there, and that the path
still reaches the same states as one traced with bounds twice as fine
(which never needs the pre-cut to stay on its branch).
"""

import dataclasses

import numpy as np
import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels import LoadControl, build_system, trace
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.settings import SolverSettings
from flexval.reducedmodels.core.tracer import PREDICTOR_STATES


class RecordingControl(LoadControl):
    """LoadControl that records each attempt's sub-step before and after, and its predictor."""

    def __init__(self, factors):
        super().__init__(factors)
        self.attempts = []

    def attempt(self):
        before = self.step
        problem, guess, origin = super().attempt()
        self.attempts.append((before, self.step, self.system.motion_ratio(origin, guess)))
        return problem, guess, origin


def soft_stretch(model: str, settings: SolverSettings | None = None):
    """The system of ``model`` on the open chain, its f- case and the recorded stepping."""
    scene = load_scene("open_chain")
    case = scene.load_case("f-")
    system = build_system(scene.mechanism, parse_model(model), settings)
    control = RecordingControl(case.factors())
    points = list(trace(system, system.loads(case), control))
    return system, points, control


@pytest.mark.parametrize("model", ["dcmm:1", "prbm", "beam:20"])
def test_no_solve_starts_beyond_the_step_bounds(model):
    system, points, control = soft_stretch(model)
    assert [round(p.factor, 12) for p in points] == [round(0.1 * k, 12) for k in range(11)]
    assert all(ratio <= 1.0 for _, _, ratio in control.attempts)
    # the pre-cut acted: some attempt halved its sub-step before solving
    assert any(after < before for before, after, _ in control.attempts)


def test_pre_cut_path_reaches_the_finely_stepped_states():
    """Against bounds twice as fine: the same states within what Newton leaves.

    Tracing with other sub-steps moves the states only by what the
    convergence test leaves (error_tol 1e-10 scaled). Measured largest
    scaled difference over the 11 levels against bounds twice as fine:
    1.0e-11 (dcmm:1), 3.2e-10 (prbm), 1.2e-10 (beam:20); 1e-9 bounds the
    three, far below anything the reports print (1e-4 mm on a 100 mm size).
    """
    system, points, _ = soft_stretch("dcmm:1")
    fine = dataclasses.replace(
        SolverSettings(), max_rotation_step=0.125, max_translation_step=0.025
    )
    _, fine_points, _ = soft_stretch("dcmm:1", fine)
    for p, f in zip(points, fine_points, strict=True):
        assert np.max(np.abs(system.scaled(p.state - f.state))) <= 1e-9


def test_first_substep_starts_on_the_linear_solution():
    """The first sub-step's predictor is the solution of the linearised problem, K^-1 f dfactor.

    At a load factor of 1e-7 the path is linear to O(1e-14) of the full
    load, below the residual tolerance (1e-10 of it): Newton accepts the
    prediction without a correction. From the rest state (what the
    extrapolation of one state gives) it needs at least one.
    """
    scene = load_scene("open_chain")
    system = build_system(scene.mechanism, parse_model("dcmm:1"))
    loads = system.loads(scene.load_case("f+"))
    points = list(trace(system, loads, LoadControl([0.0, 1e-7])))
    assert points[1].iterations == 0
    assert np.max(np.abs(system.scaled(points[1].state - points[0].state))) > 1e-9


@pytest.mark.parametrize("model", ["dcmm:1", "beam:20"])
def test_predictor_reproduces_a_polynomial_path_of_its_degree(model):
    """From PREDICTOR_STATES states on a polynomial path of one degree less, the
    prediction is exact.

    Body poses follow a quartic in the load factor (internal coordinates of
    beams follow the bodies' end nodes through their own chord-wise
    predictor, so only the poses are compared); unevenly spaced factors as
    after a step cut. Agreement to round-off (1e-12 scaled).
    """
    scene = load_scene("open_chain")
    system = build_system(scene.mechanism, parse_model(model))
    q0 = system.initial_state()
    rng = np.random.default_rng(7)
    coefficients = 1e-3 * rng.standard_normal((PREDICTOR_STATES, q0.size))

    def state(factor):
        return q0 + sum(c * factor**k for k, c in enumerate(coefficients))

    factors = [0.1, 0.2, 0.25, 0.275, 0.3][-PREDICTOR_STATES:]
    predicted = system.predict([(state(f), f) for f in factors], 0.35)
    poses = slice(0, 3 * len(system.body_index))
    error = system.scaled(predicted - state(0.35))[poses]
    assert np.max(np.abs(error)) <= 1e-12


def test_predictor_with_the_slope_reproduces_a_polynomial_path_one_degree_higher():
    """Given dq/dfactor at the last state too, the prediction is exact one degree higher (Hermite).

    dcmm:1 (no connector predicts its own coordinates, so every coordinate
    follows the polynomial): a quintic path through PREDICTOR_STATES
    unevenly spaced states and its slope at the last; the same states
    without the slope miss it (by 1.9e-7 scaled, measured). Agreement to
    round-off (1e-11 scaled).
    """
    scene = load_scene("open_chain")
    system = build_system(scene.mechanism, parse_model("dcmm:1"))
    q0 = system.initial_state()
    rng = np.random.default_rng(11)
    coefficients = 1e-2 * rng.standard_normal((PREDICTOR_STATES + 1, q0.size))

    def state(factor):
        return q0 + sum(c * factor**k for k, c in enumerate(coefficients))

    def slope(factor):
        return sum(k * c * factor ** (k - 1) for k, c in enumerate(coefficients) if k)

    factors = [0.1, 0.2, 0.25, 0.275, 0.3][-PREDICTOR_STATES:]
    history = [(state(f), f) for f in factors]
    exact = state(0.35)
    with_slope = system.predict(history, 0.35, slope=slope(factors[-1]))
    assert np.max(np.abs(system.scaled(with_slope - exact))) <= 1e-11
    without = system.predict(history, 0.35)
    assert np.max(np.abs(system.scaled(without - exact))) > 1e-8


@pytest.mark.parametrize("scene, model", [("open_chain", "dcmm:2"), ("closed_chain", "prbm")])
def test_motion_ratio_is_the_largest_body_motion_over_the_bounds(scene, model):
    """System.motion_ratio (a float loop over the bodies) against its definition in numpy:
    max(|d theta| / max_rotation_step, |d(x, y)| / (max_translation_step size)) over the
    moving bodies, internal coordinates ignored, on random motions of every size and
    direction; to 2e-16 relative (math.hypot and numpy's hypot may round differently)."""
    system = build_system(load_scene(scene).mechanism, parse_model(model))
    s, bodies = system.settings, len(system.body_index)
    rng = np.random.default_rng(3)
    q0 = system.initial_state()
    for scale in (1e-6, 1e-2, 1.0, 30.0):
        q1 = q0 + rng.normal(0.0, scale, q0.size)
        d = (q1[: 3 * bodies] - q0[: 3 * bodies]).reshape(-1, 3)
        expected = max(
            np.abs(d[:, 2]).max() / s.max_rotation_step,
            np.hypot(d[:, 0], d[:, 1]).max() / (s.max_translation_step * system.size),
        )
        assert system.motion_ratio(q0, q1) == pytest.approx(expected, rel=2e-16)
        assert system.motion_ratio(q1, q1) == 0.0
