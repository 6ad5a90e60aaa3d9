"""``benchmarks/paper_protocol.py`` on a tiny grid: its table is consistent with its inputs.

A very slow (40 first periods), critically damped (ratio 1) Eq. 15 ramp must
end at the static end state within 0.1 % (the quasi-static limit asked of
dynamic runs); the script's end-of-ramp error must equal
``flexval.validation.studies.compare.errors``' ``end_disp_vec`` and ``end_rot`` on static paths.
Its ``protocol.json`` is strict JSON (a failed run's errors are null), carries
the code version and reads back through the report's reader with the table's
numbers.
"""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import pytest

from flexval.geometry import load_scene
from flexval.validation.cache import code_version
from flexval.validation.outputs import write_json
from flexval.validation.report.protocol import protocol_section, read_protocol

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "paper_protocol.py"


@pytest.fixture(scope="module")
def protocol():
    spec = importlib.util.spec_from_file_location("paper_protocol", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


QUASI_STATIC = 0.1
"""%: the bound on a slow damped ramp's distance from the static path."""


def _strict(path):
    """``path``'s JSON, refusing NaN and Infinity (strict JSON)."""

    def refuse(name):
        raise ValueError(name)

    return json.loads(path.read_text(), parse_constant=refuse)


def test_slow_damped_ramp_reproduces_the_static_end(protocol, tmp_path):
    scene, masses = protocol.with_masses(load_scene("open_chain"))
    assert "massless links" in masses  # the built-in scene has no mass data
    cell = protocol.Protocol(ramp_periods=40.0, damping_ratio=1.0)
    runs, period = protocol.run_protocol(scene, "f-", ["dcmm:1"], "dcmm:1", [cell], 1e-6)
    assert period == pytest.approx(1.0 / runs["dcmm:1"].frequencies[0])
    end = runs["dcmm:1"].dynamic[cell]
    assert end.failure is None
    assert end.simulated_seconds == pytest.approx(40.0 * period)
    (row,) = protocol.rows(runs, "dcmm:1", ["dcmm:1"])
    assert row.same_protocol == (0.0, 0.0)  # the reference against itself
    assert row.against_static == row.lag  # the reference's static end is its own
    assert max(row.lag) < QUASI_STATIC
    assert row.integration == (0.0, 0.0)  # the check runs: the same against itself
    text = protocol.protocol_markdown(
        "open_chain", "f-", "dcmm:1", masses, period, runs, [row], {}, {}, 1e-6
    )
    assert text.count("\n| dcmm:1 | 40 |") == 1
    path = write_json(
        tmp_path / "protocol.json",
        protocol.protocol_document(
            code_version(),
            "open_chain",
            "f-",
            "dcmm:1",
            masses,
            period,
            runs,
            [row],
            {"dcmm:1": (0.0, 0.0)},
            {"dcmm:1": (19.3, 13.5)},
            1e-6,
        ),
    )
    doc, why = read_protocol(path)
    assert why is None and doc == _strict(path)
    assert doc["code_version"] == code_version()
    assert doc["error_tol"] == 1e-6  # what run_protocol used
    (cell,) = doc["cells"]
    assert (cell["disp"], cell["rot"]) == row.same_protocol
    assert (cell["lag"]["disp"], cell["lag"]["rot"]) == row.lag
    assert cell["integration"] == {"disp": 0.0, "rot": 0.0}
    assert cell["ramp_s"] == pytest.approx(40.0 * period, rel=1e-15)
    assert cell["failure"] is None
    assert doc["frequencies_hz"]["dcmm:1"] == list(runs["dcmm:1"].frequencies)
    assert "wall" not in path.read_text() and "seconds" not in path.read_text()
    section = "\n".join(protocol_section(path, tmp_path, code_version()))
    assert "closest ramp 40 T1" in section and "**not reproduced**" in section
    assert "Integration error: at most 0.00 points" in section and "10 times looser" in section


def test_end_errors_match_compare(protocol):
    scene, _ = protocol.with_masses(load_scene("open_chain"))
    runs, _ = protocol.run_protocol(scene, "f-", ["dcmm:1"], "dcmm:2", [])
    static = protocol.static_errors(runs, "dcmm:2", ["dcmm:1"])["dcmm:1"]
    direct = protocol.end_errors(
        runs["dcmm:1"].static, runs["dcmm:2"].static, protocol.reference_scale(runs, "dcmm:2")
    )
    assert static == pytest.approx(direct, rel=1e-12)
    assert min(direct) > 1.0  # dcmm:1 and dcmm:2 differ on f- (a real check)


def test_a_failed_run_is_null_in_the_json(protocol, tmp_path):
    cell = protocol.Protocol(ramp_periods=2.0, damping_ratio=0.05)
    end = protocol.EndState(1.0, 1.0, 0.1)
    failed = protocol.EndState(math.nan, math.nan, math.nan, failure="no convergence at 40 %")
    runs = {
        "ref": protocol.ModelRuns(None, (1.0, 2.0), end, None, {cell: end}),
        "m": protocol.ModelRuns(None, (1.0, 2.0), end, None, {cell: failed}),
    }
    nan = (math.nan, math.nan)  # what end_errors gives a failed run
    table = [protocol.Row("m", cell, nan, nan, nan)]
    path = write_json(
        tmp_path / "protocol.json",
        protocol.protocol_document(
            "abc",
            "open_chain",
            "f-",
            "ref",
            "none",
            0.1,
            runs,
            table,
            {"m": (0.0, 0.0)},
            {"m": (10.0, 8.0)},
        ),
    )
    (entry,) = _strict(path)["cells"]
    assert entry["disp"] is None and entry["failure"] == "no convergence at 40 %"
    section = "\n".join(protocol_section(path, tmp_path, "abc"))
    assert "every run failed; not reproduced" in section
    assert "- 1 of 1 runs failed" in section


def test_integration_estimate_bounds_the_error_it_reports(protocol):
    """The check runs' change over-estimates a cell's integration error in the asymptotic
    range: dcmm:1 against dcmm:2 on a short, strongly damped ramp (12 T1, ratio 1, where the
    reference's lagging end magnifies integration errors), bound 1e-6: estimate 0.38 / 0.47
    points (disp / rot), error against a run with a 1000 times tighter bound 0.13 / 0.16."""
    scene, _ = protocol.with_masses(load_scene("open_chain"))
    cell = protocol.Protocol(ramp_periods=12.0, damping_ratio=1.0)
    runs, _ = protocol.run_protocol(scene, "f-", ["dcmm:1"], "dcmm:2", [cell], 1e-6)
    (row,) = protocol.rows(runs, "dcmm:2", ["dcmm:1"])
    converged, _ = protocol.run_protocol(scene, "f-", ["dcmm:1"], "dcmm:2", [cell], 1e-9, None)
    (best,) = protocol.rows(converged, "dcmm:2", ["dcmm:1"])
    assert best.integration is None  # no check runs asked for
    for estimate, value, exact in zip(row.integration, row.same_protocol, best.same_protocol):
        assert 0.0 < abs(value - exact) <= estimate
