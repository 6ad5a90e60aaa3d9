"""Scene input that could crash, hang or be silently ignored: each class is refused
with a SceneError naming the file and the field (CLI exit 2, no traceback), over
several values each."""

import math

import numpy as np
import pytest
from test_scene_errors import _base, _dump, _expect, _flex

from flexval.geometry import SceneError, load_scene
from flexval.geometry.magnitudes import SMALLEST_NORMAL, is_degenerate
from flexval.geometry.scene import parse_scene
from flexval.validation.cli import main

FOURBAR = {  # tests/test_joints.py's four-bar: a coupler arc between two pinned bodies
    "name": "fourbar",
    "material": {"youngs_modulus": 2200.0, "poisson_ratio": 0.35},
    "section": {"depth": 5.0, "thickness": 1.2},
    "ground": {"name": "g", "points": [[0.0, 0.0], [100.0, 0.0]]},
    "target": {"body": "a", "point": [10.0, 60.0]},
    "flexures": [
        {
            "name": "coupler",
            "bodies": ["a", "b"],
            "center": [50.0, 40.0],
            "radius": math.hypot(40.0, 20.0),
            "axis_deg": 90.0,
            "width_deg": 2 * math.degrees(math.atan2(40.0, 20.0)),
        }
    ],
    "pins": [
        {"name": "pa", "bodies": ["g", "a"], "point": [0.0, 0.0]},
        {"name": "pb", "bodies": ["b", "g"], "point": [100.0, 0.0]},
    ],
    "load_cases": [
        {"name": "fx", "kind": "force", "point": [10.0, 60.0], "angle_deg": 0.0, "value": 1.0}
    ],
}


def _fourbar():
    import copy

    return copy.deepcopy(FOURBAR)


def test_the_fourbar_base_is_valid(tmp_path):
    path = tmp_path / "ok.toml"
    path.write_text(_dump(_fourbar()))
    assert [p.name for p in load_scene(path).mechanism.pins] == ["pa", "pb"]


# --- encodings and structure -------------------------------------------------------------


@pytest.mark.parametrize(
    "encoding,hint",
    [
        ("latin-1", "Latin-1"),
        ("cp1252", "Latin-1"),
        ("utf-16", "UTF-16"),
        ("utf-16-be", None),
        ("utf-32", "UTF-32"),
    ],
)
def test_a_scene_file_that_is_not_utf8_is_refused(tmp_path, encoding, hint):
    d = _base()
    d["description"] = "Chaîne ouverte, modèle réduit"
    path = tmp_path / "enc.toml"
    path.write_bytes(_dump(d).encode(encoding))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert str(path) in str(info.value)
    assert info.value.field in ("encoding", "toml"), str(info.value)
    if hint is not None:
        assert hint in str(info.value)


def test_utf8_with_a_byte_order_mark_is_read(tmp_path):
    d = _base()
    d["description"] = "Chaîne ouverte"
    path = tmp_path / "bom.toml"
    path.write_bytes(_dump(d).encode("utf-8-sig"))
    assert load_scene(path).description == "Chaîne ouverte"


@pytest.mark.parametrize("depth", [400, 3000, 100_000])
@pytest.mark.parametrize("where", ["ground_points", "top"])
def test_arrays_nested_thousands_deep_are_a_scene_error(tmp_path, depth, where):
    text = _dump(_base())
    nested = "[" * depth + "]" * depth
    text = (
        text.replace('"points" = [[0.0, 0.0]]', f'"points" = {nested}')
        if where == "ground_points"
        else f"deep = {nested}\n" + text
    )
    path = tmp_path / "deep.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    # tomllib gives up beyond a few hundred levels; shallower nesting reaches the field checks
    assert str(path) in str(info.value)
    if depth >= 3000:
        assert info.value.field == "toml" and "nested too deeply" in str(info.value)


def test_cli_deep_nesting_exit_2_without_traceback(tmp_path, capsys):
    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "Traceback" not in err


# --- degenerate positive numbers ---------------------------------------------------------


