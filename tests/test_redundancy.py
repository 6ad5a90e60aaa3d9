"""A model whose rigid directions lock one motion more than once is refused, not traced.

The PRBM's straight leaf is inextensible (its joints on one line); a guide of
three parallel leaves, or two leaves on one line, then holds one motion rigid
more than once, and how the leaves share a load along it is statically
indeterminate in the model: traced anyway, its Newton stalls or its stresses
are arbitrary (a leaf of a nine-leaf guide at a hundred times the beams' stress).
The geometric check (:func:`redundant_connectors`) is held to an independent
answer: the saddle point's tangent at rest is singular exactly where the rigid
directions are dependent, one zero eigenvalue per dependence, over guides of
2 to 6 leaves, leaves on one line, leaves turned slightly out of parallel,
crossed leaves and pins.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexval.geometry import Force, LoadCase, Material, SceneError, Section, Segment
from flexval.geometry.mechanism import FlexureSpec, PinSpec, assemble
from flexval.reducedmodels import build_system
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.batch import run_batch
from flexval.reducedmodels.core.redundancy import redundant_connectors
from flexval.reducedmodels.core.system import System
from flexval.reducedmodels.prbm.connector import prbm_connector
from flexval.validation.cli import main

ALUMINIUM = Material(70000.0, 0.33)


def leaf(name, start, end, bodies, thickness, **extra) -> FlexureSpec:
    """A straight leaf from ``start`` to ``end`` (mm) between ``bodies``, from the first, of
    depth 10 mm and ``thickness`` (mm)."""
    return FlexureSpec(
        name,
        Segment(tuple(start), tuple(end)),
        tuple(bodies),
        Section(10.0, thickness),
        start_body=bodies[0],
        **extra,
    )


def guide(count: int, tilt: float = 0.0, spacing: float = 20.0, length: float = 50.0):
    """A guide of ``count`` straight leaves from the ground to a shuttle, the last one turned
    by ``tilt`` (rad) about its foot."""
    specs, feet = [], []
    for i in range(count):
        foot = np.array([spacing * i, 0.0])
        angle = np.pi / 2 + (tilt if i == count - 1 else 0.0)
        head = foot + length * np.array([np.cos(angle), np.sin(angle)])
        specs.append(leaf(f"leaf{i}", foot, head, ("ground", "shuttle"), 0.625))
        feet.append(foot)
    return assemble(specs, "ground", np.array(feet), ALUMINIUM, "shuttle", np.array([0.0, length]))


def on_one_line():
    """Two leaves on one line holding a block between them (the block's axial motion locked
    twice), and a third across (which keeps the block from turning)."""
    specs = [
        leaf("below", (0.0, 0.0), (0.0, 20.0), ("ground", "block"), 0.5),
        leaf("above", (0.0, 40.0), (0.0, 60.0), ("block", "ground"), 0.5),
        leaf("across", (20.0, 30.0), (40.0, 30.0), ("block", "ground"), 0.5),
    ]
    ground = np.array([[0.0, 0.0], [0.0, 60.0], [40.0, 30.0]])
    points = {"block": np.array([[0.0, 20.0], [0.0, 40.0], [20.0, 30.0]])}
    return assemble(
        specs, "ground", ground, ALUMINIUM, "block", np.array([0.0, 30.0]), body_points=points
    )


def crossed():
    """Two leaves crossing at 90 degrees (a cross pivot): independent directions."""
    specs = [
        leaf("a", (0.0, 0.0), (20.0, 20.0), ("ground", "top"), 0.3, crosses=("b",)),
        leaf("b", (20.0, 0.0), (0.0, 20.0), ("ground", "top"), 0.3, crosses=("a",)),
    ]
    return assemble(
        specs,
        "ground",
        np.array([[0.0, 0.0], [20.0, 0.0]]),
        ALUMINIUM,
        "top",
        np.array([10.0, 20.0]),
    )


def pinned_leaf():
    """A straight leaf whose axis passes through a pin of the same body: the pin holds the
    leaf's axial motion already."""
    specs = [leaf("leaf", (0.0, 0.0), (0.0, 30.0), ("ground", "arm"), 0.4)]
    pins = [PinSpec("pin", ("ground", "arm"), (0.0, 50.0))]
    return assemble(
        specs,
        "ground",
        np.array([[0.0, 0.0], [0.0, 50.0]]),
        ALUMINIUM,
        "arm",
        np.array([0.0, 50.0]),
        body_points={"arm": np.array([[0.0, 30.0]])},
        pin_specs=pins,
    )


ZERO_BELOW = 1e-13
"""An eigenvalue of the scaled tangent at rest below this, relative to its largest, is a zero
one: a dependence lands at 1e-16 to 5e-16, the most nearly dependent independent case here (a
leaf turned 1e-3 rad) at 2e-10, the others at 6e-7 and above."""


