"""VTK time series of any model (``flexval run --vtu``) and ``flexval view``.

Independent answers: a cantilever leaf's root fibre stress from the beam formula
sigma = M h / (2 I) with M = F L (sign: the fibres on the concave side are compressed),
each flexure's drawn area against the integral of its thickness h(s) ds (a notch's too),
an arc's drawn centre line on its own circle, the bodies' drawn points against their
poses, and the series read back by PyVista's own readers.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import flexval
from flexval.geometry import load_scene
from flexval.geometry.kinematics import place_points
from flexval.validation.cli import main
from flexval.validation.series import flexure_strip, level_grid

pyvista = pytest.importorskip("pyvista")

SCENES = Path(__file__).parent / "scenes"

LEAF = """
name = "leaf"
description = "cantilever leaf, tip force across it"
[material]
youngs_modulus = 10000.0
poisson_ratio = 0.3
[section]
depth = 12.0
thickness = 1.0
[ground]
name = "g"
points = [[0.0, 0.0]]
[target]
body = "tip"
point = [100.0, 0.0]
[[flexures]]
name = "leaf"
bodies = ["g", "tip"]
shape = "segment"
start = [0.0, 0.0]
end = [100.0, 0.0]
[[load_cases]]
name = "up"
kind = "force"
body = "tip"
point = [100.0, 0.0]
angle_deg = 90.0
value = 0.01
"""
# E I = 10000 * 12 * 1 / 12 = 10000 N mm^2, I = 1 mm^4: the root moment F L = 1 N mm gives
# 0.5 MPa on either face; the tip moves 1/3 mm (linear to within 1e-4 of the length)
ROOT_STRESS = 0.01 * 100.0 * 0.5 / 1.0

FAMILIES = ["beam:20", "dcmm:4", "ee", "prbm", "continuum:0"]


@pytest.fixture(scope="module")
def leaf(tmp_path_factory):
    path = tmp_path_factory.mktemp("leaf") / "leaf.toml"
    path.write_text(LEAF)
    return load_scene(str(path))


def _traced(scene, model: str, case: str):
    return flexval.run_model(scene, model, case, record_poses=True, record_shapes=True)


@pytest.mark.parametrize("model", FAMILIES)
def test_root_fibre_stress_is_the_beam_formula_with_its_sign(leaf, model):
    """Bent up (counterclockwise), the leaf's upper (left) face is compressed at the root."""
    lp = _traced(leaf, model, "up")
    flexure = leaf.mechanism.flexures[0]
    strip = flexure_strip(flexure, lp.shapes["leaf"], len(lp.load) - 1, lp.section_forces["leaf"])
    m = len(strip["stress"]) // 2
    left, right = strip["stress"][0], strip["stress"][m]
    # the models' own section forces at the root: statics of the tip force on the displaced
    # leaf (within the 1e-3 its shortening and the continuum's resultants allow)
    assert left == pytest.approx(-ROOT_STRESS, rel=2e-3)
    assert right == pytest.approx(ROOT_STRESS, rel=2e-3)
    # and zero at the free end, where the moment vanishes
    assert abs(strip["stress"][m - 1]) < 2e-3 * ROOT_STRESS


@pytest.mark.parametrize("model", ["beam:20", "dcmm:2", "prbm", "ee", "continuum:0"])
def test_a_notch_is_drawn_with_its_true_thickness(model):
    scene = load_scene(str(SCENES / "notch_hinge.toml"))
    lp = _traced(scene, model, "moment")
    flexure = scene.mechanism.flexures[0]
    strip = flexure_strip(flexure, lp.shapes["hinge"], 0, lp.section_forces["hinge"])
    m = len(strip["stress"]) // 2
    polygon = np.vstack([strip["rest"][:m], strip["rest"][m:][::-1]])
    x, y = polygon.T
    drawn = 0.5 * abs(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1)))
    s = np.linspace(0.0, flexure.shape.length, 20001)
    exact = np.trapezoid(flexure.section.thickness_at(s), s)
    assert drawn == pytest.approx(exact, rel=2e-3)
    # level 0 is the rest state: nothing moved
    assert np.abs(strip["points"] - strip["rest"]).max() < 1e-9


@pytest.mark.parametrize("model", ["beam:6", "dcmm:2", "ee", "continuum:0"])
def test_an_arc_drawn_from_a_few_chords_stays_on_its_circle(model):
    scene = load_scene("open_chain")
    lp = _traced(scene, model, "f+")
    for flexure in scene.mechanism.flexures:
        strip = flexure_strip(flexure, lp.shapes[flexure.name], 0)
        m = len(strip["stress"]) // 2
        centre, radius = flexure.shape.center, flexure.shape.radius
        h = flexure.section.thickness
        for face in (strip["rest"][:m], strip["rest"][m:]):
            distance = np.hypot(*(face - centre).T)
            assert np.allclose(np.abs(distance - radius), 0.5 * h, atol=1e-9 * radius), flexure.name


@pytest.mark.parametrize("model", FAMILIES)
def test_bodies_follow_their_poses_and_the_target_its_path(leaf, model):
    lp = _traced(leaf, model, "up")
    grid = level_grid(leaf, lp, len(lp.load) - 1)
    parts = list(grid.field_data["parts"])
    tip = grid.extract_cells(np.flatnonzero(grid.cell_data["part"] == parts.index("tip")))
    body = leaf.mechanism.bodies["tip"]
    placed = place_points(np.asarray(lp.poses["tip"][-1]), body.points - body.reference)
    assert np.allclose(tip.points[:, :2], placed, atol=1e-12)
    assert np.allclose(tip.point_data["displacement"][0, :2], [lp.dx[-1], lp.dy[-1]], atol=1e-12)
    assert set(grid.cell_data["rigid"][grid.cell_data["part"] == parts.index("leaf")]) == {0}
    for name in ("displacement", "fibre_stress"):
        assert np.isfinite(grid.point_data[name]).all()