@pytest.mark.parametrize(
    "value,expected",
    [
        (0.0, True),
        (1e-320, True),
        (-5e-324, True),
        (float("inf"), True),
        (float("nan"), True),
        (SMALLEST_NORMAL, False),
        (-1e300, False),
    ],
)
def test_is_degenerate(value, expected):
    assert is_degenerate(value) is expected


@pytest.mark.parametrize("thickness", [1e-110, 1e-104, 1e-200])
def test_a_thickness_whose_cube_underflows_is_refused(tmp_path, thickness):
    d = _base()
    d["section"]["thickness"] = thickness
    msg = _expect(tmp_path, d, "flexures.e12", "second moment I")
    assert "zero, subnormal or not finite" in msg


@pytest.mark.parametrize("field,value", [("youngs_modulus", 1e-320), ("youngs_modulus", 5e-324)])
def test_subnormal_inputs_are_refused(tmp_path, field, value):
    d = _base()
    d["material"][field] = value
    _expect(tmp_path, d, f"material.{field}", "subnormal")


@pytest.mark.parametrize("E", [1e-303, 1e-305, 1e-306])
def test_a_modulus_that_makes_ei_subnormal_is_refused(tmp_path, E):
    # h = 0.1 mm, b = 1 mm: I = 8.3e-5 mm^4, so EI or the compliance L / EI leaves the doubles
    d = _base()
    d["material"]["youngs_modulus"] = E
    msg = _expect(tmp_path, d, "flexures.e12")
    assert "bending stiffness EI" in msg or "compliance" in msg, msg


@pytest.mark.parametrize("depth", [1e-306, 1e-307])
def test_a_depth_that_makes_i_or_a_subnormal_is_refused(tmp_path, depth):
    # h = 0.1 mm: I = b h^3 / 12 = 8e-311 and 8e-312 mm^4, A = b h = 1e-307 (normal) and 1e-308
    d = _base()
    d["section"]["depth"] = depth
    msg = _expect(tmp_path, d, "flexures.e12", "zero, subnormal or not finite")
    assert f"b = {depth:g} mm" in msg


@pytest.mark.parametrize("radius", [1e-150, 1e-200])
def test_a_vanishing_arc_is_refused(tmp_path, radius):
    d = _base()
    _flex(d, "e23").update(radius=radius, thickness=radius / 10)
    path = tmp_path / "tiny.toml"
    path.write_text(_dump(d))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.field.startswith("flexures.e23"), str(info.value)


def test_cli_degenerate_number_exit_2(tmp_path, capsys):
    d = _base()
    d["section"]["thickness"] = 1e-110
    path = tmp_path / "tiny.toml"
    path.write_text(_dump(d))
    assert main(["run", str(path), "--model", "ee"]) == 2
    err = capsys.readouterr().err
    assert "flexures.e12" in err and "Traceback" not in err


# --- mechanisms that are not structures --------------------------------------------------


def _pins(*pins):
    """Pin tables from (name, two body letters, point) triples."""
    return [{"name": n, "bodies": list(b), "point": list(p)} for n, b, p in pins]


@pytest.mark.parametrize(
    "pins,moving",
    [
        # b pinned to a instead of the ground: a-b turn about pa
        (_pins(("pa", "ga", (0.0, 0.0)), ("pb", "ba", (100.0, 0.0))), "['a', 'b']"),
        # both pins at the same ground point: the coupler turns about it
        (_pins(("pa", "ga", (0.0, 0.0)), ("pb", "bg", (0.0, 0.0))), "['a', 'b']"),
    ],
)
def test_pins_that_leave_the_mechanism_mobile_are_refused(tmp_path, pins, moving):
    d = _fourbar()
    d["ground"]["points"] = [[0.0, 0.0]]
    d["pins"] = pins
    msg = _expect(tmp_path, d, "pins")
    assert f"{moving} can move" in msg


@pytest.mark.parametrize(
    "extra,named",
    [
        # the same body pinned twice to the ground at one point
        (("pa2", ["g", "a"], [0.0, 0.0]), "['pa', 'pa2']"),
        # the same body pinned to the ground at a second point: one constraint too many
        (("pa2", ["a", "g"], [100.0, 0.0]), "['pa', 'pa2']"),
    ],
)
def test_redundant_pins_are_refused_by_name(tmp_path, extra, named):
    d = _fourbar()
    name, bodies, point = extra
    d["pins"].append({"name": name, "bodies": bodies, "point": point})
    msg = _expect(tmp_path, d, "pins.pa2", "redundant pins")
    assert named in msg, msg