def rest_zero_eigenvalues(mechanism) -> int:
    """The zero eigenvalues of the PRBM's tangent at rest (symmetrically scaled by its rows'
    sizes), the independent count, of a System built without the check."""
    connectors = [prbm_connector(f, mechanism) for f in mechanism.flexures]
    if mechanism.pins:
        from flexval.reducedmodels.core.drives import constraint_connectors

        connectors += constraint_connectors(mechanism)
    system = System(mechanism, connectors)
    rest = LoadCase("rest", (Force(mechanism.target_body, mechanism.target_point, 0.0, 0.0),), 2)
    tangent = system.assemble(system.initial_state(), system.loads(rest), 0.0)[2].toarray()
    scale = 1.0 / np.sqrt(np.abs(tangent).sum(axis=1))
    values = np.abs(np.linalg.eigvalsh(scale[:, None] * tangent * scale[None, :]))
    return int(np.sum(values < ZERO_BELOW * values.max()))


CASES = {
    "two parallel leaves": (lambda: guide(2), 0),
    "three parallel leaves": (lambda: guide(3), 1),
    "four parallel leaves": (lambda: guide(4, spacing=7.0), 2),
    "six parallel leaves": (lambda: guide(6, spacing=3.0, length=80.0), 4),
    "three leaves, one turned 0.05 rad": (lambda: guide(3, tilt=0.05), 0),
    "three leaves, one turned 1e-3 rad": (lambda: guide(3, tilt=1e-3), 0),
    "two leaves on one line": (on_one_line, 1),
    "crossed leaves": (crossed, 0),
}


@pytest.mark.parametrize("name", list(CASES))
def test_dependent_rigid_directions_are_the_singular_rest_tangents(name):
    make, dependences = CASES[name]
    mechanism = make()
    assert rest_zero_eigenvalues(mechanism) == dependences
    connectors = [prbm_connector(f, mechanism) for f in mechanism.flexures]
    named = redundant_connectors(mechanism, connectors)
    assert bool(named) == bool(dependences)
    if dependences:
        assert len(named) >= dependences + 1  # a dependence takes two directions at least


def test_a_pin_on_a_leafs_axis_is_a_dependence():
    mechanism = pinned_leaf()
    assert rest_zero_eigenvalues(mechanism) == 1
    with pytest.raises(SceneError, match="'leaf', 'pin'"):
        build_system(mechanism, parse_model("prbm"))
    build_system(mechanism, parse_model("beam:4"))  # the leaf's axial stiffness: determinate


@pytest.mark.parametrize("count", [3, 5, 9])
def test_prbm_refuses_a_guide_of_more_than_two_parallel_leaves(count):
    mechanism = guide(count, spacing=4.0)
    with pytest.raises(SceneError) as caught:
        build_system(mechanism, parse_model("prbm"))
    assert caught.value.field == "flexures.leaf0"
    assert all(f"'leaf{i}'" in caught.value.reason for i in range(count))
    assert "statically indeterminate" in caught.value.reason
    for model in ("beam:4", "dcmm:1"):  # they carry the leaves' axial stiffness
        build_system(mechanism, parse_model(model))


def test_a_batch_returns_each_copys_refusal():
    """Copies traced together get what their solo runs raise: the redundant guide its
    SceneError, the determinate one its path."""
    mechanisms = [guide(2), guide(3), guide(2)]
    case = LoadCase("push", (Force("shuttle", np.array([0.0, 50.0]), 0.0, 1.0),), 3)
    results = run_batch(mechanisms, parse_model("prbm"), [case] * 3)
    assert isinstance(results[1], SceneError) and "'leaf2'" in str(results[1])
    assert results[0].converged and results[2].converged


SCENE = """
name = "three_leaves"
[material]
youngs_modulus = 70000.0
poisson_ratio = 0.33
[section]
depth = 10.0
thickness = 0.625
[ground]
name = "ground"
points = [[0.0, 0.0], [10.0, 0.0], [20.0, 0.0]]
[target]
body = "shuttle"
point = [10.0, 50.0]
[[flexures]]
name = "left"
bodies = ["ground", "shuttle"]
shape = "segment"
start = [0.0, 0.0]
end = [0.0, 50.0]
[[flexures]]
name = "middle"
bodies = ["ground", "shuttle"]
shape = "segment"
start = [10.0, 0.0]
end = [10.0, 50.0]
[[flexures]]
name = "right"
bodies = ["ground", "shuttle"]
shape = "segment"
start = [20.0, 0.0]
end = [20.0, 50.0]
[[load_cases]]
name = "lateral"
kind = "force"
angle_deg = 0.0
value = 5.0
"""


def test_the_command_says_which_leaves_and_exits_2(tmp_path, capsys):
    scene = tmp_path / "three_leaves.toml"
    scene.write_text(SCENE)
    out = tmp_path / "out"
    assert main(["run", str(scene), "--model", "prbm", "--out-dir", str(out)]) == 2
    err = capsys.readouterr().err
    assert "'left', 'middle', 'right'" in err and "beam:N or dcmm:N" in err
    assert "Traceback" not in err
    assert main(["run", str(scene), "--model", "beam:10", "--out-dir", str(out)]) == 0
