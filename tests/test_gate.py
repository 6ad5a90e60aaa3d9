"""``flexval gate``: verdicts, exit codes, the JUnit XML and JSON, the result cache, bad input.

The expected verdicts are computed here from the library's own error
function (:func:`flexval.validation.studies.compare.errors`) on paths run directly
(:func:`flexval.validation.run.run_model`), never typed in; those of
``limit_load`` from the report's limit-load and bifurcation tables
(:func:`flexval.validation.studies.campaign.run_campaign`,
:func:`flexval.validation.report.strength.limit_load_data` and ``bifurcation_data``), and
those of ``frequency`` from the report's natural-frequency table
(:func:`flexval.validation.report.frequencies.frequency_data`). The reference is
``beam:100`` (fast) where the brief's acceptance run uses ``continuum:1``:
on the open chain's f+ case ``dcmm:1`` is about 15 % off either.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels import Family, SolverError, parse_model, register
from flexval.reducedmodels.catalogue import unregister
from flexval.validation.cli import main
from flexval.validation.run import run_model
from flexval.validation.studies.compare import errors

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
            "limit_load = 1.0\nmodes = 3\n",
            "gates[0].modes",
        ),
        (
            'reference = "beam:100"\nscenes = ["open_chain"]\n[[gates]]\nmodel = "beam:20"\n'
            "frequency = 1.0\nmodes = 0\n",
            "gates[0].modes",
        ),
        (
            'reference = "beam:100"\nscenes = ["open_chain"]\n[[gates]]\nmodel = "beam:20"\n'
            "frequency = -1.0\n",
            "gates[0].frequency",
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
    from flexval.validation.studies.gatefile import GATE, GATES, field_reference

    text = field_reference()
    for table in (GATES, GATE):
        for f in table.fields:
            assert f"`{f.name}`" in text


# --- limit_load ----------------------------------------------------------------------------
SCENES = Path(__file__).parent / "scenes"
LIMIT_SCENES = ("euler_column", "deep_arch")  # a bifurcation point; a limit point


def _first_critical(limits: dict, bifurcations: dict, model: str, case: str) -> float | None:
    """The smaller of a model's limit load and first bifurcation load in the report's tables."""
    loads = [t[model][case]["load"] for t in (limits, bifurcations) if case in t.get(model, {})]
    return min(loads) if loads else None


@pytest.fixture(scope="module")
def limit_expected() -> dict[str, tuple[float, float | None, float | None]]:
    """{scene: (beam:10's limit_load error %, beam:10's, ee's first critical load)} from
    the report's limit-load and bifurcation tables."""
    from flexval.validation.report.strength import bifurcation_data, limit_load_data
    from flexval.validation.studies.campaign import run_campaign

    models = [REFERENCE, "beam:10", "ee"]
    out = {}
    for name in LIMIT_SCENES:
        scene = load_scene(SCENES / f"{name}.toml")
        paths, failures = run_campaign(
            scene, [parse_model(m) for m in models], scene.load_cases, 1, None
        )
        limits = limit_load_data(failures, REFERENCE)
        bifurcations = bifurcation_data(paths, models, ["P"], REFERENCE)
        ref = _first_critical(limits, bifurcations, REFERENCE, "P")
        own = _first_critical(limits, bifurcations, "beam:10", "P")
        table = limits if "P" in limits.get("beam:10", {}) else bifurcations
        assert abs(table["beam:10"]["P"]["error_percent"]) == pytest.approx(
            100 * abs(own - ref) / ref, rel=1e-12
        )  # one kind of critical point each: the report's own error
        out[name] = (
            100 * abs(own - ref) / ref,
            own,
            _first_critical(limits, bifurcations, "ee", "P"),
        )
    return out


def _limit_gates(tmp_path, threshold: float) -> str:
    path = tmp_path / "limits.toml"
    scenes = [str(SCENES / f"{n}.toml") for n in LIMIT_SCENES]
    path.write_text(
        f'reference = "{REFERENCE}"\nscenes = {json.dumps(scenes)}\n'
        f'[[gates]]\nmodel = "beam:10"\nlimit_load = {threshold}\n'
        '[[gates]]\nmodel = "ee"\nlimit_load = 50.0\n'
    )
    return str(path)


def test_limit_load_gates_compare_the_reports_first_critical_loads(tmp_path, limit_expected):
    worst = max(e for e, _, _ in limit_expected.values())
    best = min(e for e, _, _ in limit_expected.values())
    threshold = (worst + best) / 2  # fails on one scene, holds on the other
    record, junit = tmp_path / "limits.json", tmp_path / "limits.xml"
    argv = [_limit_gates(tmp_path, threshold), "--json", str(record), "--junit", str(junit)]
    assert _run(argv) == 1
    rows = json.loads(record.read_text())["results"]
    assert [(r["model"], r["scene"], r["metric"]) for r in rows] == [
        (m, s, "limit_load") for m in ("beam:10", "ee") for s in LIMIT_SCENES
    ]
    for row in rows[:2]:
        error, own, _ = limit_expected[row["scene"]]
        assert row["value_percent"] == pytest.approx(error, rel=1e-12)
        assert row["passed"] == (error <= threshold)
        assert f"{own:.5g} N" in row["detail"]
    for row in rows[2:]:  # the linear ee has none, the reference has one: fails, saying so
        assert limit_expected[row["scene"]][2] is None
        assert row["passed"] is False and row["value_percent"] is None
        assert "ee: no critical load within 1 times the load" in row["reason"]
    assert {r["scene"] for r in rows[:2] if not r["passed"]} == {
        n for n, (e, _, _) in limit_expected.items() if e > threshold
    }
    cases = {c.get("classname") + " " + c.get("name"): c for c in ET.parse(junit).iter("testcase")}
    arch = cases["flexval.gate.beam:10 deep_arch P limit_load"]
    assert "limit point" in arch.find("system-out").text
    column = cases["flexval.gate.beam:10 euler_column P limit_load"]
    assert "bifurcation point" in column.find("system-out").text

    assert _run([_limit_gates(tmp_path, 1.01 * worst), "--json", str(record)]) == 1
    rows = json.loads(record.read_text())["results"]
    assert all(r["passed"] for r in rows if r["model"] == "beam:10")


def test_a_limit_load_gate_without_critical_loads_passes_saying_so(tmp_path, capsys):
    from flexval.validation.report.strength import bifurcation_data, limit_load_data
    from flexval.validation.studies.campaign import run_campaign

    scene = load_scene("open_chain")
    models = [REFERENCE, "beam:20"]
    paths, failures = run_campaign(
        scene, [parse_model(m) for m in models], [scene.load_case("f+")], 1, None
    )
    assert not limit_load_data(failures, REFERENCE)
    assert not bifurcation_data(paths, models, ["f+"], REFERENCE)
    path, junit = tmp_path / "g.toml", tmp_path / "g.xml"
    path.write_text(
        f'reference = "{REFERENCE}"\nscenes = ["open_chain"]\nload_cases = ["f+"]\n'
        '[[gates]]\nmodel = "beam:20"\nlimit_load = 0.0\n'
    )
    assert _run([str(path), "--junit", str(junit)]) == 0
    text = f"no critical load within 1 times the load ({scene.load_case('f+').magnitude:.5g} N)"
    assert text in capsys.readouterr().out
    (case,) = ET.parse(junit).iter("testcase")
    assert case.find("failure") is None and text in case.find("system-out").text


# --- frequency -----------------------------------------------------------------------------
STEEL = 7.85e-9  # t/mm^3


def _dense_open_chain(folder) -> str:
    """The open chain renamed, with a flexure density of its own (material.density)."""
    from importlib import resources

    text = resources.files("flexval.geometry").joinpath("scenes", "open_chain.toml").read_text()
    text = text.replace('name = "open_chain"', 'name = "steel_chain"', 1)
    text = text.replace("[material]\n", f"[material]\ndensity = {STEEL!r}\n", 1)
    (folder / "steel_chain.toml").write_text(text)
    return "steel_chain.toml"


@pytest.fixture(scope="module")
def frequency_expected(tmp_path_factory) -> dict[tuple[str, int], tuple[float, int]]:
    """{(scene, modes): (dcmm:1's worst mode error in percent, its mode number)} from the
    report's natural-frequency table (modes = 4, its count) and from the same analysis
    with 2 modes."""
    from flexval.validation.report.frequencies import (
        DEFAULT_DENSITY,
        MODE_COUNT,
        frequency_data,
        lowest_frequencies,
        mode_errors,
    )
    from flexval.validation.studies.modes import choose_density

    folder = tmp_path_factory.mktemp("scenes")
    out = {}
    for scene in (load_scene("open_chain"), load_scene(folder / _dense_open_chain(folder))):
        errs = frequency_data(scene, ["dcmm:1"], REFERENCE).errors["dcmm:1"]
        k = max(range(MODE_COUNT), key=lambda j: abs(errs[j]))
        out[scene.name, MODE_COUNT] = (abs(errs[k]), k + 1)
        massive, _ = choose_density(scene, None, DEFAULT_DENSITY)
        two = [lowest_frequencies(massive, parse_model(m), 2) for m in ("dcmm:1", REFERENCE)]
        errs = mode_errors(*two)
        k = max(range(2), key=lambda j: abs(errs[j]))
        out[scene.name, 2] = (abs(errs[k]), k + 1)
    return out


def _frequency_gates(tmp_path, threshold: float, modes: int = 4) -> str:
    scene = _dense_open_chain(tmp_path)
    path = tmp_path / "modes.toml"
    path.write_text(
        f'reference = "{REFERENCE}"\nscenes = ["open_chain", "{scene}"]\n'
        f'[[gates]]\nmodel = "dcmm:1"\nfrequency = {threshold}\nmodes = {modes}\n'
    )
    return str(path)


def test_frequency_gates_compare_the_reports_natural_frequencies(tmp_path, frequency_expected):
    four = {s: v for (s, n), v in frequency_expected.items() if n == 4}
    threshold = sum(e for e, _ in four.values()) / 2
    assert min(e for e, _ in four.values()) < threshold < max(e for e, _ in four.values())
    record, junit = tmp_path / "modes.json", tmp_path / "modes.xml"
    argv = [_frequency_gates(tmp_path, threshold), "--json", str(record), "--junit", str(junit)]
    assert _run(argv) == 1
    rows = json.loads(record.read_text())["results"]
    assert [(r["scene"], r["case"], r["metric"]) for r in rows] == [
        ("open_chain", "rest", "frequency"),
        ("steel_chain", "rest", "frequency"),
    ]
    for row in rows:
        error, mode = four[row["scene"]]
        assert row["value_percent"] == pytest.approx(error, rel=1e-12)
        assert row["passed"] == (error <= threshold)
        assert f"mode {mode} of 4" in row["detail"]
    cases = {c.get("name"): c for c in ET.parse(junit).iter("testcase")}
    assert "PLA" in cases["open_chain rest frequency"].find("system-out").text
    steel = cases["steel_chain rest frequency"].find("system-out").text
    assert f"the scene's flexure density {STEEL:g}" in steel

    assert _run([_frequency_gates(tmp_path, 1.01 * max(e for e, _ in four.values()))]) == 0


def test_a_frequency_gate_compares_the_lowest_modes_it_names(tmp_path, frequency_expected):
    two = {s: v for (s, n), v in frequency_expected.items() if n == 2}
    record = tmp_path / "two.json"
    worst = max(e for e, _ in two.values())
    assert _run([_frequency_gates(tmp_path, 1.01 * worst, 2), "--json", str(record)]) == 0
    for row in json.loads(record.read_text())["results"]:
        error, mode = two[row["scene"]]
        assert row["value_percent"] == pytest.approx(error, rel=1e-9)
        assert f"mode {mode} of 2" in row["detail"]
    assert _run([_frequency_gates(tmp_path, 0.99 * worst, 2)]) == 1


def test_prepare_caches_critical_loads_and_frequencies(tmp_path, monkeypatch):
    """A warm gate reads the limit searches and the modal analyses from the cache."""
    from flexval.validation.studies import gatemetrics

    cache = tmp_path / "ci-cache"
    limits, modes = _limit_gates(tmp_path, 50.0), _frequency_gates(tmp_path, 50.0)
    cold = {}
    for gates in (limits, modes):
        record = tmp_path / "cold.json"
        _run([gates, "--cache", str(cache), "--json", str(record)])
        cold[gates] = json.loads(record.read_text())["results"]
    fresh = tmp_path / "fresh-cache"
    for gates in (limits, modes):
        assert _run([gates, "--prepare", "--cache", str(fresh)]) == 0

    def never(*args, **kwargs):
        raise AssertionError("computed, not read from the cache")

    monkeypatch.setattr(gatemetrics, "_search", never)
    monkeypatch.setattr(gatemetrics, "lowest_frequencies", never)
    for gates in (limits, modes):
        record = tmp_path / "warm.json"
        _run([gates, "--cache", str(fresh), "--json", str(record)])
        warm = json.loads(record.read_text())["results"]
        strip = [{k: v for k, v in r.items() if k != "seconds"} for r in warm]
        assert strip == [{k: v for k, v in r.items() if k != "seconds"} for r in cold[gates]]


def test_a_parasitic_gate_scores_each_component_against_the_references_own(tmp_path):
    """On tapered_leaf's stage pushed sideways, beam:100 gives a parasitic dy of -0.21 mm and
    a rotation of -1.2e-4 rad (CalculiX gives the same to 1 %): dcmm:1 predicts no dy
    (100 % off), dcmm:2 four times the rotation (312 % off). filleted_stage's vertical
    push moves its symmetric stage without parasitic motion but round-off: nothing to score,
    the gate passes and says why."""
    rows = {}
    for scene, case, status in (("tapered_leaf", "f+", 1), ("filleted_stage", "v-", 0)):
        gates = tmp_path / f"{scene}.toml"
        gates.write_text(
            f'reference = "beam:100"\nscenes = ["{scene}"]\nload_cases = ["{case}"]\n'
            '[[gates]]\nmodel = "dcmm:1"\nparasitic = 99.0\n'
            '[[gates]]\nmodel = "dcmm:2"\nparasitic = 400.0\n'
        )
        out = tmp_path / f"{scene}.json"
        assert _run([str(gates), "--json", str(out)]) == status
        rows.update({(r["model"], r["scene"]): r for r in json.loads(out.read_text())["results"]})
    assert not rows["dcmm:1", "tapered_leaf"]["passed"]
    assert rows["dcmm:1", "tapered_leaf"]["value_percent"] == pytest.approx(100.0, abs=0.01)
    assert rows["dcmm:2", "tapered_leaf"]["passed"]
    assert 300.0 < rows["dcmm:2", "tapered_leaf"]["value_percent"] < 330.0
    for model in ("dcmm:1", "dcmm:2"):
        row = rows[model, "filleted_stage"]
        assert row["passed"] and row["value_percent"] is None
        assert "nothing to score" in row["reason"]
