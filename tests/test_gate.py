"""``flexval gate``: verdicts, exit codes, the JUnit XML and JSON, the result cache, bad input.

The expected verdicts are computed here from the library's own error
function (:func:`flexval.validation.compare.errors`) on paths run directly
(:func:`flexval.validation.run.run_model`), never typed in. The reference is
``beam:100`` (fast) where the brief's acceptance run uses ``continuum:1``:
on the open chain's f+ case ``dcmm:1`` is about 15 % off either.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels import Family, SolverError, parse_model, register
from flexval.reducedmodels.catalogue import unregister
from flexval.validation.cli import main
from flexval.validation.compare import errors
from flexval.validation.run import run_model

pytestmark = pytest.mark.usefixtures("private_mesh_cache")

REFERENCE = "beam:100"
CASES = ("f+", "m+")


def _gates(tmp_path, dcmm_threshold: float, extra: str = "") -> str:
    path = tmp_path / "gates.toml"
    path.write_text(
        f'reference = "{REFERENCE}"\n'
        'scenes = ["open_chain"]\n'
        f"load_cases = {json.dumps(list(CASES))}\n"
        '[[gates]]\nmodel = "beam:20"\npath_disp = 1.0\n'
        f'[[gates]]\nmodel = "dcmm:1"\npath_disp = {dcmm_threshold}\n' + extra
    )
    return str(path)


@pytest.fixture(scope="module")
def expected() -> dict[tuple[str, str], float]:
    """{(model, case): path_disp error in percent} from the library's error function."""
    scene = load_scene("open_chain")
    out = {}
    for case in CASES:
        lc = scene.load_case(case)
        ref = run_model(scene, parse_model(REFERENCE), lc)
        for model in ("beam:20", "dcmm:1"):
            lp = run_model(scene, parse_model(model), lc)
            out[model, case] = errors(lp, ref, scene.mechanism.size())["path_disp"]
    return out


def _run(argv: list[str]) -> int:
    return main(["gate", *argv, "--workers", "1", "--quiet"])


def test_a_failing_gate_exits_1_with_one_failing_junit_case(tmp_path, expected, capsys):
    junit, record = tmp_path / "gate.xml", tmp_path / "gate.json"
    status = _run([_gates(tmp_path, 5.0), "--junit", str(junit), "--json", str(record)])
    thresholds = {"beam:20": 1.0, "dcmm:1": 5.0}
    failing = {k for k, v in expected.items() if v > thresholds[k[0]]}
    assert failing == {("dcmm:1", "f+")}  # the figures allow the brief's verdict
    assert status == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "3 passed, 1 failed" in out

    root = ET.parse(junit).getroot()
    assert root.tag == "testsuites"
    assert (root.get("tests"), root.get("failures")) == ("4", "1")
    cases = [(s, c) for s in root.findall("testsuite") for c in s.findall("testcase")]
    assert len(cases) == 4  # one per model x scene x case x metric
    for suite, case in cases:
        assert {"name", "classname", "time"} <= set(case.attrib)
        float(case.get("time"))
        assert {"name", "tests", "failures", "errors", "time"} <= set(suite.attrib)
    failed = [(s, c) for s, c in cases if c.find("failure") is not None]
    assert len(failed) == 1
    suite, case = failed[0]
    assert "dcmm:1" in suite.get("name") and case.get("name") == "open_chain f+ path_disp"
    assert f"{expected['dcmm:1', 'f+']:.4g}" in case.find("failure").get("message")
    assert all(
        c.find("failure") is None for s, c in cases if c.get("classname").endswith("beam:20")
    )

    data = json.loads(record.read_text())
    assert data["passed"] is False and data["reference"] == REFERENCE
    for row in data["results"]:
        assert row["value_percent"] == pytest.approx(expected[row["model"], row["case"]], rel=1e-12)
        assert row["passed"] == (row["value_percent"] <= row["threshold_percent"])


def test_gates_that_hold_exit_0(tmp_path, expected):
    assert max(expected.values()) < 20.0
    assert _run([_gates(tmp_path, 20.0)]) == 0


def test_a_warm_cache_serves_every_path(tmp_path):
    """``--prepare`` fills the cache folder; the gate then reads every path from it (each
    path's seconds are those of the run that filled it, bit for bit)."""
    cache = tmp_path / "ci-cache"
    gates = _gates(tmp_path, 20.0)
    assert _run([gates, "--prepare", "--cache", str(cache)]) == 0
    entries = sorted((cache / "results").iterdir())
    assert len(entries) == 3 * len(CASES)  # the reference and both models on every case
    first, second = tmp_path / "1.json", tmp_path / "2.json"
    assert _run([gates, "--cache", str(cache), "--json", str(first)]) == 0
    assert _run([gates, "--cache", str(cache), "--json", str(second)]) == 0
    assert sorted((cache / "results").iterdir()) == entries
    one, two = (json.loads(p.read_text())["results"] for p in (first, second))
    assert one == two


