"""The kernel's contract and its one path tracer.

* a minimal connector that implements only what the contract requires
  (``evaluate``, ``shape``) and keeps every default is solved exactly
  (springs in series: closed-form compliance);
* the tracer yields exactly the requested load levels, in order, each a
  converged equilibrium, and the recorder's LoadPath is built from them;
* arc length through the Da Deppo arch yields points on the arc-length
  constraint, in equilibrium, past the limit point.
"""

import math

import numpy as np
import pytest
from builders import cantilever, tip_force
from test_continuation import deep_arch

from flexval.geometry import Arc, Force, LoadCase, Moment, Segment
from flexval.reducedmodels import (
    Connector,
    LoadControl,
    SolverSettings,
    System,
    build_system,
    solve_path,
    trace,
)
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.continuation import ArcLength, arc_dot

K1, K2, KT = 40.0, 60.0, 500.0
"""Spring stiffnesses of :class:`SeriesSprings`: N/mm, N/mm, N mm/rad."""


class SeriesSprings(Connector):
    """Two isotropic linear springs in series through a free node, and a torsion spring.

    Energy 1/2 k1 |u - d_a|^2 + 1/2 k2 |d_b - u|^2 + 1/2 kt (theta_b - theta_a)^2,
    with d_a, d_b the displacements of the bodies' reference points and u
    (the internal coordinates, mm) the node's. Only the required methods
    are written: every optional hook keeps its default.
    """

    n_internal = 2

    def __init__(self, bodies, references):
        self.name = "springs"
        self.bodies = tuple(bodies)
        self.rest = [np.asarray(references[b], float) for b in bodies]
        self.hessian = np.zeros((8, 8))
        for i, k in ((0, K1), (3, K2)):
            for d in range(2):
                a, n = i + d, 6 + d
                self.hessian[np.ix_([a, n], [a, n])] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
        self.hessian[np.ix_([2, 5], [2, 5])] += KT * np.array([[1.0, -1.0], [-1.0, 1.0]])

    def evaluate(self, pose_a, pose_b, internal):
        d = np.concatenate(
            [
                pose_a[:2] - self.rest[0],
                [pose_a[2]],
                pose_b[:2] - self.rest[1],
                [pose_b[2]],
                internal,
            ]
        )
        grad = self.hessian @ d
        return 0.5 * float(d @ grad), grad, self.hessian

    def shape(self, pose_a, pose_b, internal):
        return np.array([pose_a[:2], self.rest[0] + internal, pose_b[:2]])


def spring_system():
    mech = cantilever(Segment((0.0, 0.0), (10.0, 0.0)))  # only its bodies are used
    references = {b: mech.bodies[b].reference for b in mech.bodies}
    return System(mech, [SeriesSprings(("g", "t"), references)], SolverSettings())


def test_a_connector_that_keeps_every_default_is_solved_exactly():
    system = spring_system()
    mech = system.mechanism
    force, moment = 3.0, 20.0  # N, N mm
    case = LoadCase(
        "FM",
        (Force("t", mech.bodies["t"].reference, math.radians(30.0), force), Moment("t", moment)),
        6,
    )
    lp = solve_path(system, case)
    lam = np.linspace(0.0, 1.0, 6)
    compliance = 1.0 / K1 + 1.0 / K2  # springs in series, mm/N
    # the load acts at the reference point, which is offset from the target point
    rel = mech.target_point - mech.bodies["t"].reference
    turn = lam * moment / KT
    expect_x = (
        lam * force * compliance * math.cos(math.radians(30.0))
        + rel[0] * (np.cos(turn) - 1)
        - rel[1] * np.sin(turn)
    )
    np.testing.assert_allclose(lp.rotation, turn, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(lp.dx, expect_x, rtol=1e-10, atol=1e-14)
    assert lp.converged and lp.valid == [True] * 6 and lp.validity == [None] * 6
    # a linear problem: one correction per level (plus the check it converged)
    assert max(lp.stats["iterations"]) <= 2


def test_the_contract_requires_evaluate_and_shape():
    class Incomplete(Connector):
        def evaluate(self, pose_a, pose_b, internal):
            return 0.0, np.zeros(6), np.zeros((6, 6))

    with pytest.raises(TypeError, match="shape"):
        Incomplete()


def test_the_tracer_yields_the_requested_levels_in_equilibrium():
    mech = cantilever(Arc((0.0, 0.0), 10.0, math.pi / 2, math.pi / 2), h=0.3)
    system = build_system(mech, parse_model("beam:10"))
    case = tip_force(mech, 0.0, -2.0, levels=5)
    loads = system.loads(case)
    factors = case.factors(None)
    points = list(trace(system, loads, LoadControl(factors)))
    assert [p.factor for p in points] == list(factors)
    for p in points:
        _, g, _ = system.assemble(p.state, loads, p.factor)
        assert system.residual(g, loads) < 1e-7  # converged (force_tol 1e-10 or step)
    # every Newton iteration is attributed to exactly one yielded point
    totals = [p.counters.newton_iterations for p in points]
    assert totals == list(np.cumsum([p.iterations for p in points]))
    assert points[-1].counters.substeps >= len(factors) - 1
    # the recorder builds the same levels from the same points
    lp = solve_path(system, case)
    assert lp.stats["iterations"] == [p.iterations for p in points]
    assert lp.dx == [system.target(p.state)[0] for p in points]


def test_arc_length_points_lie_on_the_constraint_in_equilibrium_past_the_limit():
    system, case = deep_arch(20)
    loads = system.loads(case)
    stepping = ArcLength(12.0, 40, psi=0.0, max_steps=4000, max_growth=1.0)
    points = []
    for p in trace(system, loads, stepping):
        points.append(p)
        if len(points) >= 3 and points[-1].factor < points[-2].factor:
            break  # past the first limit point
    factors = [p.factor for p in points]
    assert max(factors) == pytest.approx(9.0, abs=0.1)  # the arch's limit, ~9.01 at N = 20
    for prev, p in zip(points, points[1:]):
        d = p.state - prev.state
        assert math.sqrt(arc_dot(system, d, d)) == pytest.approx(p.step, rel=1e-6)
        _, g, _ = system.assemble(p.state, loads, p.factor)
        assert system.residual(g, loads) < 1e-7


@pytest.mark.parametrize("model", ["dcmm:2", "prbm", "beam:4", "ee"])
def test_hessian_product_equals_the_assembled_local_hessian(model):
    """local_hessian_product is the matrix-free form of local_hessian(...) @ x
    (same pattern values; summation order only, so 1e-12 relative)."""
    from flexval.geometry import load_scene
    from flexval.reducedmodels.core.system import local_hessian, local_hessian_product
    from flexval.reducedmodels.models import build_system

    system = build_system(load_scene("closed_chain").mechanism, parse_model(model))
    rng = np.random.default_rng(3)
    for c, local in zip(system.connectors, system.local_states(system.initial_state())):
        h = c.evaluate(*local)[2]
        x = rng.standard_normal(6 + c.n_internal)
        full = local_hessian(c, h) @ x
        assert np.allclose(
            local_hessian_product(c, h, x), full, rtol=1e-12, atol=1e-12 * np.abs(full).max()
        )
