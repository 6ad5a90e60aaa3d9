"""Hostile input found by generating a few hundred bad and extreme inputs (issue #12):
each class below once ran long, crashed or was accepted silently; each now fails up front
with a message naming the field and the value (exit 2), over several values each."""

import pytest
from test_scene_errors import _base, _dump

from geometry import SceneError, load_scene
from geometry.loads import MAX_LOAD_SUBSTEPS
from reducedmodels.core import SolverSettings
from validation.cli import EXIT_INPUT, main


def test_the_level_cap_is_the_solvers_sub_step_cap():
    assert SolverSettings().max_substeps == MAX_LOAD_SUBSTEPS


@pytest.mark.parametrize("levels", [MAX_LOAD_SUBSTEPS + 1, 50_000, 100_000, 2**63])
def test_scene_levels_beyond_the_sub_step_cap_are_refused(tmp_path, levels):
    """``levels`` the solver cannot reach (one sub-step per increment at least) are refused
    while reading the scene, not after a long run ending in exit 3."""
    data = _base()
    data["load_cases"][0]["levels"] = levels
    path = tmp_path / "levels.toml"
    path.write_text(_dump(data))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    msg = str(info.value)
    assert "load_cases.m+.levels" in msg and str(levels) in msg, msg
    assert str(MAX_LOAD_SUBSTEPS) in msg


@pytest.mark.parametrize("levels", [2, 11, MAX_LOAD_SUBSTEPS])
def test_scene_levels_within_the_cap_are_accepted(tmp_path, levels):
    data = _base()
    data["load_cases"][0]["levels"] = levels
    path = tmp_path / "levels.toml"
    path.write_text(_dump(data))
    assert load_scene(path).load_cases[0].levels == levels