def test_a_model_that_cannot_reach_full_load_fails_its_gates(tmp_path, capsys):
    def run(*args, **kwargs):
        raise SolverError("no equilibrium beyond this load", 0.25)

    register(Family("gate-toy", "a model that stops at a quarter of the load", run))
    try:
        extra = '[[gates]]\nmodel = "gate-toy"\nend_rot = 50.0\n'
        record = tmp_path / "gate.json"
        assert _run([_gates(tmp_path, 20.0, extra), "--json", str(record)]) == 1
    finally:
        unregister("gate-toy")
    rows = [r for r in json.loads(record.read_text())["results"] if r["model"] == "gate-toy"]
    assert len(rows) == len(CASES)
    for row in rows:
        assert row["passed"] is False and row["value_percent"] is None
        assert "25 %" in row["reason"] and "no equilibrium" in row["reason"]


@pytest.mark.parametrize(
    "text, named",
    [
        ('reference = "beam:100"\nscenes = ["open_chain"]\ntolerance = 1\n', "'tolerance'"),
        (
            'reference = "beam:100"\nscenes = ["open_chain"]\n[[gates]]\nmodel = "beam:20"\n'
            "path_dsp = 1.0\n",
            "path_dsp",
        ),
        (
            'reference = "beam:100"\nscenes = ["open_chain"]\n[[gates]]\nmodel = "bem:20"\n'
            "path_disp = 1.0\n",
            "'bem:20'",
        ),
        (
            'reference = "beam:100"\nscenes = ["open_chain"]\n[[gates]]\nmodel = "beam:20"\n'
            "limit_load = 1.0\n",
            "not supported yet",
        ),
        (
            'reference = "beam:100"\nscenes = ["open_chain"]\n[[gates]]\nmodel = "beam:20"\n'
            "frequency = 1.0\n",
            "not supported yet",
        ),
        (
            'reference = "beam:100"\nscenes = ["open_chain"]\n[[gates]]\nmodel = "beam:20"\n'
            "path_disp = -1.0\n",
            "gates[0].path_disp",
        ),
        (
            'reference = "beam:100"\nscenes = ["open_chain"]\nload_cases = ["f+", "x"]\n'
            '[[gates]]\nmodel = "beam:20"\npath_disp = 1.0\n',
            "'x'",
        ),
        (
            'reference = "beam:100"\nscenes = ["no_such.toml"]\n[[gates]]\nmodel = "beam:20"\n'
            "path_disp = 1.0\n",
            "no_such.toml",
        ),
        ('reference = "beam:100"\nscenes = ["open_chain"]\n[[gates]]\nmodel = "beam:20"\n', "no"),
    ],
)
def test_bad_gates_files_exit_2_naming_the_field(tmp_path, capsys, text, named):
    path = tmp_path / "gates.toml"
    path.write_text(text)
    assert _run([str(path)]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err


def test_prepare_writes_no_verdict(tmp_path, capsys):
    assert _run([_gates(tmp_path, 5.0), "--prepare", "--junit", str(tmp_path / "x.xml")]) == 2
    assert "--prepare writes no verdict" in capsys.readouterr().err


def test_scene_files_are_found_relative_to_the_gates_file(tmp_path, capsys):
    from importlib import resources

    folder = tmp_path / "ci"
    folder.mkdir()
    text = resources.files("flexval.geometry").joinpath("scenes", "open_chain.toml").read_text()
    (folder / "mine.toml").write_text(text)
    (folder / "gates.toml").write_text(
        'reference = "beam:100"\nscenes = ["mine.toml"]\nload_cases = ["m+"]\n'
        '[[gates]]\nmodel = "beam:20"\nend_rot = 1.0\n'
    )
    assert _run([str(folder / "gates.toml")]) == 0
    assert "1 checks: 1 passed, 0 failed" in capsys.readouterr().out


def test_the_gates_reference_names_every_declared_field():
    from flexval.validation.gatefile import GATE, GATES, field_reference

    text = field_reference()
    for table in (GATES, GATE):
        for f in table.fields:
            assert f"`{f.name}`" in text
