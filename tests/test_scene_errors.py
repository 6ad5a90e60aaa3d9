"""Every kind of bad scene input gives a SceneError naming the file, the field
and the value; the CLI turns it into exit code 2 with no traceback."""

import tomllib
from importlib import resources

import pytest

from flexval.geometry import SceneError, load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.cli import main


def _base() -> dict:
    text = resources.files("flexval.geometry").joinpath("scenes", "open_chain.toml").read_text()
    return tomllib.loads(text)


def _dump(data: dict) -> str:
    """Minimal TOML writer for the scene layout (tables, arrays of tables, scalars)."""

    def val(v):
        if isinstance(v, str):
            return '"' + v + '"'
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float):
            if v != v:
                return "nan"
            if v in (float("inf"), float("-inf")):
                return "inf" if v > 0 else "-inf"
            return repr(v)
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f'"{k}" = {val(x)}' for k, x in v.items()) + "}"
        return repr(v)

    out = [
        f'"{k}" = {val(v)}'
        for k, v in data.items()
        if not isinstance(v, (dict, list))
        or (isinstance(v, list) and not (v and isinstance(v[0], dict)))
    ]
    for k, v in data.items():
        if isinstance(v, dict):
            out.append(f"[{k}]")
            out += [f'"{kk}" = {val(x)}' for kk, x in v.items()]
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for item in v:
                out.append(f"[[{k}]]")
                out += [f'"{kk}" = {val(x)}' for kk, x in item.items()]
    return "\n".join(out) + "\n"


def _expect(tmp_path, data, field, value_text=None):
    path = tmp_path / "bad.toml"
    path.write_text(_dump(data))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    msg = str(info.value)
    assert str(path) in msg
    assert f"'{field}'" in msg, msg
    if value_text is not None:
        assert value_text in msg, msg
    return msg


def test_writer_round_trips_the_builtin_scene(tmp_path):
    path = tmp_path / "ok.toml"
    path.write_text(_dump(_base()))
    assert len(load_scene(path).mechanism.flexures) == 3


def _flex(data, name):
    return next(f for f in data["flexures"] if f["name"] == name)


@pytest.mark.parametrize("field,value", [("radius", 0.0), ("radius", -1.0)])
def test_non_positive_radius(tmp_path, field, value):
    d = _base()
    _flex(d, "e23")[field] = value
    _expect(tmp_path, d, f"flexures.e23.{field}", repr(value))


def test_non_positive_thickness(tmp_path):
    d = _base()
    d["section"]["thickness"] = 0.0
    _expect(tmp_path, d, "section.thickness", "0.0")


def test_non_positive_modulus(tmp_path):
    d = _base()
    d["material"]["youngs_modulus"] = -2100.0
    _expect(tmp_path, d, "material.youngs_modulus", "-2100.0")


def test_thickness_not_below_diameter(tmp_path):
    d = _base()
    _flex(d, "e34")["thickness"] = 5.0  # r = 2.5
    _expect(tmp_path, d, "flexures.e34.thickness", "5.0")


@pytest.mark.parametrize("width", [0.0, 360.0, -10.0, 400.0])
def test_width_outside_open_interval(tmp_path, width):
    d = _base()
    _flex(d, "e12")["width_deg"] = width
    _expect(tmp_path, d, "flexures.e12.width_deg", repr(width))


@pytest.mark.parametrize("nu", [-1.0, 0.5, 0.7])
def test_poisson_outside_range(tmp_path, nu):
    d = _base()
    d["material"]["poisson_ratio"] = nu
    _expect(tmp_path, d, "material.poisson_ratio", repr(nu))


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), 1e300])
def test_nan_inf_absurd(tmp_path, bad):
    d = _base()
    _flex(d, "e12")["center"] = [0.0, bad]
    _expect(tmp_path, d, "flexures.e12.center[1]")
    d = _base()
    d["load_cases"][0]["value"] = bad
    _expect(tmp_path, d, "load_cases.m+.value")


def test_dangling_body(tmp_path):
    d = _base()
    d["flexures"].append(
        {
            "name": "e45",
            "bodies": ["4", "5"],
            "center": [22.0, 18.0],
            "radius": 1.0,
            "axis_deg": 0.0,
            "width_deg": 90.0,
        }
    )
    _expect(tmp_path, d, "flexures", "'5'")


def test_unconnected_body(tmp_path):
    d = _base()
    # e23 now joins 5 and 3: bodies 3, 4, 5 are no longer reachable from the ground
    _flex(d, "e23")["bodies"] = ["5", "3"]
    _expect(tmp_path, d, "flexures")


def test_flexure_end_meets_no_ground_point(tmp_path):
    d = _base()
    d["ground"]["points"] = [[1.0, 1.0]]
    _expect(tmp_path, d, "flexures.e12", "e12")


