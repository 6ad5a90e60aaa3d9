"""The continuum's group assembly (flexval.validation.continuum.group) against the
per-connector chain rule.

Reference: each ContinuumConnector's own gradient and Hessian over its local
coordinates (checked by finite differences in tests/test_continuum.py),
scattered densely into the global arrays. The closed chain has flexures
sharing bodies and faces on the ground, so every index path is exercised.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels.core.connector import ConnectorGroup
from flexval.validation.continuum import ContinuumConnector
from flexval.validation.continuum.group import ContinuumGroup
from flexval.validation.continuum.run import build_system
from tests.builders import assert_assembles_like_its_connectors

pytestmark = pytest.mark.usefixtures("private_mesh_cache")  # meshes go to a temporary cache


@pytest.mark.parametrize("scene_name", ["closed_chain", "open_chain"])
def test_group_assembly_equals_the_connectors_chain_rule(scene_name):
    scene = load_scene(scene_name)
    system = build_system(scene.mechanism, 0)
    assert [type(group) for group, _ in system._groups][0] is ContinuumGroup
    loads = system.loads(scene.load_case("f+"))
    rng = np.random.default_rng(5)
    q = system.initial_state() + 1e-3 * rng.standard_normal(system.n_dofs)
    assert_assembles_like_its_connectors(system, q, loads, 0.7)


def test_flexures_of_different_laws_are_evaluated_one_by_one():
    mech = load_scene("open_chain").mechanism
    conns = [
        ContinuumConnector(f, mech, 0, law=law)
        for f, law in zip(mech.flexures, ("svk", "neo-hookean", "svk"))
    ]
    assert type(ContinuumConnector.group(conns)) is ConnectorGroup
    assert type(ContinuumConnector.group(conns[::2])) is ContinuumGroup


def test_section_forces_from_the_end_face_equal_those_from_the_whole_gradient():
    scene = load_scene("closed_chain")
    system = build_system(scene.mechanism, 0)
    q = system.initial_state() + 1e-3 * np.random.default_rng(2).standard_normal(system.n_dofs)
    for conn, local in zip(system.connectors, system.local_states(q)):
        face = conn.section_forces(*local)  # end-face elements only
        full = conn.section_forces(*local, gradient=conn.evaluate(*local)[1])
        # the same nodal forces summed in another order: round-off (1e-16), 1e-13 allowed
        for name in ("axial", "moment"):
            a, b = getattr(face, name), getattr(full, name)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * np.abs(b).max())
