"""The discussion's verdict on the fine beam against the continuum is computed, not assumed."""

from __future__ import annotations

from types import SimpleNamespace

from flexval.validation.report.data import PAPER_REFERENCE
from flexval.validation.report.discussion import SMALL_GAP, _reference_bullet


def _scene(name: str, gap: float):
    """A scene's results whose fine beam differs from the continuum by ``gap`` percent."""
    errors = {"f+": {"path_disp": gap, "path_rot": 0.5 * gap}}
    return SimpleNamespace(
        scene=SimpleNamespace(name=name, mechanism=SimpleNamespace(flexures=())),
        cases=["f+"],
        reference="continuum:1",
        has_reference=lambda: True,
        error_table=lambda ref: {PAPER_REFERENCE: errors},
    )


def _bullet(*scenes) -> str:
    data = SimpleNamespace(scenes=list(scenes), reference="continuum:1")
    (line,) = _reference_bullet(data)
    return line


def test_a_small_gap_everywhere_is_called_small():
    text = _bullet(_scene("a", 0.2), _scene("b", 0.9 * SMALL_GAP))
    assert "is small" in text and "not small" not in text


def test_a_scene_beyond_the_small_gap_is_named_with_its_gap():
    text = _bullet(_scene("a", 0.2), _scene("notches", 6.5))
    assert "is not small on notches (up to 6.5 %)" in text
    assert "a (up to" not in text