def test_no_ground(tmp_path):
    d = _base()
    del d["ground"]
    _expect(tmp_path, d, "ground")
    d = _base()
    d["ground"]["name"] = "0"
    _expect(tmp_path, d, "ground", "'0'")


def test_target_on_unknown_body(tmp_path):
    d = _base()
    d["target"]["body"] = "9"
    _expect(tmp_path, d, "target.body", "'9'")


def test_load_on_unknown_body(tmp_path):
    d = _base()
    d["load_cases"][0]["body"] = "7"
    _expect(tmp_path, d, "load_cases.m+.body", "'7'")


def test_duplicate_names(tmp_path):
    d = _base()
    _flex(d, "e23")["name"] = "e12"
    _expect(tmp_path, d, "flexures.name", "'e12'")
    d = _base()
    d["load_cases"][1]["name"] = "m+"
    _expect(tmp_path, d, "load_cases.name", "'m+'")


def test_unknown_field_and_wrong_type(tmp_path):
    d = _base()
    _flex(d, "e12")["radiu"] = 3.0
    _expect(tmp_path, d, "flexures.e12.radiu")
    d = _base()
    _flex(d, "e12")["radius"] = "three"
    _expect(tmp_path, d, "flexures.e12.radius", "'three'")


def test_malformed_toml_and_missing_file(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("name = \n[[flexures]\n")
    with pytest.raises(SceneError, match="toml"):
        load_scene(path)
    with pytest.raises(SceneError, match="no such file"):
        load_scene(tmp_path / "nothing.toml")


@pytest.mark.parametrize("text", ["beam", "beam:0", "dcmm:x", "prbm:3", "fem", "continuum:99"])
def test_bad_model_names(text):
    if text == "beam":
        assert parse_model(text).id == "beam:20"
        return
    with pytest.raises(SceneError, match="model"):
        parse_model(text)


def test_cli_exit_code_2_without_traceback(tmp_path, capsys):
    d = _base()
    d["material"]["youngs_modulus"] = 0.0
    path = tmp_path / "bad.toml"
    path.write_text(_dump(d))
    out_json = tmp_path / "out.json"
    assert main(["run", str(path), "--model", "dcmm:1", "--json", str(out_json)]) == 2
    err = capsys.readouterr().err
    assert "material.youngs_modulus" in err and "Traceback" not in err
    assert not out_json.exists()
    assert main(["info", str(tmp_path / "missing.toml")]) == 2
    assert main(["run", "open_chain", "--model", "beam:-3"]) == 2
    assert main(["run", "open_chain", "--model", "ee", "--load-case", "nope"]) == 2


def test_crossing_flexures_are_impossible_geometry(tmp_path):
    d = _base()
    # a half circle ending on link 2 at (2.598, 4.5) that swings left through e12's top
    d["flexures"].append(
        {
            "name": "ex",
            "bodies": ["2", "5"],
            "center": [2.598, 6.5],
            "radius": 2.0,
            "axis_deg": 180.0,
            "width_deg": 180.0,
            "start_body": "5",
        }
    )
    d["load_cases"].append({"name": "m5", "kind": "moment", "body": "5", "value": 1e-3})
    _expect(tmp_path, d, "flexures.ex", "crosses flexure")


def test_arc_closing_on_itself(tmp_path):
    d = _base()
    _flex(d, "e34")["width_deg"] = 358.0  # ends 0.087 mm apart < h = 0.1 mm
    _expect(tmp_path, d, "flexures.e34.width_deg", "closes on itself")


def test_crossings_finds_a_proper_crossing_only():
    import numpy as np

    from flexval.geometry.overlap import crossings

    p = np.array([[0.0, 0.0], [2.0, 2.0]])
    q = np.array([[0.0, 2.0], [2.0, 0.0]])
    np.testing.assert_allclose(crossings(p, q), [[1.0, 1.0]])
    assert len(crossings(p, q + [5.0, 0.0])) == 0  # disjoint
    assert len(crossings(p, p + [0.0, 1.0])) == 0  # parallel


# --- errors that name the real mistake --------------------------------------------------


def _as_segment(f: dict, shape: str | None = "segment") -> dict:
    """Flexure ``f`` turned into a straight one from its arc's first to its second end
    (``shape`` left out if None)."""
    for key in ("center", "radius", "axis_deg", "width_deg"):
        f.pop(key)
    f.update(start=[0.0, 0.0], end=[4.0, 4.0])
    if shape is not None:
        f["shape"] = shape
    return f


@pytest.mark.parametrize(
    "edit, field, words",
    [
        # start/end without shape: the default arc would miss its centre
        (lambda f: _as_segment(f, None), "flexures.e12.shape", "'start' and 'end' belong to a"),
        (
            lambda f: _as_segment(f, None).update(contour="circular", height=0.3),
            "flexures.e12.shape",
            'give shape = "notch"',
        ),
        (
            lambda f: (
                [f.pop(k) for k in ("center", "radius", "axis_deg", "width_deg")]
                and f.update(points=[[0.0, 0.0], [2.0, 1.0], [4.0, 0.0]])
            ),
            "flexures.e12.shape",
            'give shape = "spline"',
        ),
        # a field of another shape on an explicit shape, or on a complete arc
        (lambda f: _as_segment(f).update(radius=3.0), "flexures.e12.radius", "belongs to an arc"),
        (lambda f: _as_segment(f).update(contour="circular"), "flexures.e12.contour", "a notch"),
        (lambda f: _as_segment(f).update(height=0.3), "flexures.e12.height", "not to a segment"),
        (lambda f: f.update(contour="elliptical"), "flexures.e12.contour", "not to an arc"),
        (lambda f: f.update(start=[0.0, 0.0]), "flexures.e12.start", "gives no shape"),
        (
            lambda f: _as_segment(f).update(points=[[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]]),
            "flexures.e12.points",
            'shape = "spline"',
        ),
        # misspellings name the nearest known name
        (lambda f: f.update(raduis=3.0), "flexures.e12.raduis", "did you mean 'radius'?"),
        (lambda f: f.update(shape="segmnet"), "flexures.e12.shape", "did you mean 'segment'?"),
        (lambda f: f.update(widthdeg=240.0), "flexures.e12.widthdeg", "'width_deg'?"),
    ],
)
def test_flexure_fields_in_the_wrong_place_name_the_mistake(tmp_path, edit, field, words):
    d = _base()
    edit(_flex(d, "e12"))
    msg = _expect(tmp_path, d, field)
    assert words in msg, msg
    assert "'flexures.e12.center' = None" not in msg


def test_start_end_without_shape_is_not_a_missing_centre(tmp_path):
    """The error names the missing shape and its value, not the arc's centre it lacks."""
    d = _base()
    _as_segment(_flex(d, "e12"), None)
    msg = _expect(tmp_path, d, "flexures.e12.shape", "= None")
    assert 'shape = "segment"' in msg and 'shape = "notch"' in msg, msg
    _flex(d, "e12")["shape"] = "segment"  # the fix the message names is accepted
    path = tmp_path / "fixed.toml"
    path.write_text(_dump(d))
    assert load_scene(path).mechanism.flexures[0].shape.kind == "segment"


@pytest.mark.parametrize(
    "case, edit, field, words",
    [
        (0, lambda c: c.update(kind="momnet"), "load_cases.m+.kind", "did you mean 'moment'?"),
        (2, lambda c: c.update(kind="froce"), "load_cases.f+.kind", "did you mean 'force'?"),
        (2, lambda c: c.pop("kind"), "load_cases.f+.kind", "point and angle_deg belong to a force"),
        (2, lambda c: c.pop("angle_deg"), "load_cases.f+.angle_deg", "a force needs its direction"),
        (
            2,
            lambda c: c.pop("point") and c.update(body="3"),
            "load_cases.f+.point",
            "a force on body '3' needs its point of application",
        ),
        (0, lambda c: c.update(point=[1.0, 2.0]), "load_cases.m+.point", "a moment has no point"),
        (0, lambda c: c.update(vlaue=1.0), "load_cases.m+.vlaue", "did you mean 'value'?"),
    ],
)
def test_load_fields_in_the_wrong_place_name_the_mistake(tmp_path, case, edit, field, words):
    d = _base()
    edit(d["load_cases"][case])
    msg = _expect(tmp_path, d, field)
    assert words in msg, msg


def test_a_force_without_point_on_the_target_body_acts_at_the_target_point(tmp_path):
    """The documented default stays: a force on the target body without ``point``."""
    d = _base()
    d["load_cases"][2].pop("point")
    path = tmp_path / "ok.toml"
    path.write_text(_dump(d))
    force = load_scene(path).load_case("f+").components[0]
    assert list(force.point) == [20.0, 15.8]


def test_a_misspelt_table_names_the_nearest(tmp_path):
    d = _base()
    d["gravity"] = {"acceleraton": [0.0, -9810.0]}
    _expect(tmp_path, d, "gravity.acceleraton", "did you mean 'acceleration'?")
    d = _base()
    d["materail"] = d.pop("material")
    _expect(tmp_path, d, "materail", "did you mean 'material'?")


def test_cli_names_the_missing_shape_with_exit_2(tmp_path, capsys):
    d = _base()
    _as_segment(_flex(d, "e23"), None)
    path = tmp_path / "bad.toml"
    path.write_text(_dump(d))
    assert main(["run", str(path), "--model", "dcmm:1"]) == 2
    err = capsys.readouterr().err
    assert "field 'flexures.e23.shape' = None" in err and "'start' and 'end'" in err, err
    assert "Traceback" not in err
