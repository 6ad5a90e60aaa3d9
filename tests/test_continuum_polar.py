"""The continuum's section-wise predictor (flexval.validation.continuum.polar).

Checks against geometry known independently of the module: the sections of
an arc mesh lie on its radii, the polar description round-trips, and a
deformed flexure turning rigidly at a constant rate is predicted exactly
(where extrapolating node positions misses by the third power of the step),
from two states or from one state and the path's slope, whose polar form is
the derivative of the polar description (central differences).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexval.geometry import Arc, Material, Section, Segment
from flexval.geometry.mechanism import FlexureSpec, assemble
from flexval.reducedmodels.core.extrapolation import hermite_weights
from flexval.validation.continuum import ContinuumConnector
from flexval.validation.continuum.group import ContinuumGroup
from flexval.validation.continuum.polar import (
    cross_sections,
    first_order_change,
    from_polar,
    stack_sections,
    to_polar,
)

pytestmark = pytest.mark.usefixtures("private_mesh_cache")  # meshes go to a temporary cache


ARC = Arc((0.0, 0.0), 3.0, math.radians(60.0), math.radians(200.0))


def connector(shape, h: float, level: int, start_on_ground: bool = True) -> ContinuumConnector:
    """One flexure from the ground (body 1) to body 2, the shape's start on the ground or not."""
    spec = FlexureSpec("e", shape, ("1", "2"), Section(1.0, h))
    ground, tip = (0, 1) if start_on_ground else (1, 0)
    mech = assemble(
        [spec],
        "1",
        shape.end_points[ground : ground + 1],
        Material(2100.0, 0.35),
        "2",
        shape.end_points[tip],
    )
    return ContinuumConnector(mech.flexures[0], mech, level)


@pytest.mark.parametrize("level", [0, 1, 2])
def test_arc_sections_lie_on_radii_from_start_to_end_and_right_to_left(level):
    conn = connector(ARC, 0.3, level)
    sections = cross_sections(conn.mesh)
    rel = conn.mesh.nodes[sections] - np.asarray(ARC.center)
    angle = np.unwrap(np.arctan2(rel[..., 1], rel[..., 0]), axis=0)
    radius = np.hypot(rel[..., 0], rel[..., 1])
    assert sections.shape == (2 * conn.mesh.n_l + 1, 2 * conn.mesh.n_t + 1)
    # nodes are placed on the polar map to round-off (1e-15 of the radius)
    np.testing.assert_allclose(angle - angle[:, :1], 0.0, atol=1e-12)
    assert np.all(np.diff(radius, axis=1) < 0.0)  # counterclockwise: the centre is left
    assert np.all(np.diff(angle[:, 0]) > 0.0)  # the arc runs counterclockwise
    np.testing.assert_array_equal(np.sort(sections[0]), np.sort(conn.mesh.start_face))
    np.testing.assert_array_equal(np.sort(sections[-1]), np.sort(conn.mesh.end_face))


def test_polar_description_round_trips_a_deformed_segment():
    conn = connector(Segment((0.0, 0.0), (2.0, 0.5)), 0.25, 1)
    sections = stack_sections([cross_sections(conn.mesh)], [0])
    X = conn.mesh.nodes
    x = X + 0.05 * np.column_stack([np.sin(3.0 * X[:, 0]), np.cos(2.0 * X[:, 0] + X[:, 1])])
    np.testing.assert_allclose(
        from_polar(to_polar(x, sections), sections, x), x, rtol=0, atol=1e-14
    )