def test_a_four_bar_of_pins_only_is_mobile(tmp_path):
    # rigid a, b, c pinned in a parallelogram to the ground; d hangs on b by a flexure
    d = _fourbar()
    d["ground"]["points"] = [[0.0, 0.0], [100.0, 0.0]]
    d["pins"] = _pins(
        ("p1", "ga", (0.0, 0.0)),
        ("p2", "ab", (0.0, 50.0)),
        ("p3", "bc", (100.0, 50.0)),
        ("p4", "cg", (100.0, 0.0)),
    )
    d["flexures"] = [
        {
            "name": "f",
            "bodies": ["b", "d"],
            "center": [50.0, 60.0],
            "radius": 5.0,
            "axis_deg": 90.0,
            "width_deg": 90.0,
            "start_body": "b",
        }
    ]
    d["target"] = {"body": "d", "point": [50.0, 70.0]}
    d["load_cases"] = [{"name": "m", "kind": "moment", "body": "d", "value": 1.0}]
    msg = _expect(tmp_path, d, "pins", "can move")
    assert all(f"'{b}'" in msg.split("can move")[0] for b in "abcd"), msg


@pytest.mark.parametrize("model", ["ee", "dcmm:1", "prbm", "beam:4"])
def test_cli_redundant_pin_exit_2_for_every_model(tmp_path, capsys, model):
    d = _fourbar()
    d["pins"].append({"name": "twice", "bodies": ["g", "a"], "point": [0.0, 0.0]})
    path = tmp_path / "redundant.toml"
    path.write_text(_dump(d))
    assert main(["run", str(path), "--model", model]) == 2
    err = capsys.readouterr().err
    assert "redundant pins" in err and "Traceback" not in err


# --- scene entries accepted but ignored --------------------------------------------------


@pytest.mark.parametrize(
    "bodies,field,text",
    [
        ([{"name": "9", "points": [[1.0, 1.0]]}], "bodies.9", "no flexure or pin"),
        ([{"name": "4", "points": [[20.0, 15.8]]}], "bodies.4.points", "meets this point"),
        (
            [{"name": "2", "points": [[2.598, 4.5]]}, {"name": "2", "points": [[6.059, 6.5]]}],
            "bodies.name",
            "duplicate",
        ),
    ],
)
def test_body_entries_that_would_be_ignored_are_refused(tmp_path, bodies, field, text):
    d = _base()
    d["bodies"] = bodies
    _expect(tmp_path, d, field, text)


@pytest.mark.parametrize("point", [[5.0, 5.0], [1e3, -1e3], [0.0, 0.5]])
def test_ground_points_nothing_uses_are_refused(tmp_path, point):
    d = _base()
    d["ground"]["points"].append(point)
    _expect(tmp_path, d, "ground.points", "no flexure end or pin")


@pytest.mark.parametrize(
    "key,value", [("levels", 3), ("name", "inner"), ("loads", [{"kind": "moment", "value": 1e9}])]
)
def test_case_fields_inside_a_combined_load_component_are_refused(tmp_path, key, value):
    d = _base()
    d["load_cases"].append(
        {
            "name": "both",
            "loads": [
                {"kind": "moment", "value": 1e-3, key: value},
                {"kind": "force", "value": 1e-3, "angle_deg": 0.0},
            ],
        }
    )
    _expect(tmp_path, d, f"load_cases.both.loads[0].{key}", "unknown field")


@pytest.mark.parametrize("flexure,body", [("e12", "1")])
def test_a_start_body_leaving_the_ground_end_off_every_ground_point(tmp_path, flexure, body):
    d = _base()
    _flex(d, flexure)["start_body"] = body  # puts e12's far end on the ground
    _expect(tmp_path, d, f"flexures.{flexure}.start_body", "away from every ground point")


