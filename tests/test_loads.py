"""Dead loads (flexval.reducedmodels.core.loads) against their potential written out independently.

The potential of dead forces F at material points x = p + R(theta) rel and
moments M on body rotations is V = -lambda (sum F . x + sum M theta); here
it is evaluated with numpy's rotation matrices from the load case's
components, and :meth:`Loads.add_to`'s energy, gradient and tangent
diagonal are checked against it and its central finite differences.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexval.geometry import Force, LoadCase, Moment
from flexval.reducedmodels.core.loads import MANY_LOADS, Loads

BODIES = {"ground": -1, "a": 0, "b": 1}
REFERENCE = {"ground": np.array([0.0, 0.0]), "a": np.array([10.0, 2.0]), "b": np.array([-4.0, 7.0])}
SIZE = 20.0
H = 1e-5
"""Central-difference step (mm, rad); the gradients' differences measured: 4e-10 N, N mm."""
FD_TOL = 1e-8
"""Absolute tolerance (N, N mm) on the first differences: 25 times the measured."""
H2 = 1e-3
"""Second-difference step (rad); the diagonal's differences measured: 1.2e-6 N mm
(truncation ~H2^2 |V''''| / 12 on loads of tens of N mm)."""
FD2_TOL = 1e-4
"""Absolute tolerance (N mm) on the second differences: 80 times the measured."""


def pose_dofs(body: str) -> np.ndarray:
    """The pose dofs of BODIES' numbering (ground: -1)."""
    k = BODIES[body]
    return np.full(3, -1) if k < 0 else np.arange(3 * k, 3 * k + 3)


def case(*components) -> LoadCase:
    """A load case of these components."""
    return LoadCase("test", tuple(components), 3)


CASES = {
    "one force": case(Force("a", np.array([12.0, 5.0]), 0.7, 3.0)),
    "two forces on one body and a moment": case(
        Force("b", np.array([1.0, 9.0]), -2.1, 4.0),
        Force("b", np.array([-6.0, 3.0]), 0.3, -2.5),
        Moment("a", 40.0),
    ),
    "loads on the ground are dropped": case(
        Force("ground", np.array([1.0, 1.0]), 0.0, 5.0),
        Moment("ground", 3.0),
        Moment("b", -25.0),
        Force("a", np.array([0.0, 0.0]), 1.9, 1.5),
    ),
    "many loads, some on the ground: one numpy pass": case(
        *[
            Force(body, np.array([0.5 * k, 3.0 - k]), 0.4 * k - 1.0, 2.0 + 0.5 * k)
            for k in range(6)
            for body in ("a", "b", "ground")
        ],
        *[Moment(body, 7.0 - 3.0 * k) for k in range(3) for body in ("b", "ground", "a")],
    ),
}


def potential(load_case: LoadCase, q: np.ndarray, factor: float) -> float:
    """-factor (sum F . x + sum M theta) from the components, with rotation matrices (N mm)."""
    total = 0.0
    for comp in load_case.components:
        k = BODIES[comp.body]
        if k < 0:
            continue
        x, y, theta = q[3 * k : 3 * k + 3]
        if isinstance(comp, Moment):
            total += comp.value * theta
            continue
        rotation = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
        point = np.array([x, y]) + rotation @ (comp.point - REFERENCE[comp.body])
        total += comp.value * np.array([np.cos(comp.angle), np.sin(comp.angle)]) @ point
    return -factor * total


@pytest.mark.parametrize("name", CASES)
def test_add_to_is_the_potential_and_its_derivatives(name: str) -> None:
    load_case, factor = CASES[name], 0.8
    loads = Loads.of_case(load_case, pose_dofs, REFERENCE, SIZE)
    moving = sum(BODIES[c.body] >= 0 for c in load_case.components)
    assert loads.many == (moving > MANY_LOADS)  # one numpy pass over many, a loop over few
    rng = np.random.default_rng(3)
    q = np.concatenate([REFERENCE["a"], [0.4], REFERENCE["b"], [-1.1]]) + rng.normal(0, 1, 6)
    grad, diagonal = np.zeros(6), np.zeros(6)
    energy = loads.add_to(q, factor, grad, diagonal)
    assert energy == pytest.approx(potential(load_case, q, factor), rel=1e-14, abs=1e-12)
    step = np.eye(6) * H
    fd_grad = [
        (potential(load_case, q + e, factor) - potential(load_case, q - e, factor)) / (2 * H)
        for e in step
    ]
    np.testing.assert_allclose(grad, fd_grad, rtol=0, atol=FD_TOL)
    # the tangent diagonal holds the rotations' second derivatives (translations: zero)
    fd_second = [
        (
            potential(load_case, q + e, factor)
            - 2 * potential(load_case, q, factor)
            + potential(load_case, q - e, factor)
        )
        / H2**2
        for e in np.eye(6) * H2
    ]
    np.testing.assert_allclose(diagonal, fd_second, rtol=0, atol=FD2_TOL)
    # the load vector is minus the gradient's derivative in the factor (it is linear in it)
    np.testing.assert_allclose(loads.vector(q), -grad / factor, rtol=1e-14, atol=1e-14)
