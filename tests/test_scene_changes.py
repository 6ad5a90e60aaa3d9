"""Scene.with_changes: a scene's numbers changed in Python by the paths sweep axes use."""

import pytest

from flexval.geometry import SceneError, load_scene
from flexval.validation.cache import exact
from flexval.validation.sweep import load_sweep


def test_a_change_is_the_scene_a_sweep_point_builds(tmp_path):
    base = load_scene("open_chain")
    changed = base.with_changes({"section.thickness": 0.11, "flexures.e34.width_deg": 200})
    assert all(f.section.thickness == 0.11 for f in changed.mechanism.flexures)
    e34 = next(f for f in changed.mechanism.flexures if f.name == "e34")
    assert e34.shape.parameters()["width_deg"] == pytest.approx(200.0)
    assert base.mechanism.flexures[0].section.thickness == 0.1  # the base is untouched
    sweep_file = tmp_path / "s.toml"
    sweep_file.write_text(
        'name = "s"\nbase = "open_chain"\nmodels = ["ee"]\n'
        '[[axes]]\npath = "section.thickness"\nvalues = [0.11]\n'
        '[[axes]]\npath = "flexures.e34.width_deg"\nvalues = [200.0]\n'
    )
    point = load_sweep(sweep_file).points[0]
    assert exact(point.scene.mechanism) == exact(changed.mechanism)  # every bit
    assert exact(base.with_changes({}).mechanism) == exact(base.mechanism)


def test_a_filtered_scene_stays_filtered():
    only = load_scene("open_chain").with_load_cases(["f+"])
    assert [c.name for c in only.with_changes({"material.youngs_modulus": 2000.0}).load_cases] == [
        "f+"
    ]


@pytest.mark.parametrize(
    "changes, field, words",
    [
        ({"section.thicknes": 0.1}, "section.thicknes", "did you mean"),
        ({"flexures.e99.radius": 3.0}, "flexures.e99.radius", "no entry named 'e99'"),
        ({"section.thickness": "thin"}, "section.thickness", "must be a number"),
        ({"section.thickness": True}, "section.thickness", "must be a number"),
        ({"section.thickness": -0.1}, "thickness", ""),
        ({"name": 3.0}, "name", "not a number"),
    ],
)
def test_a_bad_change_names_the_field(changes, field, words):
    with pytest.raises(SceneError) as caught:
        load_scene("open_chain").with_changes(changes)
    text = str(caught.value)
    assert field in text and words in text


def test_a_run_json_reads_back_as_paths_arrays_and_a_frame(tmp_path):
    import numpy as np

    import flexval
    from flexval.validation.cli import main

    out = tmp_path / "run.json"
    argv = ["run", "open_chain", "--model", "dcmm:1", "--model", "ee", "--load-case", "f+"]
    assert main([*argv, "--json", str(out)]) == 0
    paths = flexval.read_results(out)
    assert [p.model for p in paths] == ["dcmm:1", "ee"]
    arrays = paths[0].arrays()
    assert arrays["load"].shape == (11,) and arrays["valid"].dtype == bool
    np.testing.assert_array_equal(arrays["displacement"], np.hypot(arrays["dx"], arrays["dy"]))
    frame = paths[1].to_dataframe()
    assert list(frame.columns[:2]) == ["model", "load_case"] and len(frame) == 11
    assert frame["rotation"].iloc[-1] == paths[1].rotation[-1]


def test_a_sweep_points_scene_keeps_no_data_and_says_so(tmp_path):
    """A sweep's point is its base with the axis values written in (built without a parse
    where the incremental build proves it): it changes by the sweep's axes, not by itself."""
    sweep_file = tmp_path / "s.toml"
    sweep_file.write_text(
        'name = "s"\nbase = "open_chain"\nmodels = ["ee"]\n'
        '[[axes]]\npath = "section.thickness"\nvalues = [0.11, 0.12]\n'
    )
    for point in load_sweep(sweep_file).points:
        assert point.scene.data is None
        with pytest.raises(SceneError, match="keeps no scene data"):
            point.scene.with_changes({"section.thickness": 0.2})
