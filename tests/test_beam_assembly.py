"""The beam System's compiled assembly against the per-connector chain rule.

Reference: each BeamConnector's own gradient and Hessian over its local
coordinates (checked by central differences in tests/test_beam.py, and
evaluated there over all 36 entries of every element tangent), scattered
densely into the global arrays with the loads' terms. The System instead
adds only the entries its storage keeps (the upper band, or the whole
dense matrix) straight from the kernel; both scenes (flexures sharing
bodies, ends on the ground) and both storages are exercised. The first
solve with the assembled tangent (factorisation and solve in one compiled
call) is checked against a dense solve of the reference matrix.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.models import build_system
from tests.builders import assert_assembles_like_its_connectors


@pytest.mark.parametrize(
    "scene_name, model, kind",
    [
        ("open_chain", "beam:10", "banded"),
        ("closed_chain", "beam:20", "banded"),
        ("closed_chain", "beam:3", "dense"),
    ],
)
def test_system_assembly_equals_the_connectors_chain_rule(scene_name, model, kind):
    scene = load_scene(scene_name)
    system = build_system(scene.mechanism, parse_model(model))
    assert system.layout.kind == kind
    loads = system.loads(scene.load_case("f+"))
    rng = np.random.default_rng(11)
    q = system.initial_state() + 1e-2 * rng.standard_normal(system.n_dofs)
    ref_grad, ref_tangent = assert_assembles_like_its_connectors(system, q, loads, 0.7)
    _, grad, tangent = system.assemble(q, loads, 0.7)
    # the Newton correction: relative round-off of a solve, times the condition number
    # (~1e8 for slender flexures), far below 1e-6
    np.testing.assert_allclose(
        tangent.solve(-grad), np.linalg.solve(ref_tangent, -ref_grad), rtol=1e-6, atol=1e-9
    )


def test_assembly_leaves_no_trace_between_calls():
    """Work arrays the System reuses (coordinates, the loads' diagonal) carry nothing over."""
    scene = load_scene("open_chain")
    system = build_system(scene.mechanism, parse_model("beam:10"))
    loads = system.loads(scene.load_case("f+"))
    q = system.initial_state() + 1e-2 * np.random.default_rng(4).standard_normal(system.n_dofs)
    first = system.assemble(q, loads, 0.7)
    system.assemble(q + 0.1, loads, 0.3)
    again = system.assemble(q, loads, 0.7)
    assert again[0] == first[0]
    np.testing.assert_array_equal(again[1], first[1])
    np.testing.assert_array_equal(again[2].toarray(), first[2].toarray())
