"""Scene syntax of notch hinges, splines and tapers: good scenes build the right shapes and
sections, and every bad value is a SceneError naming its field and value (exit code 2)."""

import tomllib
from pathlib import Path

import numpy as np
import pytest
from test_scene_errors import _dump

from flexval.geometry import SceneError, load_scene
from flexval.geometry.profiles import LinearTaper, NotchProfile
from flexval.geometry.shapes import Segment, Spline
from flexval.validation.cli import main

SCENES = Path(__file__).parent / "scenes"
NOTCH = SCENES / "notch_hinge.toml"
SPLINE = SCENES / "spline_flexure.toml"


def _data(path: Path) -> dict:
    return tomllib.loads(path.read_text())


def _load(tmp_path, data: dict):
    path = tmp_path / "scene.toml"
    path.write_text(_dump(data))
    return load_scene(path)


def _refused(tmp_path, data: dict, field: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        _load(tmp_path, data)
    assert info.value.field == field, str(info.value)
    return info.value


def _edit_flexure(path: Path, **changes) -> dict:
    data = _data(path)
    flexure = data["flexures"][0]
    for key, value in changes.items():
        if value is None:
            flexure.pop(key, None)
        else:
            flexure[key] = value
    return data


def test_notch_scene_builds_a_segment_with_its_profile():
    flexure = load_scene(NOTCH).mechanism.flexures[0]
    assert flexure.shape == Segment((0.0, 0.0), (2.0, 0.0))
    assert flexure.section.thickness == 0.1 and flexure.section.depth == 5.0
    assert flexure.section.profile == NotchProfile("circular", 0.1, 1.0, 2.0)


def test_corner_filleted_height_defaults_to_t_plus_two_r(tmp_path):
    data = _edit_flexure(NOTCH, contour="corner-filleted", fillet_radius=0.3, height=None)
    profile = _load(tmp_path, data).mechanism.flexures[0].section.profile
    assert profile.height == pytest.approx(0.1 + 2 * 0.3) and profile.fillet_radius == 0.3
    data = _edit_flexure(NOTCH, contour="corner-filleted", fillet_radius=0.3, height=0.7)
    assert _load(tmp_path, data).mechanism.flexures[0].section.profile == profile


def test_power_notch_reads_its_exponent(tmp_path):
    data = _edit_flexure(NOTCH, contour="power", exponent=2.5)
    profile = _load(tmp_path, data).mechanism.flexures[0].section.profile
    assert profile.contour == "power" and profile.exponent == 2.5


def test_spline_scene_builds_a_spline_with_a_taper():
    flexure = load_scene(SPLINE).mechanism.flexures[0]
    points = _data(SPLINE)["flexures"][0]["points"]
    assert flexure.shape == Spline(tuple(map(tuple, points)))
    assert flexure.section.profile == LinearTaper(0.5, 0.3, flexure.shape.length)
    assert flexure.section.thickness == 0.3  # the smallest


def test_tapers_on_arcs_and_segments_and_an_even_taper_is_uniform(tmp_path):
    data = _data(SPLINE)
    data["flexures"][0] = {
        "name": "s",
        "bodies": ["ground", "tip"],
        "shape": "segment",
        "start": [0.0, 0.0],
        "end": [18.0, 2.0],
        "thickness": [0.3, 0.6],
    }
    section = _load(tmp_path, data).mechanism.flexures[0].section
    assert section.profile == LinearTaper(0.3, 0.6, float(np.hypot(18.0, 2.0)))
    data["flexures"][0]["thickness"] = [0.4, 0.4]
    section = _load(tmp_path, data).mechanism.flexures[0].section
    assert section.is_uniform and section.thickness == 0.4
    data["flexures"][0] = {
        "name": "s",
        "bodies": ["ground", "tip"],
        "center": [9.0, -6.0],
        "radius": float(np.hypot(9.0, 6.0)),
        "axis_deg": 90.0,
        "width_deg": 2 * float(np.degrees(np.arctan2(9.0, 6.0))),
        "thickness": [0.5, 0.2],
    }
    data["target"]["point"] = [18.0, 0.0]
    data["load_cases"][0]["point"] = [18.0, 0.0]
    flexure = _load(tmp_path, data).mechanism.flexures[0]
    assert flexure.shape.kind == "arc"
    assert flexure.section.profile == LinearTaper(0.5, 0.2, flexure.shape.length)


@pytest.mark.parametrize(
    ("changes", "field", "words"),
    [
        ({"thickness": 1.0}, "height", "smallest thickness"),  # t >= H
        ({"thickness": 1.2}, "height", "smallest thickness"),
        (
            {"contour": "corner-filleted", "fillet_radius": 1.5, "height": None},
            "fillet_radius",
            "L/2",
        ),
        (
            {"contour": "corner-filleted", "fillet_radius": 0.3, "height": 1.0},
            "height",
            "t + 2 r",
        ),
        ({"contour": "corner-filleted", "height": None}, "fillet_radius", "fillet radius"),
        ({"contour": "power", "exponent": 0.0}, "exponent", "positive"),
        ({"contour": "power", "exponent": -2.0}, "exponent", "positive"),
        ({"contour": "power"}, "exponent", "exponent"),
        ({"exponent": 2.0}, "exponent", "no exponent"),
        ({"fillet_radius": 0.2}, "fillet_radius", "no fillet radius"),
        ({"contour": "parabolic"}, "contour", "circular"),
        ({"contour": None}, "contour", "circular"),
        ({"height": None}, "height", "missing"),
        ({"thickness": [0.1, 0.2]}, "thickness", "a number"),
        ({"end": [0.0, 0.0]}, "end", "zero length"),
    ],
)
def test_bad_notch_values_name_their_field(tmp_path, changes, field, words):
    error = _refused(tmp_path, _edit_flexure(NOTCH, **changes), f"flexures.hinge.{field}")
    assert words in error.reason


@pytest.mark.parametrize(
    ("changes", "field", "words"),
    [
        ({"points": [[0.0, 0.0], [18.0, 2.0]]}, "points", "at least 3"),
        ({"points": [[0.0, 0.0], [9.0, 3.0], [9.0, 3.0], [18.0, 2.0]]}, "points[2]", "repeats"),
        (
            {"points": [[0.0, 0.0], [9.0, 3.0], [4.0, 6.0], [5.0, -2.0], [18.0, 2.0]]},
            "points",
            "crosses itself",
        ),
        (
            {"points": [[0.0, 0.0], [10.0, 4.0], [12.0, -3.0], [4.0, 1.5], [18.0, 2.0]]},
            "points",
            "crosses itself",
        ),
        ({"points": [[0.0, 0.0], [9.0, "x"], [18.0, 2.0]]}, "points[1][1]", "number"),
        ({"thickness": [0.5, 0.0]}, "thickness", "taper to zero"),
        ({"thickness": [-0.1, 0.3]}, "thickness", "negative"),
        ({"thickness": [0.5, 0.3, 0.2]}, "thickness", "[h_start, h_end]"),
        ({"thickness": 10.0}, "thickness", "radius of curvature"),
        ({"thickness": [0.3, 10.0]}, "thickness", "radius of curvature"),
    ],
)
def test_bad_spline_values_name_their_field(tmp_path, changes, field, words):
    error = _refused(tmp_path, _edit_flexure(SPLINE, **changes), f"flexures.s.{field}")
    assert words in error.reason or words in str(error.value)


def test_a_taper_thicker_than_the_arc_can_hold_is_refused(tmp_path):
    data = _data(SPLINE)
    data["flexures"][0] = {
        "name": "s",
        "bodies": ["ground", "tip"],
        "center": [9.0, -6.0],
        "radius": float(np.hypot(9.0, 6.0)),
        "axis_deg": 90.0,
        "width_deg": 2 * float(np.degrees(np.arctan2(9.0, 6.0))),
        "thickness": [0.5, 25.0],
    }
    error = _refused(tmp_path, data, "flexures.s.thickness")
    assert error.value == [0.5, 25.0] and "2 r" in error.reason


def test_bad_notch_is_exit_code_2_naming_the_field(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(_dump(_edit_flexure(NOTCH, thickness=1.5)))
    assert main(["run", str(path), "--model", "ee"]) == 2
    err = capsys.readouterr().err
    assert "flexures.hinge.height" in err and "Traceback" not in err


def test_prbm_of_a_spline_is_exit_code_2_naming_the_flexure(capsys):
    assert main(["run", str(SPLINE), "--model", "prbm"]) == 2
    err = capsys.readouterr().err
    assert "flexures.s" in err and "beam, dcmm or continuum" in err


def test_the_new_scenes_run_their_requested_models(capsys):
    assert main(["run", str(NOTCH)]) == 0
    assert main(["run", str(SPLINE)]) == 0
    out = capsys.readouterr().out
    assert "prbm" in out and "dcmm:4" in out


def test_info_describes_a_notch_by_its_law_and_compliance_stiffnesses(tmp_path, capsys):
    """flexval info: t, H and contour, and 1 / ∫ ds / EI against quad."""
    from scipy.integrate import quad

    out = tmp_path / "info.json"
    assert main(["info", str(NOTCH), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "circular notch, t = 0.1 mm at the middle, H = 1 mm at the ends" in text
    import json

    section = json.loads(out.read_text())["flexures"][0]["section"]
    profile = load_scene(NOTCH).mechanism.flexures[0].section.profile
    E, b = 70000.0, 5.0
    w = quad(lambda s: 12.0 / (E * b * float(profile.thickness(s)) ** 3), 0.0, 2.0, epsrel=1e-12)[0]
    assert section["rotational_stiffness_Nmm"] == pytest.approx(1.0 / w, rel=1e-10)
    assert section["contour"] == "circular" and section["height"] == 1.0


def test_plot_draws_the_true_outline(tmp_path):
    from flexval.validation.report.drawing import flexure_outline

    flexure = load_scene(NOTCH).mechanism.flexures[0]
    outline = flexure_outline(flexure)
    # the outline's half-width is h(x) / 2 along the straight axis
    profile = flexure.section.profile
    np.testing.assert_allclose(np.abs(outline[:, 1]), 0.5 * profile.thickness(outline[:, 0]))
    assert np.abs(outline[:, 1]).min() == pytest.approx(0.05)  # t / 2 at the middle
    png = tmp_path / "notch.png"
    assert main(["plot", str(NOTCH), "-o", str(png)]) == 0 and png.stat().st_size > 0


def test_opensees_peer_names_a_varying_section_instead_of_running():
    from flexval.validation.studies.peers import compare_with_opensees

    rows = compare_with_opensees(load_scene(NOTCH))
    assert [r.case for r in rows] == ["moment", "force"]
    assert all("uniform sections only" in r.reason and "'hinge'" in r.reason for r in rows)


def test_a_notch_too_thin_to_compute_with_is_refused_by_name(tmp_path):
    """t = 1e-110 mm is a normal number, but b t^3 / 12 underflows: the magnitude check
    of a varying section names the flexure and the quantity."""
    error = _refused(tmp_path, _edit_flexure(NOTCH, thickness=1e-110), "flexures.hinge")
    assert "second moment" in error.reason