def test_the_first_order_change_is_the_derivative_of_the_polar_description():
    conn = connector(ARC, 0.3, 1)
    sections = stack_sections([cross_sections(conn.mesh)], [0])
    X = conn.mesh.nodes
    x = X + 0.05 * np.column_stack([np.sin(3.0 * X[:, 0]), np.cos(2.0 * X[:, 0] + X[:, 1])])
    dx = np.column_stack([np.cos(X[:, 1]), X[:, 0] * X[:, 1]])
    change = first_order_change(x, dx, sections)

    def gaps(h: float) -> list[float]:
        """Largest mismatch of each polar field's central difference (mm, rad)."""
        plus, minus = to_polar(x + h * dx, sections), to_polar(x - h * dx, sections)
        return [
            float(np.abs(exact - (p - m) / (2 * h)).max())
            for exact, p, m in zip(change, plus, minus)
        ]

    # second order: halving h quarters every mismatch (3.5-4.5 allows the next
    # term; at these h round-off, ~1e-16 / h of the short chords' angles, is
    # 100 times smaller), so the change is the derivative, not an approximation
    ratios = [a / b for a, b in zip(gaps(1e-4), gaps(5e-5))]
    assert all(3.5 < r < 4.5 for r in ratios), ratios
    assert max(gaps(1e-4)) < 1e-7


