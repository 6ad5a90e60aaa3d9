"""Report figures a designer shows: each path component on its own axis with its critical
points marked, deformed shapes magnified where the motion is too small to see."""

from pathlib import Path

import matplotlib.image
import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels import parse_model
from flexval.validation.report import figures
from flexval.validation.run import run_model

GUIDE = Path(__file__).parent / "scenes" / "leaf_guide.toml"


@pytest.mark.parametrize(
    "motion, size, scale",
    [(0.3, 50.0, 10.0), (5.0, 50.0, 1.0), (0.0, 50.0, 1.0), (1e-4, 25.0, 20000.0), (2.4, 50, 2.0)],
)
def test_the_deformation_scale_is_a_round_factor_that_makes_the_motion_visible(motion, size, scale):
    assert figures.deformation_scale(motion, size) == scale
    if scale > 1.0:  # drawn between half and the whole of the visible share
        drawn = scale * motion / size
        assert figures.VISIBLE_MOTION / 2.5 <= drawn <= figures.VISIBLE_MOTION


def test_the_load_path_figure_marks_where_a_path_bifurcates(tmp_path):
    scene = load_scene(str(GUIDE))
    case = scene.load_cases[0]
    paths = {}
    for model in ("beam:20", "ee"):
        try:
            paths[model] = run_model(scene, parse_model(model), case)
        except Exception as exc:  # beam:20 stops at the sway bifurcation: its path so far
            paths[model] = exc.path
    curves = figures.load_path_curves(paths)
    beam = next(c for c in curves if c["model"] == "beam:20")
    assert beam["bifurcations"] and set(beam) >= {"dx", "dy", "rotation"}
    png = tmp_path / "paths.png"
    figures.load_paths(scene, case.name, paths, png)
    height, width = matplotlib.image.imread(png).shape[:2]
    assert width > 2.5 * height  # three panels side by side
