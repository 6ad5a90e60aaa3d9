"""The generated references cover what the parsers really accept.

The scene and sweep file references are rendered from the field declarations
the parsers read, and the CLI reference from the argument parser. These tests
hold the declarations to the parsers' real behaviour: every declared field is
accepted where it is declared, an undeclared one is refused, the refusal lists
exactly the declared fields, and the rendered Markdown names every field,
command and option.
"""

from __future__ import annotations

import ast
import copy
import tomllib
from importlib import resources

import pytest

from flexval.geometry import SceneError
from flexval.geometry.scene import field_reference, parse_scene
from flexval.geometry.scenefields import SCENE_TABLES
from flexval.validation.cli.reference import cli_reference, commands
from flexval.validation.sweep.fields import AXES, SWEEP
from flexval.validation.sweep.fields import field_reference as sweep_reference
from flexval.validation.sweep.spec import parse_sweep

UNDECLARED = "not_a_declared_field"


def _open_chain() -> dict:
    text = resources.files("flexval.geometry").joinpath("scenes", "open_chain.toml").read_text()
    return tomllib.loads(text)


def _table(data: dict, path: str, variant: str | None) -> dict:
    """The table of ``data`` at ``path`` (an entry, for an array of tables), created if absent."""
    if path == "":
        return data
    if path in ("material", "section", "ground", "target"):
        return data[path]
    if path == "request":
        return data.setdefault("request", {})
    if path == "gravity":
        return data.setdefault("gravity", {"acceleration": [0.0, -9810.0]})
    if path == "flexures":
        return data["flexures"][0]
    if path == "bodies":
        data["bodies"] = [{"name": "2"}]
        return data["bodies"][0]
    if path == "pins":
        data["pins"] = [{"name": "p", "bodies": ["1", "2"], "point": [0.0, 0.0]}]
        return data["pins"][0]
    if path == "load_cases" and variant == "combined":
        data["load_cases"][0] = {"name": "m+", "loads": [{"kind": "moment", "value": 1e-3}]}
        return data["load_cases"][0]
    if path == "load_cases":
        return data["load_cases"][0]
    if path == "measurements":
        data["measurements"] = [{"load_case": "m+", "file": "probe.csv"}]
        return data["measurements"][0]
    if path == "load_cases.loads":
        data["load_cases"][0] = {"name": "m+", "loads": [{"kind": "moment", "value": 1e-3}]}
        return data["load_cases"][0]["loads"][0]
    raise AssertionError(f"no probe for scene table {path!r}: add one to _table")


def _variants(table) -> list[str | None]:
    """The variants the parser tells apart by their known fields (None: all alike)."""
    if table.path == "load_cases":
        return ["single", "combined"]
    return [None]


SCENE_PROBES = [(t, v) for t in SCENE_TABLES for v in _variants(t)]


def _expected_list(exc: SceneError) -> set[str]:
    """The field names an 'unknown field' error lists."""
    assert exc.reason.startswith("unknown field; expected one of "), exc.reason
    return set(ast.literal_eval(exc.reason.removeprefix("unknown field; expected one of ")))


@pytest.mark.parametrize(
    "table,variant", SCENE_PROBES, ids=[f"{t.path or 'top'}-{v}" for t, v in SCENE_PROBES]
)
def test_the_scene_parser_accepts_exactly_the_declared_fields(table, variant):
    base = _open_chain()
    parse_scene(copy.deepcopy(base), "<base>")
    data = copy.deepcopy(base)
    target = _table(data, table.path, variant)
    target[UNDECLARED] = 1.0
    with pytest.raises(SceneError) as info:
        parse_scene(data, "<probe>")
    assert info.value.field.endswith(UNDECLARED), info.value
    assert _expected_list(info.value) == set(table.keys(variant))

    for name in sorted(table.keys(variant)):
        data = copy.deepcopy(base)
        target = _table(data, table.path, variant)
        target.setdefault(name, "probe")
        try:
            parse_scene(data, "<probe>")
        except SceneError as exc:
            assert not exc.reason.startswith("unknown field"), (name, exc)


def test_every_scene_table_has_a_probe():
    paths = {t.path for t in SCENE_TABLES}
    assert {"", "material", "flexures", "load_cases", "load_cases.loads"} <= paths
    for table in SCENE_TABLES:
        _table(_open_chain(), table.path, None)


def test_the_scene_reference_names_every_declared_field():
    text = field_reference()
    for table in SCENE_TABLES:
        if table.path:
            assert f"`{table.heading}`" in text
        for f in table.fields:
            assert f"| `{f.name}` |" in text, (table.path, f.name)
    for name in ("youngs_modulus", "width_deg", "axis_deg", "angle_deg", "density", "t1"):
        assert f"`{name}`" in text


def _sweep() -> dict:
    return {
        "base": "open_chain",
        "models": ["ee"],
        "load_cases": ["m+"],
        "axes": [{"path": "section.thickness", "values": [0.1]}],
    }


@pytest.mark.parametrize("table", [SWEEP, AXES], ids=["top", "axes"])
def test_the_sweep_parser_accepts_exactly_the_declared_fields(table):
    base = _sweep()
    parse_sweep(copy.deepcopy(base), "<base>")

    def target(data):
        return data if table is SWEEP else data["axes"][0]

    data = copy.deepcopy(base)
    target(data)[UNDECLARED] = 1.0
    with pytest.raises(SceneError) as info:
        parse_sweep(data, "<probe>")
    assert info.value.field.endswith(UNDECLARED), info.value
    assert _expected_list(info.value) == set(table.keys())

    for name in sorted(table.keys()):
        data = copy.deepcopy(base)
        target(data).setdefault(name, "probe")
        try:
            parse_sweep(data, "<probe>")
        except SceneError as exc:
            assert not exc.reason.startswith("unknown field"), (name, exc)


def test_the_sweep_reference_names_every_declared_field():
    text = sweep_reference()
    for table in (SWEEP, AXES):
        for f in table.fields:
            assert f"| `{f.name}` |" in text, (table.path, f.name)


def test_the_cli_reference_names_every_command_and_option():
    text = cli_reference()
    cmds = commands()
    assert {"run", "sweep", "modes", "report", "converge", "info"} <= set(cmds)
    for name, parser in cmds.items():
        assert f"## `flexval {name}`" in text
        for action in parser._actions:
            for option in action.option_strings:
                if option not in ("-h", "--help"):
                    assert f"`{option}`" in text, (name, option)
