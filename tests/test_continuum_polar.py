"""The continuum's section-wise predictor (validation.continuum.polar).

Checks against geometry known independently of the module: the sections of
an arc mesh lie on its radii, the polar description round-trips, and a
deformed flexure turning rigidly at a constant rate is predicted exactly
(where extrapolating node positions misses by the third power of the step).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from geometry import Arc, Material, Section, Segment
from geometry.mechanism import FlexureSpec, assemble
from validation.continuum import ContinuumConnector
from validation.continuum.polar import cross_sections, from_polar, stack_sections, to_polar


pytestmark = pytest.mark.usefixtures("private_mesh_cache")  # meshes go to a temporary cache


ARC = Arc((0.0, 0.0), 3.0, math.radians(60.0), math.radians(200.0))


def connector(shape, h: float, level: int, start_on_ground: bool = True) -> ContinuumConnector:
    """One flexure from the ground (body 1) to body 2, the shape's start on the ground or not."""
    spec = FlexureSpec("e", shape, ("1", "2"), Section(1.0, h))
    ground, tip = (0, 1) if start_on_ground else (1, 0)
    mech = assemble([spec], "1", shape.end_points[ground:ground + 1], Material(2100.0, 0.35),
                    "2", shape.end_points[tip])
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
    assert np.all(np.diff(radius, axis=1) < 0.0)     # counterclockwise: the centre is left
    assert np.all(np.diff(angle[:, 0]) > 0.0)       # the arc runs counterclockwise
    np.testing.assert_array_equal(np.sort(sections[0]), np.sort(conn.mesh.start_face))
    np.testing.assert_array_equal(np.sort(sections[-1]), np.sort(conn.mesh.end_face))


def test_polar_description_round_trips_a_deformed_segment():
    conn = connector(Segment((0.0, 0.0), (2.0, 0.5)), 0.25, 1)
    sections = stack_sections([cross_sections(conn.mesh)], [0])
    X = conn.mesh.nodes
    x = X + 0.05 * np.column_stack([np.sin(3.0 * X[:, 0]), np.cos(2.0 * X[:, 0] + X[:, 1])])
    np.testing.assert_allclose(from_polar(to_polar(x, sections), sections, x), x,
                               rtol=0, atol=1e-14)


@pytest.mark.parametrize("start_on_ground", [True, False])
def test_a_flexure_turning_rigidly_is_predicted_exactly(start_on_ground):
    conn = connector(ARC, 0.3, 1, start_on_ground)
    X = conn.mesh.nodes
    bent = X + 0.02 * np.column_stack([X[:, 1] ** 2, -X[:, 0] * X[:, 1]])   # a deformed shape
    pivot, step = np.array([0.5, -1.0]), 0.2                                # rad per state

    def turned(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The deformed flexure and both bodies turned by k steps about the pivot."""
        c, s = math.cos(k * step), math.sin(k * step)
        rot = np.array([[c, -s], [s, c]])
        x = pivot + (bent - pivot) @ rot.T
        poses = []
        for face, rel in zip(conn._face, conn._rel):       # body reference = face node - rel
            ref = X[face[0]] - rel[0]
            poses.append(np.array([*(pivot + (ref - pivot) @ rot.T), k * step]))
        # the bodies hold the faces of the undeformed mesh: make the bent shape agree there
        x[conn._face[0]] = conn.positions(*poses, np.zeros(conn.n_internal))[conn._face[0]]
        x[conn._face[1]] = conn.positions(*poses, np.zeros(conn.n_internal))[conn._face[1]]
        return poses[0], poses[1], (x[conn.free_nodes] - X[conn.free_nodes]).ravel()

    states = [turned(k) for k in range(3)]
    weights = [1.0, -3.0, 3.0]                        # Lagrange through 0, 1, 2 at 3
    exact = turned(3)
    predicted = conn.predict_internal(states, weights, exact[0], exact[1])
    np.testing.assert_allclose(predicted, exact[2], rtol=0, atol=1e-12)
    # extrapolating node positions (the default) misses by O(step^3) of the offsets (~1 mm)
    cartesian = sum(w * s[2] for w, s in zip(weights, states))
    assert np.abs(cartesian - exact[2]).max() > 1e-3


def _rest(conn: ContinuumConnector) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rest state (pose_a, pose_b, internal) of a connector."""
    refs = [conn.mesh.nodes[face[0]] - rel[0] for face, rel in zip(conn._face, conn._rel)]
    return (np.array([*refs[0], 0.0]), np.array([*refs[1], 0.0]),
            np.zeros(conn.n_internal))


def test_the_newton_update_agrees_with_the_linear_one_to_first_order():
    conn = connector(ARC, 0.3, 1, start_on_ground=False)
    pose_a, pose_b, internal = _rest(conn)
    X = conn.mesh.nodes[conn.free_nodes]
    direction = (np.column_stack([np.sin(2.0 * X[:, 1]), X[:, 0] * X[:, 1]]).ravel(),
                 np.array([0.3, -0.2, 0.5]), np.array([-0.1, 0.4, -0.3]))

    def gap(eps: float) -> float:
        """Largest distance between the nonlinear and the linear update of a correction eps."""
        new = (pose_a + eps * direction[1], pose_b + eps * direction[2],
               internal + eps * direction[0])
        return float(np.abs(conn.update_internal((pose_a, pose_b, internal), new)
                            - new[2]).max())

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
    turn = 0.05 * np.sin(np.linspace(0.0, math.pi, sections.shape[0]))   # 0 at the faces
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
