"""Point scenes built from the base scene by replacing values equal the fully parsed ones.

The reference is the full build (:meth:`PointBuilder.build`: the base data with the values
written in, parsed and checked by the scene loader); the incremental build
(:meth:`PointBuilder.build_block`) must give the same scene bit for bit (every field, those
left out of comparisons included), the same digest, and for a refused point the same
reason, on every built-in sweep and on random points of every value field of every
built-in scene, refused values among them.
"""

import dataclasses
import math
import textwrap
from pathlib import Path

import numpy as np
import pytest

from flexval.geometry import BUILTIN_SCENES, SceneError
from flexval.geometry.scene import read_scene_data
from flexval.reducedmodels import LoadPath, parse_model
from flexval.validation.sweep import load_sweep
from flexval.validation.sweep.builtin import BUILTIN_SWEEPS
from flexval.validation.sweep.incremental import MIN_BOX_POINTS, edits_of
from flexval.validation.sweep.spec import Axis, PointBuilder, parse_sweep
from flexval.validation.sweep.tasks import run_model_block

BENCHMARK_SWEEPS = sorted((Path(__file__).parents[1] / "benchmarks" / "sweeps").glob("*.toml"))


def _bits(v):
    """Every bit of ``v``: all fields of a dataclass (compared or not), floats by their hex,
    arrays by dtype, shape and bytes, containers in order."""
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        fields = dataclasses.fields(v)
        return (type(v).__qualname__, tuple((f.name, _bits(getattr(v, f.name))) for f in fields))
    if isinstance(v, dict):
        return ("dict", tuple((k, _bits(x)) for k, x in v.items()))
    if isinstance(v, (list, tuple)):
        return (type(v).__name__, tuple(_bits(x) for x in v))
    if isinstance(v, (set, frozenset)):
        return ("set", tuple(sorted(map(repr, v))))
    if isinstance(v, np.ndarray):
        return ("array", v.dtype.str, v.shape, v.tobytes())
    if isinstance(v, float):
        return ("float", v.hex())
    if v is None or isinstance(v, (str, int, bool)):
        return (type(v).__name__, v)
    raise TypeError(f"no exact form for {type(v).__name__}")


def _same_points(builder: PointBuilder, indices: list[int], values: np.ndarray) -> np.ndarray:
    """Assert that the block build of the points equals their full builds; which of them
    the incremental build proved (and so built without a parse)."""
    inc = builder.incremental()
    proven = inc.proven(values) if inc is not None else np.zeros(len(indices), dtype=bool)
    got = builder.build_block(indices, values)
    for index, row, point in zip(indices, values.tolist(), got):
        want = builder.build(index, dict(zip((a.path for a in builder.axes), row)))
        assert point.digest == want.digest
        assert _bits(point.params) == _bits(want.params)
        assert point.reason == want.reason
        assert _bits(point.scene) == _bits(want.scene), f"point {index} {want.params}"
    return proven


@pytest.mark.parametrize("name", BUILTIN_SWEEPS + tuple(str(p) for p in BENCHMARK_SWEEPS))
def test_every_builtin_sweep_point_builds_as_the_full_parse(name):
    sweep = load_sweep(name)
    b = sweep.points.builder
    # a sweep of fewer points than a proven box holds: its points repeated
    positions = np.resize(np.arange(min(len(sweep.points), 300)), MIN_BOX_POINTS)
    if len(sweep.points) > MIN_BOX_POINTS:
        positions = np.arange(min(len(sweep.points), 300))
    proven = _same_points(b, positions.tolist(), b.values(positions))
    value_axes = edits_of(b.base, [a.path for a in b.axes]) is not None
    assert proven.all() == value_axes  # geometry axes (arc widths, notch heights) parse


def _value_paths(base: dict) -> list[str]:
    """Every value field of a scene's data (see flexval.validation.sweep.incremental)."""
    paths = ["section.thickness", "section.depth"]
    paths += ["material.youngs_modulus", "material.poisson_ratio"]
    for f in base["flexures"]:
        paths += [f"flexures.{f['name']}.thickness", f"flexures.{f['name']}.depth"]
    for c in base["load_cases"]:
        if "loads" in c:
            paths += [f"load_cases.{c['name']}.loads.{i}.value" for i in range(len(c["loads"]))]
        else:
            paths.append(f"load_cases.{c['name']}.value")
    return [p for p in paths if edits_of(base, [p]) is not None]


def _base_value(base: dict, path: str) -> float:
    """The value the base scene gives ``path`` (a flexure's own, else the section's)."""
    node = base
    for part in path.split("."):
        if isinstance(node, list):
            node = node[int(part)] if part.isdigit() else next(x for x in node if x["name"] == part)
        elif part in node:
            node = node[part]
        else:
            return float(base["section"][part])
    return float(node)


REFUSED = (-1.0, 0.0, 1e-320, 1e-200, 1e200, 60.0, math.nan)
"""Factors of a base value that the scene loader may refuse: a negative or zero value, a
subnormal one, magnitudes that underflow or overflow EI, a thickness past an arc's radius
or a Poisson ratio past 0.5, and a value that is not a number."""


