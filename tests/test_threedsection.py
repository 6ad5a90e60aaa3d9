"""The report's "2D idealisation against 3D" section, rendered from a threed.json document."""

from __future__ import annotations

import json

import pytest

from flexval.validation.report.threed import (
    THREED_FORMAT,
    position,
    read_threed,
    threed_section,
)


def _doc(code: str = "abc") -> dict:
    def end(d: float, rot: float) -> dict:
        return {"dx": d * 0.6, "dy": d * 0.8, "rot": rot}  # |d| = d

    case = {
        "threed": [
            {"model": "continuum:0[3d]", "level": 0, "failure": None, **end(1.04, 0.52)},
            {"model": "continuum:1[3d]", "level": 1, "failure": None, **end(1.03, 0.515)},
        ],
        "planes": {"stress": end(1.10, 0.55), "strain": end(0.98, 0.49)},
        "errors": {
            "continuum:1": {"end_disp_vec": 6.7, "end_rot": 6.6},
            "beam:100": {"end_disp_vec": 6.8, "end_rot": 6.7},
            "beam:100[plate]": {"end_disp_vec": 4.9, "end_rot": 4.8},
            "beam:100[width]": {"end_disp_vec": 0.4, "end_rot": 0.3},
        },
    }
    failed = {
        "threed": [{"model": "continuum:0[3d]", "level": 0, "failure": "stopped at 40 %"}],
        "planes": {"stress": end(1.0, 0.5), "strain": end(0.9, 0.45)},
        "errors": {},
    }
    return {
        "format": THREED_FORMAT,
        "code_version": code,
        "planes": {"stress": "continuum:1", "strain": "continuum:1[plane=strain]"},
        "scenes": {
            "open_chain": {
                "depth": 1.0,
                "thickness": 0.1,
                "searle": {"e12": 3.33},
                "cases": {"m+": case, "f-": failed},
            }
        },
    }


def test_position_between_the_idealisations():
    assert position(1.10, 1.10, 0.98) == 0.0
    assert position(0.98, 1.10, 0.98) == pytest.approx(1.0)
    assert position(1.04, 1.10, 0.98) == pytest.approx(0.5)
    assert position(1.2, 1.10, 0.98) < 0  # softer than plane stress: outside the bracket
    assert position(1.0, 1.0, 1.0) is None  # the idealisations coincide


def test_section_places_3d_and_names_the_closest_option(tmp_path):
    path = tmp_path / "threed.json"
    path.write_text(json.dumps(_doc()))
    text = "\n".join(threed_section(path, "open_chain", "abc"))
    # |d| 1.03 between 1.10 (stress) and 0.98 (strain): (1.03 - 1.10) / (0.98 - 1.10) = 0.58
    assert "| m+ | 1 | 1.03 | 0.971 | 1.1 | 0.98 | 0.58 | 0.58 | plane strain |" in text
    assert "failed: stopped at 40 %" in text
    assert "is itself 6.70–6.70 % from 3D" in text
    assert "lies 0.58–0.58 of the way" in text and "closer to plane strain on every case" in text
    assert "- `beam:100`: m+: `beam:100[width]`." in text
    assert "Stale" not in text


def test_stale_missing_and_foreign_files(tmp_path):
    path = tmp_path / "threed.json"
    path.write_text(json.dumps(_doc("old")))
    assert "**Stale:**" in "\n".join(threed_section(path, "open_chain", "new"))
    assert threed_section(path, "closed_chain", "new") == []  # a scene the file lacks
    missing = "\n".join(threed_section(tmp_path / "none.json", "open_chain", "new"))
    assert "does not exist" in missing and "threed_study.py" in missing
    assert "no `--threed` file" in "\n".join(threed_section(None, "open_chain", "new"))
    path.write_text(json.dumps({"format": "flexval-protocol/1"}))
    assert "is not a flexval-threed/1 file" in read_threed(path)[1]
    bad = _doc()
    del bad["scenes"]["open_chain"]["cases"]["m+"]["planes"]["strain"]
    path.write_text(json.dumps(bad))
    assert "malformed entry" in read_threed(path)[1]
