"""The System's index maps against their plain connector-by-connector construction.

The System builds its tangent layout from each group's Hessian pattern
(``ConnectorGroup.hessian_pattern``: the beams' from their element table in
one pass). Reference, built here independently: every connector's own
``hessian_pattern`` (or its dense square) mapped through its local-to-global
dofs, ground entries dropped, then the diagonal. The layout made from those
entries must be the System's (same storage, permutation and slot of every
entry), on beams, DCMM, PRBM, pinned scenes (Lagrange multipliers) and
weights (wrapped connectors).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from flexval.geometry import MassData, load_scene
from flexval.reducedmodels.beam.elements import BeamGroup
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.tangent import TangentLayout
from flexval.reducedmodels.models import build_system

SCENES = Path(__file__).parent / "scenes"


def plain_entries(system) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of every kept Hessian entry, connector by connector, then the diagonal."""
    rows, cols = [], []
    for c, idx in zip(system.connectors, system.local_to_global):
        pattern = c.hessian_pattern()
        if pattern is None:
            r, cc = np.repeat(idx, idx.size), np.tile(idx, idx.size)
        else:
            r, cc = idx[pattern[0]], idx[pattern[1]]
        keep = (r >= 0) & (cc >= 0)
        rows.append(r[keep]), cols.append(cc[keep])
    diagonal = np.arange(system.n_dofs)
    return np.concatenate([*rows, diagonal]), np.concatenate([*cols, diagonal])


@pytest.mark.parametrize(
    "scene, model",
    [
        ("open_chain", "beam:4"),
        ("closed_chain", "beam:30"),
        ("open_chain", "dcmm:3"),
        ("closed_chain", "dcmm:7"),
        ("closed_chain", "prbm"),
        (SCENES / "lee_frame.toml", "beam:12"),
        (SCENES / "deep_arch.toml", "dcmm:4"),
    ],
)
@pytest.mark.parametrize("gravity", [False, True])
def test_layout_is_the_one_of_the_connectors_own_entries(scene, model, gravity):
    mechanism = load_scene(scene).mechanism
    if gravity:  # the flexures' weights: connectors wrapped in Weighted
        mechanism = dataclasses.replace(
            mechanism, inertia=MassData(density=7.8e-9, gravity=np.array([0.0, -9810.0]))
        )
    system = build_system(mechanism, parse_model(model))
    compiled = any(group.compiled for group, _ in system.groups)
    rows, cols = plain_entries(system)
    reference = TangentLayout(system.n_dofs, rows, cols, system.n_multipliers, compiled)
    layout = system.layout
    assert (layout.kind, layout.size) == (reference.kind, reference.size)
    np.testing.assert_array_equal(layout.slots, reference.slots)
    if layout.kind == "banded":
        assert layout.b == reference.b
        np.testing.assert_array_equal(layout.perm, reference.perm)


@pytest.mark.parametrize(
    "scene, model", [("open_chain", "beam:5"), ("closed_chain", "dcmm:2"), ("open_chain", "prbm")]
)
def test_group_pattern_is_its_connectors_patterns_end_to_end(scene, model):
    """A group's pattern (beams: from the element table) is the concatenation of its
    connectors' own, each shifted by the connector's first local coordinate."""
    system = build_system(load_scene(scene).mechanism, parse_model(model))
    for group, _ in system.groups:
        rows, cols, start = [], [], 0
        for c in group.connectors:
            r, cc = c.hessian_pattern()
            rows.append(r + start), cols.append(cc + start)
            start += 6 + c.n_internal
        got_rows, got_cols = group.hessian_pattern()
        np.testing.assert_array_equal(got_rows, np.concatenate(rows))
        np.testing.assert_array_equal(got_cols, np.concatenate(cols))


@pytest.mark.parametrize(
    "scene, model",
    [
        ("open_chain", "beam:1"),
        ("open_chain", "beam:7"),
        ("closed_chain", "beam:3"),
        (SCENES / "lee_frame.toml", "beam:5"),
    ],
)
def test_beam_group_tables_are_its_connectors_tables_end_to_end(scene, model):
    """The group's node and element tables, built for all its flexures at once, are each
    connector's own (its node dof table, elements node after node) shifted and laid end to end."""
    system = build_system(load_scene(scene).mechanism, parse_model(model))
    for group, _ in system.groups:
        if not isinstance(group, BeamGroup):
            continue
        node_dof, dofs, first, chain_nodes, start, node = [], [], [], [0], 0, 0
        for c in group.connectors:
            table = c._node_dof_table()
            node_dof.append(table[:, 0] + start)
            dofs.append(np.hstack([table[:-1], table[1:]]) + start)
            first.append(node + np.arange(c._n_nodes - 1))
            start += 6 + c.n_internal
            node += c._n_nodes
            chain_nodes.append(node)
        np.testing.assert_array_equal(group._node_dof, np.concatenate(node_dof))
        np.testing.assert_array_equal(group._dofs, np.concatenate(dofs))
        np.testing.assert_array_equal(group._first, np.concatenate(first))
        np.testing.assert_array_equal(group._chain_nodes, chain_nodes)
        assert group._n_local == start and group._n_nodes == node
        for array in (group._node_dof, group._dofs, group._first, group._chain_nodes):
            assert array.dtype == np.int64


@pytest.mark.parametrize(
    "scene, model",
    [("open_chain", "dcmm:1"), ("closed_chain", "beam:4"), (SCENES / "lee_frame.toml", "prbm")],
)
def test_gather_maps_read_the_ground_pose_after_the_coordinates(scene, model):
    """Each connector's places in [q, ground pose]: its own dofs, and for a pose on the
    ground the ground pose's three entries after q."""
    system = build_system(load_scene(scene).mechanism, parse_model(model))
    n = system.n_dofs
    for idx, gather in zip(system.local_to_global, system._gather):
        expected = np.where(idx >= 0, idx, n + np.arange(idx.size) % 3)
        np.testing.assert_array_equal(gather, expected)
        assert gather.dtype == np.int64
    q = system.initial_state()
    for (pose_a, pose_b, _), c in zip(system.local_states(q), system.connectors):
        for pose, body in zip((pose_a, pose_b), c.bodies):
            np.testing.assert_array_equal(pose, system.pose(q, body))