def test_the_linear_response_records_its_own_linear_poses(leaf):
    """ee's poses are q0 + lambda dq: the rotation is the path's, growing linearly."""
    lp = _traced(leaf, "ee", "up")
    turns = np.array([pose[2] for pose in lp.poses["tip"]])
    assert np.allclose(turns, lp.rotation, rtol=0, atol=1e-15)
    factors = np.asarray(lp.load) / lp.load[-1]
    assert np.allclose(turns, factors * turns[-1], rtol=1e-12, atol=0)
    moments = np.array(lp.section_forces["leaf"]["moment"])
    assert np.allclose(moments, factors[:, None] * moments[-1], rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("model", ["beam:10", "dcmm:3", "ee", "prbm", "continuum:0"])
def test_run_writes_a_series_pyvista_reads_for_every_family(tmp_path, model):
    out = tmp_path / "vtk"
    status = main(
        ["run", "notch_fourbar", "--model", model, "--load-case", "f+", "--vtu", str(out)]
    )
    assert status == 0
    pvd = out / f"notch_fourbar_f+_{model.replace(':', '')}.pvd"
    reader = pyvista.get_reader(str(pvd))
    assert len(reader.time_values) == 11
    reader.set_active_time_value(reader.time_values[-1])
    last = reader.read()[0]
    scene = load_scene("notch_fourbar")
    names = [f.name for f in scene.mechanism.flexures] + list(scene.mechanism.bodies)
    assert list(last.field_data["parts"]) == names
    assert float(last.field_data["load"][0]) == pytest.approx(5.0)
    assert np.isfinite(last.point_data["fibre_stress"]).all()
    # the fibre stress drawn reaches the path's own peak stress (MPa), not more
    lp = _traced(scene, model, "f+")
    peak = max(v[-1] for v in lp.peak_stress.values())
    assert np.abs(last.point_data["fibre_stress"]).max() == pytest.approx(peak, rel=5e-3)
    assert pyvista.read(pvd) is not None


def test_a_stopped_path_leaves_the_levels_it_reached(tmp_path, capsys):
    """Past the Euler load, load control stops (exit 3); the series holds the levels reached."""
    out = tmp_path / "vtk"
    status = main(
        ["run", str(SCENES / "euler_column.toml"), "--model", "beam:10", "--vtu", str(out)]
    )
    assert status == 3
    reader = pyvista.get_reader(str(out / "euler_column_P_beam10.pvd"))
    assert 1 < len(reader.time_values) < 11


def test_vtu_refused_with_dynamic(tmp_path, capsys):
    status = main(
        ["run", "notch_fourbar", "--dynamic", "--duration", "0.01", "--vtu", str(tmp_path)]
    )
    assert status == 2
    assert "--vtu" in capsys.readouterr().err


def test_view_renders_a_level_off_screen_and_refuses_bad_input(tmp_path, capsys, monkeypatch):
    out = tmp_path / "vtk"
    assert (
        main(["run", "notch_fourbar", "--model", "prbm", "--load-case", "f+", "--vtu", str(out)])
        == 0
    )
    pvd = out / "notch_fourbar_f+_prbm.pvd"
    png = tmp_path / "level.png"
    assert main(["view", str(pvd), "--screenshot", str(png), "--level", "5"]) == 0
    from PIL import Image

    with Image.open(png) as picture:
        assert picture.size == (1200, 900)
        assert len(np.unique(np.asarray(picture.convert("L")))) > 10  # something was drawn
    capsys.readouterr()
    bad = [
        ([str(tmp_path / "none.pvd"), "--screenshot", str(png)], "no such file"),
        ([str(pvd), "--screenshot", str(png), "--level", "11"], "--level"),
        ([str(pvd), "--screenshot", str(png), "--field", "von_mises"], "--field"),
        ([str(pvd), "--screenshot", str(tmp_path / "x.jpg")], "--screenshot"),
        ([str(png), "--screenshot", str(png)], "RESULT"),
    ]
    for args, named in bad:
        assert main(["view", *args]) == 2, args
        assert named in capsys.readouterr().err
    (out / "notch_fourbar_f+_prbm" / "level_003.vtu").write_text("damaged")
    assert main(["view", str(pvd), "--screenshot", str(png)]) == 2
    err = capsys.readouterr().err
    assert "level 3" in err and "Traceback" not in err
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    assert main(["view", str(pvd)]) == 2
    assert "no display" in capsys.readouterr().err


def test_view_warps_the_continuum_field_file(tmp_path):
    """The continuum's own field file (its reference mesh) is drawn warped by its
    displacement."""
    from flexval.validation.view import prepared, read_levels

    scene = load_scene("notch_fourbar")
    flexval.run_model(scene, "continuum:0", "f+", vtu_dir=tmp_path)
    (found,) = sorted(tmp_path.glob("*.vtu"))
    (grid,) = read_levels(found)
    shown = prepared(grid, "von_mises")
    moved = shown.points - grid.points
    assert np.allclose(moved, grid.point_data["displacement"])
    assert math.isclose(np.abs(moved).max(), np.abs(grid.point_data["displacement"]).max())
