"""The stiffness at the target (`flexval stiffness`) against closed forms.

* A straight cantilever's compliance at a point rigidly attached to its tip, by
  Castigliano's theorem on the Euler-Bernoulli energy (the bending moment along the
  leaf is linear in the load at the point, the normal force is its x part), computed
  here by quadrature, independently of the transport the code applies.
* A parallel leaf guide's sway stiffness 24 EI / L^3 at rest and, under a compression
  N per leaf, 2 EI lambda^3 sin(lambda) / (L^3 (2 - 2 cos(lambda) - lambda sin(lambda))),
  lambda = L sqrt(N / EI): a clamped-guided beam-column's lateral stiffness from the
  stability functions (Livesley and Chandler 1956), which vanishes at the sway load.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from builders import cantilever

from flexval.geometry import Segment, load_scene
from flexval.reducedmodels.analyses.modes import scaled_case
from flexval.reducedmodels.analyses.targetstiffness import target_stiffness
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.models import build_system
from flexval.validation.cli import main
from flexval.validation.studies.stiffness import run_stiffness

L, E, B, H = 10.0, 2100.0, 1.0, 0.1  # mm, MPa, mm, mm
OFFSET = (3.0, -2.0)  # the target point from the tip, mm
GUIDE = Path(__file__).parent / "scenes" / "leaf_guide.toml"


def _castigliano() -> np.ndarray:
    """C = int a a^T / EI ds + e1 e1^T L / EA, a(s) = d M(s) / d (Fx, Fy, M) at the point."""
    EI, EA = E * B * H**3 / 12.0, E * B * H
    px, py = L + OFFSET[0], OFFSET[1]
    s, w = np.polynomial.legendre.leggauss(8)  # the integrand is quadratic in s: exact
    s, w = 0.5 * L * (s + 1.0), 0.5 * L * w
    a = np.stack([-py * np.ones_like(s), px - s, np.ones_like(s)])
    compliance = (a * w) @ a.T / EI
    compliance[0, 0] += L / EA
    return compliance


@pytest.mark.parametrize(
    "model, rtol", [("beam:20", 1e-9), ("dcmm:1", 1e-9), ("ee", 1e-9), ("continuum:1", 5e-3)]
)
def test_a_cantilevers_compliance_at_an_offset_point_is_castiglianos(model, rtol):
    mech = cantilever(Segment((0.0, 0.0), (L, 0.0)), E=E, b=B, h=H, target_offset=OFFSET)
    system = build_system(mech, parse_model(model))
    rest = scaled_case(system, None, 0.0)
    found = target_stiffness(system, system.initial_state(), system.loads(rest), 0.0)
    exact = _castigliano()
    np.testing.assert_allclose(found.compliance, exact, rtol=rtol, atol=rtol * np.abs(exact).max())
    np.testing.assert_allclose(found.stiffness @ found.compliance, np.eye(3), atol=1e-8)
    np.testing.assert_allclose(found.point, [L + OFFSET[0], OFFSET[1]])
    assert found.stable in (True, None)


def _guided_pair(compression_per_leaf: float) -> float:
    """Two clamped-guided leaves' lateral stiffness under a compression each (N/mm)."""
    EI = 70000.0 * 10.0 * 0.625**3 / 12.0
    length = 50.0
    if compression_per_leaf == 0.0:
        return 24.0 * EI / length**3
    lam = length * math.sqrt(compression_per_leaf / EI)
    one = EI * lam**3 * math.sin(lam) / (length**3 * (2 - 2 * math.cos(lam) - lam * math.sin(lam)))
    return 2.0 * one


SWAY_LOAD = 112.46  # N, 2 pi^2 EI / L^2 of the guide


@pytest.mark.parametrize("model, base", [("beam:100", 4e-4), ("continuum:0", 1e-3)])
def test_a_leaf_guides_sway_stiffness_falls_with_its_preload_as_the_stability_functions(
    model, base
):
    """The guide of tests/scenes/leaf_guide.toml pushed along its leaves (150 N at full load,
    shared by the two): its sway stiffness (x, the shuttle's rotation held) at 0, 25, 50 and
    70 % of the push, the last 93 % of the way to the sway load. A stiffness that vanishes
    at the sway load magnifies any relative difference of the model's tangent (its
    discretisation, the leaves' shortening N L / EA the closed form leaves out) by
    1 / (1 - P / P_cr): the tolerance is ``base`` so magnified (measured: beam:100 2e-6,
    1.5e-4, 5.1e-4, 3.1e-3; continuum:0 9.7e-4 to 4.9e-3 at 25 to 70 %)."""
    scene = load_scene(str(GUIDE))
    case = scene.load_case("push")
    for fraction in (0.0, 0.25, 0.5, 0.7):
        _, found, _ = run_stiffness(scene, parse_model(model), case, fraction)
        push = 150.0 * fraction
        exact = _guided_pair(push / 2.0)
        rtol = base / (1.0 - push / SWAY_LOAD)
        assert found.stiffness[0, 0] == pytest.approx(exact, rel=rtol), fraction
        assert found.stable is not False


def test_the_command_prints_and_writes_the_matrices_and_refuses_bad_input(tmp_path, capsys):
    out = tmp_path / "k.json"
    argv = ["stiffness", str(GUIDE), "--model", "beam:20", "--load-case", "push", "--at", "0.5"]
    assert main([*argv, "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "stiffness of body shuttle" in text and "at 0.5 of push" in text and "compliance" in text
    record = json.loads(out.read_text())
    assert record["coordinates"] == ["dx", "dy", "rotation"] and record["at"] == 0.5
    k = np.array(record["stiffness"])
    np.testing.assert_allclose(k @ np.array(record["compliance"]), np.eye(3), atol=1e-8)
    assert record["units"]["stiffness"][2][2] == "N mm/rad"
    # past the sway load the loaded state cannot be reached by load control: exit 3
    assert main([*argv[:-2], "--at", "0.9"]) == 3
    assert "solver failure" in capsys.readouterr().err
    for bad, field in ((["--at", "0.5"], "--at"), (["--load-case", "push", "--at", "2"], "--at")):
        assert main(["stiffness", str(GUIDE), "--model", "beam:20", *bad]) == 2
        assert f"field '{field}'" in capsys.readouterr().err
    assert main(["stiffness", str(GUIDE), "--model", "ee", "--load-case", "push"]) == 0
    assert "linear: the same at every load" in capsys.readouterr().out


def test_a_model_rigid_at_the_target_says_so_instead_of_inverting(tmp_path, capsys):
    """prbm's links are inextensible: on tapered_leaf's stage, held by two straight leaves,
    it cannot move along the leaves nor turn (rigid links in a parallelogram); its compliance
    has those zero directions and the command names them, no infinite or NaN stiffness."""
    out = tmp_path / "k.json"
    assert main(["stiffness", "tapered_leaf", "--model", "prbm", "--json", str(out)]) == 0
    assert "no finite stiffness: prbm is rigid at the target along" in capsys.readouterr().out
    record = json.loads(out.read_text())
    assert record["stiffness"] is None and len(record["rigid_directions"]) >= 1
    compliance = np.array(record["compliance"])
    for direction in record["rigid_directions"]:
        moved = compliance @ np.array(direction)
        assert np.abs(moved).max() <= 1e-12 * np.abs(compliance).max()
    assert main(["stiffness", "tapered_leaf", "--model", "beam:20"]) == 0  # elastic leaves
    assert "Fx N" in capsys.readouterr().out
