"""Slenderness and arc-angle extremes (small CI size of `flexval stress --sweeps`)."""

import pytest

from validation.sweeps import format_sweep, sweep


@pytest.fixture(scope="module")
def rows():
    return sweep([(120.0, 1 / 1000), (0.0, 1 / 30), (350.0, 1 / 30)],
                 ["beam:40", "dcmm:2", "prbm"])


def test_continuum_does_not_lock_when_very_slender(rows):
    # h/r = 1/1000: shear and thickness effects are O((h/r)^2) = 1e-6, so the continuum
    # must meet the thin-beam limit; a locking mesh would be orders of magnitude stiffer.
    # beam:40's own discretisation error is ~ (2.1/40)^2/24 ~ 1e-4: gate 0.2 %
    e = rows[0]["errors"]["beam:40"]
    assert e["disp"] < 0.2 and e["rot"] < 0.2


def test_straight_limit_and_nearly_closed_arc(rows):
    straight, closed = rows[1]["errors"], rows[2]
    assert straight["beam:40"]["disp"] < 0.5 and straight["prbm"]["disp"] < 2.0
    # 350 deg: the beam still follows the continuum, the table-bound PRBM refuses by name
    assert closed["errors"]["beam:40"]["disp"] < 1.0
    assert "outside the fitted range" in closed["failures"]["prbm"]
    text = format_sweep(rows, "t")
    assert "failed" in text and "350" in text