def _turning(conn: ContinuumConnector, rate: float):
    """The flexure of ``conn``, deformed, with both bodies turning about a pivot at ``rate``.

    Returns ``state(factor)`` -> (pose_a, pose_b, internal) after turning by
    rate * factor rad, and ``slope(factor)``, its derivative per unit factor.
    """
    X = conn.mesh.nodes
    bent = X + 0.02 * np.column_stack([X[:, 1] ** 2, -X[:, 0] * X[:, 1]])  # a deformed shape
    pivot = np.array([0.5, -1.0])
    refs = [X[face[0]] - rel[0] for face, rel in zip(conn.end_faces, conn.end_offsets)]

    def rotation(factor: float) -> np.ndarray:
        c, s = math.cos(rate * factor), math.sin(rate * factor)
        return np.array([[c, -s], [s, c]])

    def state(factor: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rot = rotation(factor)
        poses = [np.array([*(pivot + (ref - pivot) @ rot.T), rate * factor]) for ref in refs]
        x = pivot + (bent - pivot) @ rot.T
        return poses[0], poses[1], (x[conn.free_nodes] - X[conn.free_nodes]).ravel()

    def slope(factor: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        def turn_rate(points: np.ndarray) -> np.ndarray:  # d/dfactor of points turning
            rel = points - pivot
            return rate * np.column_stack([-rel[:, 1], rel[:, 0]])

        rot = rotation(factor)
        poses = [
            np.array([*turn_rate((pivot + (ref - pivot) @ rot.T)[None])[0], rate]) for ref in refs
        ]
        x = pivot + (bent[conn.free_nodes] - pivot) @ rot.T
        return poses[0], poses[1], turn_rate(x).ravel()

    return state, slope


@pytest.mark.parametrize("start_on_ground", [True, False])
def test_a_flexure_turning_rigidly_is_predicted_exactly(start_on_ground):
    conn = connector(ARC, 0.3, 1, start_on_ground)
    state, _ = _turning(conn, 0.2)  # rad per unit factor
    states = [state(k) for k in range(3)]
    weights = [1.0, -3.0, 3.0]  # Lagrange through 0, 1, 2 at 3
    exact = state(3)
    predicted = conn.predict_internal(states, weights, exact[0], exact[1])
    np.testing.assert_allclose(predicted, exact[2], rtol=0, atol=1e-12)
    # extrapolating node positions (the default) misses by O(step^3) of the offsets (~1 mm)
    cartesian = sum(w * s[2] for w, s in zip(weights, states))
    assert np.abs(cartesian - exact[2]).max() > 1e-3


@pytest.mark.parametrize("start_on_ground", [True, False])
def test_with_the_slope_one_state_predicts_a_rigid_turn_exactly(start_on_ground):
    conn = connector(ARC, 0.3, 1, start_on_ground)
    state, slope = _turning(conn, 0.2)
    group = ContinuumGroup([conn])
    remember, predict = group.predictor(np.arange(6 + conn.n_internal))  # coordinates = local
    memories = np.array([remember(np.concatenate(state(1.0)))])
    exact = state(2.5)
    guess = np.concatenate([exact[0], exact[1], np.zeros(conn.n_internal)])
    weights, slope_weight = hermite_weights([1.0], 2.5)  # 1 and 1.5: a straight line
    predicted = predict(
        memories, np.asarray(weights), guess, np.concatenate(slope(1.0)), slope_weight
    )
    # the turn is linear in the polar variables: exact to round-off
    np.testing.assert_allclose(predicted, exact[2], rtol=0, atol=1e-12)
    # without the slope one state predicts no motion at all
    still = predict(memories, np.ones(1), guess)
    assert np.abs(still - exact[2]).max() > 0.1
    # and without the slope the predictor is the group's predict_internal
    states = [state(k) for k in range(3)]
    lagrange = np.array([1.0, -3.0, 3.0])
    np.testing.assert_allclose(
        predict(np.array([remember(np.concatenate(s)) for s in states]), lagrange, guess),
        group.predict_internal([[s] for s in states], lagrange, [(exact[0], exact[1])]),
        rtol=0,
        atol=1e-13,
    )


def _rest(conn: ContinuumConnector) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rest state (pose_a, pose_b, internal) of a connector."""
    refs = [
        conn.mesh.nodes[face[0]] - rel[0] for face, rel in zip(conn.end_faces, conn.end_offsets)
    ]
    return (np.array([*refs[0], 0.0]), np.array([*refs[1], 0.0]), np.zeros(conn.n_internal))


def test_the_newton_update_agrees_with_the_linear_one_to_first_order():
    conn = connector(ARC, 0.3, 1, start_on_ground=False)
    pose_a, pose_b, internal = _rest(conn)
    X = conn.mesh.nodes[conn.free_nodes]
    direction = (
        np.column_stack([np.sin(2.0 * X[:, 1]), X[:, 0] * X[:, 1]]).ravel(),
        np.array([0.3, -0.2, 0.5]),
        np.array([-0.1, 0.4, -0.3]),
    )

    def gap(eps: float) -> float:
        """Largest distance between the nonlinear and the linear update of a correction eps."""
        new = (
            pose_a + eps * direction[1],
            pose_b + eps * direction[2],
            internal + eps * direction[0],
        )
        return float(np.abs(conn.update_internal((pose_a, pose_b, internal), new) - new[2]).max())

    # second order: halving the correction quarters the gap (3.5-4.5 allows the
    # third-order term, which is below 10 % of it at these sizes)
    ratios = [gap(eps) / gap(eps / 2) for eps in (1e-2, 5e-3)]
    assert all(3.5 < r < 4.5 for r in ratios), ratios
    assert gap(1e-2) < 1e-2 * np.abs(direction[0]).max()


def test_the_newton_update_turns_sections_by_finite_angles():
    conn = connector(ARC, 0.3, 1)
    pose_a, pose_b, internal = _rest(conn)
    sections = cross_sections(conn.mesh)
    X = conn.mesh.nodes
    turn = 0.05 * np.sin(np.linspace(0.0, math.pi, sections.shape[0]))  # 0 at the faces
    centre = X[sections[:, sections.shape[1] // 2]]
    linear, exact = X.copy(), X.copy()
    for k, nodes in enumerate(sections):
        rel = X[nodes] - centre[k]
        c, s = math.cos(turn[k]), math.sin(turn[k])
        linear[nodes] = centre[k] + rel + turn[k] * np.column_stack([-rel[:, 1], rel[:, 0]])
        exact[nodes] = centre[k] + rel @ np.array([[c, s], [-s, c]])
    free = conn.free_nodes
    new = (pose_a, pose_b, (linear[free] - X[free]).ravel())
    updated = conn.update_internal((pose_a, pose_b, internal), new)
    np.testing.assert_allclose(updated, (exact[free] - X[free]).ravel(), rtol=0, atol=1e-14)
    # the linear update misses by turn^2 / 2 times the half thickness (0.15 mm)
    assert np.abs(new[2] - updated).max() > 0.1 * 0.05**2 / 2 * 0.15