@pytest.mark.parametrize("scene", BUILTIN_SCENES)
def test_random_value_points_build_as_the_full_parse(scene):
    """Three value fields of the scene drawn together, lognormal about their base values
    (sigma 0.05): every point valid and built without a parse, as the full parse builds it;
    then wider (sigma 0.2) and one point in five with a factor that may be refused: equal
    scenes, digests and refusal reasons, and no refused point proven valid."""
    base = read_scene_data(scene)[1]
    rng = np.random.default_rng(sum(map(ord, scene)))
    paths = _value_paths(base)
    assert len(paths) >= 4
    picked = [paths[k] for k in rng.choice(len(paths), size=3, replace=False)]
    axes = tuple(Axis(p, (), True, 0) for p in picked)
    b = PointBuilder(base, axes, "zip", f"<test {scene}>", scene, ("x",), None)
    n = 60
    factors = rng.lognormal(0.0, 0.05, size=(n, 3))  # 3 sigma: a Poisson ratio of 0.4
    values = factors * np.array([_base_value(base, p) for p in picked])
    assert _same_points(b, list(range(n)), values).all()
    factors = rng.lognormal(0.0, 0.2, size=(n, 3))
    odd = rng.random(n) < 0.2
    factors[odd, rng.integers(0, 3, odd.sum())] = rng.choice(REFUSED, odd.sum())
    values = factors * np.array([_base_value(base, p) for p in picked])
    proven = _same_points(b, list(range(n, 2 * n)), values)
    valid = [b.build(k, dict(zip(picked, row))).scene is not None for k, row in enumerate(values)]
    assert not np.any(proven & ~np.array(valid))
    assert not all(valid)


WIDE = """
name = "wide"
base = "open_chain"
models = ["dcmm:1"]
reference = "ee"
load_cases = ["f+"]

[[axes]]
path = "section.thickness"
sample = "normal"
mean = 0.1
std = 0.06
count = 400
seed = 3
"""


def test_a_negative_thickness_of_a_wide_draw_is_refused_with_the_parse_message(tmp_path):
    (tmp_path / "wide.toml").write_text(textwrap.dedent(WIDE), "utf-8")
    sweep = load_sweep(tmp_path / "wide.toml")
    b = sweep.points.builder
    positions = np.arange(len(sweep.points))
    values = b.values(positions)
    negative = values[:, 0] <= 0.0
    assert 5 <= negative.sum() <= 30  # the tail below zero
    proven = _same_points(b, positions.tolist(), values)
    assert not np.any(proven & negative)
    assert proven.sum() >= len(positions) - negative.sum() - 40  # the rest mostly unparsed
    reasons = {p.reason for p in b.build_block(positions.tolist(), values) if p.scene is None}
    assert reasons == {"section.thickness: must be positive"}


def test_a_refused_listed_value_stops_the_sweep_with_the_parse_message(tmp_path):
    data = {
        "base": "open_chain",
        "models": ["dcmm:1"],
        "reference": "ee",
        "axes": [{"path": "section.thickness", "values": [0.1, 0.12, 7.0, 0.2]}],
    }
    with pytest.raises(SceneError) as got:
        parse_sweep(data, "<listed>")
    b = PointBuilder(
        read_scene_data("open_chain")[1],
        (Axis("section.thickness", (0.1, 0.12, 7.0, 0.2), False),),
        "grid",
        "<listed>",
        "sweep",
        ("f+",),
        None,
    )
    with pytest.raises(SceneError) as want:
        b.build(2)
    assert str(got.value) == str(want.value)
    assert "2 r = 6 mm" in str(got.value)


def test_the_models_give_the_same_paths_bit_for_bit(tmp_path):
    """ee and dcmm:1 on the incremental scenes and on the parsed ones: the same load paths."""
    sweep = load_sweep(BENCHMARK_SWEEPS[0])
    b = sweep.points.builder
    positions = list(range(12))
    values = b.values(np.array(positions))
    fast = [p.scene for p in b.build_block(positions, values)]
    full = [b.build(k).scene for k in positions]
    for model in ("ee", "dcmm:1"):
        spec = parse_model(model)
        for a, c in zip(run_model_block(spec, fast, ("f+",)), run_model_block(spec, full, ("f+",))):
            assert isinstance(a[0], LoadPath)
            for name in ("load", "dx", "dy", "rotation"):
                assert (
                    np.asarray(getattr(a[0], name)).tobytes()
                    == np.asarray(getattr(c[0], name)).tobytes()
                )


def test_sweeps_of_other_base_values_do_not_share_a_builder():
    """Two bases differing in one value (E): each point takes its own sweep's."""
    base = read_scene_data("open_chain")[1]
    other = base | {"material": base["material"] | {"youngs_modulus": 3000.0}}
    axes = (Axis("section.thickness", (), True, 0),)
    values = np.full((10, 1), 0.11)
    got = [
        PointBuilder(data, axes, "zip", "<s>", "s", ("f+",), None).build_block(range(10), values)
        for data in (base, other)
    ]
    assert [p.scene.mechanism.material.youngs_modulus for p in got[0]] == [2100.0] * 10
    assert [p.scene.mechanism.material.youngs_modulus for p in got[1]] == [3000.0] * 10
