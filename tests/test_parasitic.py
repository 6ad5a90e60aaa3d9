"""Parasitic motion, component by component (flexval.validation.studies.parasitic).

* The metric on load paths built by hand: a model that predicts no parasitic motion is
  100 % off, a reference component of round-off size is not scored, and which components
  are parasitic follows the load (across a force and the rotation; the translation under
  a moment; none for several loads).
* A model's parasitic motion against a closed form: a parallel leaf guide pushed across
  its leaves by delta shortens by (3/5) delta^2 / L (a clamped-guided leaf's arc-length
  conservation to the first order; Awtar, Slocum and Sevincer, J. Mech. Des. 2007,
  "Characteristics of beam-based flexure modules"): measured beam:100 0.066 % and
  continuum:0 0.002 % off at delta = L/300, and the sway itself within 0.1 % of
  F L^3 / (24 EI).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from flexval.geometry import Force, LoadCase, Moment, load_scene
from flexval.reducedmodels import LoadPath, parse_model
from flexval.validation.run import run_model
from flexval.validation.studies.parasitic import (
    ROUND_OFF_FLOOR,
    parasitic_components,
    parasitic_errors,
)

FORCE_X = LoadCase("push", (Force("t", np.zeros(2), 0.0, 1.0),), 3)


def _path(dx, dy, rotation, model="m") -> LoadPath:
    return LoadPath(model, "push", [0.0, 0.5, 1.0], list(dx), list(dy), list(rotation), 0.0)


def test_a_model_without_parasitic_motion_is_100_percent_off():
    ref = _path([0.0, 1.0, 2.0], [0.0, -0.001, -0.004], [0.0, 1e-5, 2e-5])
    rigid = _path([0.0, 1.0, 2.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    rows = {r["component"]: r for r in parasitic_errors(rigid, ref, FORCE_X, 10.0)}
    assert set(rows) == {"across", "rotation"}
    assert rows["across"]["end"] == pytest.approx(100.0) and rows["across"]["unit"] == "mm"
    assert rows["rotation"]["end"] == pytest.approx(100.0) and rows["rotation"]["unit"] == "rad"
    assert rows["across"]["path"] == pytest.approx(0.004)
    half = _path([0.0, 1.0, 2.0], [0.0, -0.0005, -0.002], [0.0, 1e-5, 3e-5])
    rows = {r["component"]: r for r in parasitic_errors(half, ref, FORCE_X, 10.0)}
    assert rows["across"]["end"] == pytest.approx(50.0)
    assert rows["rotation"]["end"] == pytest.approx(50.0)


def test_a_round_off_reference_component_is_not_scored():
    motion = 2.0  # mm: the reference's translation
    tiny = 0.1 * ROUND_OFF_FLOOR * motion
    ref = _path([0.0, 1.0, motion], [0.0, tiny, tiny], [0.0, 0.0, tiny / 10.0])
    other = _path([0.0, 1.0, motion], [0.0, 0.0, 3 * tiny], [0.0, 0.0, 0.0])
    for row in parasitic_errors(other, ref, FORCE_X, 10.0):
        assert not row["scored"] and row["end"] is None


def test_which_components_are_parasitic_follows_the_load():
    angle = math.radians(30.0)
    force = LoadCase("f", (Force("t", np.zeros(2), angle, 1.0),), 3)
    (name, across), (rotation, none) = parasitic_components(force)
    assert name == "across" and across @ [math.cos(angle), math.sin(angle)] == pytest.approx(0.0)
    assert rotation == "rotation" and none is None
    moment = LoadCase("m", (Moment("t", 1.0),), 3)
    assert [n for n, _ in parasitic_components(moment)] == ["dx", "dy"]
    both = LoadCase("b", (Moment("t", 1.0), Force("t", np.zeros(2), 0.0, 1.0)), 3)
    assert parasitic_components(both) == []


@pytest.mark.parametrize("model", ["beam:100", "continuum:0"])
def test_a_leaf_guide_shortens_by_three_fifths_of_its_sway_squared_over_its_length(tmp_path, model):
    guide = Path(__file__).parent / "scenes" / "leaf_guide.toml"
    length, ei = 50.0, 70000.0 * 10.0 * 0.625**3 / 12.0
    sway = length / 300.0  # mm
    force = 24.0 * ei / length**3 * sway  # N, across the leaves (x)
    text = guide.read_text().replace("angle_deg = -90.0", "angle_deg = 0.0")
    scene_file = tmp_path / "lateral.toml"
    scene_file.write_text(text.replace("value = 150.0", f"value = {force!r}"))
    scene = load_scene(str(scene_file))
    lp = run_model(scene, parse_model(model), scene.load_cases[0])
    assert lp.dx[-1] == pytest.approx(sway, rel=2e-3)
    assert lp.dy[-1] == pytest.approx(-0.6 * lp.dx[-1] ** 2 / length, rel=2e-3)