def test_a_start_body_on_a_closed_chain_ground_flexure(tmp_path):
    import copy
    import tomllib
    from importlib import resources

    text = resources.files("flexval.geometry").joinpath("scenes", "closed_chain.toml").read_text()
    d = tomllib.loads(text)
    for f in d["flexures"]:
        if "1" in f["bodies"]:
            bad = copy.deepcopy(d)
            mech = load_scene("closed_chain").mechanism
            right = next(g.start_body for g in mech.flexures if g.name == f["name"])
            other = next(b for b in f["bodies"] if b != right)
            next(g for g in bad["flexures"] if g["name"] == f["name"])["start_body"] = other
            _expect(tmp_path, bad, f"flexures.{f['name']}.start_body", "ground point")


# --- the scene name is a file-name stem --------------------------------------------------


@pytest.mark.parametrize(
    "name",
    [
        "../escaped",
        "a/b",
        "a\\b",
        "",
        "  ",
        "..",
        ".",
        "x\ty",
        "bell\u0007",
        "x" * 201,
        "c:drive",
        "q?",
    ],
)
def test_names_unsafe_as_a_file_stem_are_refused(name):
    d = _base()
    d["name"] = name
    with pytest.raises(SceneError) as info:
        parse_scene(d, "named.toml")
    assert info.value.field == "name" and "named.toml" in str(info.value)


@pytest.mark.parametrize("name", ["open chain v2", "chaîne-ouverte", "a.b", "x" * 200, "e_12+"])
def test_ordinary_names_are_kept(tmp_path, name):
    d = _base()
    d["name"] = name
    path = tmp_path / "ok.toml"
    path.write_text(_dump(d), encoding="utf-8")
    assert load_scene(path).name == name


def test_a_non_string_name_is_refused(tmp_path):
    d = _base()
    d["name"] = 12
    _expect(tmp_path, d, "name", "12")


def test_mechanism_size_does_not_change():
    mech = load_scene("closed_chain").mechanism
    pts = np.vstack([f.shape.end_points for f in mech.flexures] + [mech.target_point[None]])
    d = pts[:, None, :] - pts[None, :, :]
    assert mech.size() == float(np.sqrt((d**2).sum(axis=-1)).max())


# --- overlap check: the spatial index prunes nothing that can cross ------------------------


def _random_polylines(seed: int, n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    starts = rng.uniform(-20.0, 20.0, size=(n, 1, 2))
    return [
        s + np.cumsum(rng.normal(scale=1.5, size=(12, 2)), axis=0) for s in starts[:, 0][:, None]
    ]


@pytest.mark.parametrize("seed,n", [(0, 2), (1, 15), (2, 60), (3, 120)])
def test_candidate_pairs_are_exactly_the_overlapping_bounding_boxes(seed, n):
    from flexval.geometry.overlap import candidate_pairs

    lines = _random_polylines(seed, n)
    lo = [line.min(axis=0) for line in lines]
    hi = [line.max(axis=0) for line in lines]
    brute = [
        (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if np.all(lo[i] <= hi[j]) and np.all(lo[j] <= hi[i])
    ]
    assert candidate_pairs(lines) == brute


@pytest.mark.parametrize("seed", [4, 5, 6, 7])
def test_crossings_restricted_to_the_box_overlap_find_every_crossing(seed):
    from flexval.geometry.overlap import crossings

    def all_pairs(p, q):  # the test on every pair of segments, no pruning
        found = []
        for a, b in zip(p[:-1], p[1:]):
            for c, d in zip(q[:-1], q[1:]):
                r, s = b - a, d - c
                den = r[0] * s[1] - r[1] * s[0]
                if den == 0:
                    continue
                t = ((c - a)[0] * s[1] - (c - a)[1] * s[0]) / den
                u = ((c - a)[0] * r[1] - (c - a)[1] * r[0]) / den
                if 0 < t < 1 and 0 < u < 1:
                    found.append(a + t * r)
        return np.array(found).reshape(-1, 2)

    lines = _random_polylines(seed, 12)
    total = 0
    for i in range(len(lines)):
        for j in range(i + 1, len(lines)):
            expected = all_pairs(lines[i], lines[j])
            np.testing.assert_allclose(crossings(lines[i], lines[j]), expected, atol=1e-12)
            total += len(expected)
    assert total > 0  # the random walks do cross, so the comparison means something
