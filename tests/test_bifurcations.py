"""Bifurcation points from the command line: Euler buckling of a clamped-free column.

tests/scenes/euler_column.toml is a straight segment flexure from the ground
to a tip body under a dead compressive tip force along its axis. Its
straight equilibrium loses stability at Euler's load pi^2 EI / (4 L^2)
while the load goes on rising along it: a bifurcation, not a limit point.
The buckled branch that crosses it is the elastica, whose tip deflection at
a load P is known in closed form (Timoshenko and Gere, Theory of elastic
stability, Sect. 2.7): with p = sqrt(P / EI) and K(m) = p L (complete
elliptic integral of the first kind, m = k^2), the tip moves 2 k / p across
the axis, its height is (2 E(m) - K(m)) / p and it turns by 2 arcsin k.

Measured (this file's commands): beam:100 locates the bifurcation at
2.46751 N by arc length and at 2.46750 N by load control, against
pi^2 EI / (4 L^2) = 2.46740 N (+4e-5); beam:20 at 2.46872 N (+5e-4). The
discrete models buckle at their own loads: dcmm:1 2.00000 N, dcmm:2
2.28836 N, dcmm:4 2.41314 N, prbm 2.40006 N. On the buckled branch at 3 N,
beam:100's tip is within 6e-5 of the elastica's. The critical mode's cosine
with the path's direction (:func:`flexval.reducedmodels.core.bifurcation.mode_cosine`)
is about 1e-9 at the column's bifurcation; Lee's frame and the deep arch,
whose limit points are traced in tests/test_limit_loads.py, report none.

A report on the column tabulates each model's bifurcation beside the limit
loads, and a sweep's rows carry it (``bifurcation_load``; null where a path
has none).
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from builders import in_process_client
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from flexval.reducedmodels import LoadPath
from flexval.validation.cli import main
from flexval.validation.failures import BIFURCATION
from flexval.validation.report.data import compute_report
from flexval.validation.report.writer import write_report
from flexval.validation.sweep import load_sweep, results_store, run_sweep, sweep_rows, write_outputs

SCENES = Path(__file__).parent / "scenes"
COLUMN = SCENES / "euler_column.toml"


def _column() -> tuple[float, float, float]:
    """(EI N mm^2, L mm, P N) of the column scene, read from its file."""
    data = tomllib.loads(COLUMN.read_text())
    section, (flexure,) = data["section"], data["flexures"]
    ei = data["material"]["youngs_modulus"] * section["depth"] * section["thickness"] ** 3 / 12
    length = math.dist(flexure["start"], flexure["end"])
    return ei, length, data["load_cases"][0]["value"]


def euler_load() -> float:
    """pi^2 EI / (4 L^2), N."""
    ei, length, _ = _column()
    return math.pi**2 * ei / (4.0 * length**2)


def elastica_tip(load: float) -> tuple[float, float, float]:
    """The buckled clamped-free elastica's tip under ``load`` (N): (across mm, along mm, rad)."""
    ei, length, _ = _column()
    p = math.sqrt(load / ei)
    m = brentq(lambda m: ellipk(m) - length * p, 1e-12, 1.0 - 1e-12)
    k = math.sqrt(m)
    return 2.0 * k / p, (2.0 * ellipe(m) - ellipk(m)) / p - length, 2.0 * math.asin(k)


def _run(tmp_path, *args: str) -> tuple[int, dict]:
    out = tmp_path / "r.json"
    code = main(["run", str(COLUMN), *args, "--json", str(out)])
    (result,) = json.loads(out.read_text())["results"]
    return code, result


@pytest.mark.parametrize("model, tolerance", [("beam:100", 5e-3), ("beam:20", 5e-3)])
def test_arclength_reports_euler_buckling_as_a_bifurcation(tmp_path, capsys, model, tolerance):
    code, r = _run(tmp_path, "--arclength", "--model", model)
    assert code == 0 and r["converged"]
    (found,) = r["bifurcations"]
    assert found["load"] == pytest.approx(euler_load(), rel=tolerance)
    assert found["load"] == pytest.approx(found["fraction"] * _column()[2], rel=1e-12)
    assert r["limit_points"] == []  # the load rises through it
    assert r["dx"][-1] == pytest.approx(0.0, abs=1e-6)  # the straight branch, traced on
    assert f"bifurcation: load {found['load']:.6g} N" in capsys.readouterr().out


def test_load_control_names_the_bifurcation_it_stops_at(tmp_path, capsys):
    code, r = _run(tmp_path, "--model", "beam:100")
    assert code == 3 and not r["converged"]
    (found,) = r["bifurcations"]
    assert found["load"] == pytest.approx(euler_load(), rel=5e-4)
    err = capsys.readouterr().err
    assert f"bifurcation at {found['load']:.6g} N (fraction {found['fraction']:.6g})" in err
    assert "unstable equilibrium" not in err


def test_branch_switch_follows_the_elastica(tmp_path):
    code, r = _run(tmp_path, "--arclength", "--branch-switch", "--model", "beam:100")
    assert code == 0 and r["converged"] and r["settings"]["branch_switch"]
    assert len(r["bifurcations"]) == 1 and r["load"][-1] == pytest.approx(_column()[2])
    across, along, turn = elastica_tip(r["load"][-1])
    ei, length, _ = _column()
    assert abs(r["dx"][-1]) == pytest.approx(across, abs=2e-4 * length)
    assert r["dy"][-1] == pytest.approx(along, abs=2e-4 * length)
    assert abs(r["rotation"][-1]) == pytest.approx(turn, abs=2e-4)


def test_limit_points_are_not_bifurcations(tmp_path):
    out = tmp_path / "r.json"
    scene = SCENES / "lee_frame.toml"
    assert main(["run", str(scene), "--arclength", "--model", "dcmm:2", "--json", str(out)]) == 0
    (r,) = json.loads(out.read_text())["results"]
    assert r["limit_points"] and r["bifurcations"] == []


def test_bifurcations_round_trip_through_json():
    lp = LoadPath("m", "P", [1.0], [0.0], [0.0], [0.0], 0.1, bifurcations=[])
    lp.bifurcations.append({"load": 2.4675, "fraction": 0.8225})
    assert LoadPath.from_json(lp.to_json()) == lp


def test_branch_switch_needs_arclength(tmp_path, capsys):
    assert main(["run", str(COLUMN), "--model", "beam:4", "--branch-switch"]) == 2
    assert "--branch-switch" in capsys.readouterr().err


def test_report_tabulates_the_bifurcation_beside_limit_points(tmp_path):
    """A report on the column: load control stops at Euler's load, a failure at a
    bifurcation point, tabulated with its load and fraction, named in the findings and
    the discussion."""
    data = compute_report(
        [str(COLUMN)],
        ["beam:100", "beam:20"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    text = write_report(data, tmp_path).read_text()
    (res,) = data.scenes
    full = _column()[2]
    for fail in res.failures:
        assert fail.reason == BIFURCATION
        assert fail.load == pytest.approx(euler_load(), rel=5e-3)
    assert [(m, c) for m, c, _, _ in res.bifurcations()] == [("beam:100", "P"), ("beam:20", "P")]
    table = text.split("### Limit loads and bifurcations against `beam:100`")[1]
    row = next(line for line in table.splitlines() if line.startswith("| `beam:100` bifurcation |"))
    load, fraction = re.search(r"\| ([\d.]+) N at ([\d.]+) % \(\+0\.00 %\) \|$", row).groups()
    assert float(load) == pytest.approx(euler_load(), rel=5e-3)
    assert float(fraction) == pytest.approx(100 * euler_load() / full, rel=5e-3)
    assert "| `beam:20` bifurcation |" in table
    findings = text.split("### Findings")[1].split("## Discussion")[0]
    assert "`beam:100` on `P` fails at 82 % (bifurcation point, 2.47 N)." in findings
    assert f"`beam:100` on `P` has a bifurcation point at {load} N" in findings
    assert "**Bifurcations.** `beam:100` on `P` of euler_column" in text.split("## Discussion")[1]


def test_a_sweep_row_carries_the_first_bifurcation(tmp_path):
    """E doubled puts Euler's load (proportional to E) above the 3 N applied: that row
    reaches full load and carries a null, never a NaN."""
    spec = tmp_path / "sw.toml"
    spec.write_text(
        f'base = "{COLUMN}"\nmodels = ["beam:20"]\nreference = "beam:100"\n'
        'outputs = ["limit_load"]\n[[axes]]\npath = "material.youngs_modulus"\n'
        "values = [10000.0, 20000.0]\n"
    )
    sweep = load_sweep(spec)
    with in_process_client() as client:
        run_sweep(sweep, tmp_path / "o", client, use_cache=False)
    table = pq.read_table(results_store(sweep, tmp_path / "o").parts())
    assert table.column("bifurcation_load").null_count == 2
    rows = {(r["point"], r["model"]): r for r in sweep_rows(sweep, tmp_path / "o")}
    for model in ("beam:100", "beam:20"):
        low, high = rows[(0, model)], rows[(1, model)]
        assert low["status"] == "solver_failure" and low["limit_load"] is None
        assert low["bifurcation_load"] == pytest.approx(euler_load(), rel=5e-3)
        assert high["status"] == "ok" and high["bifurcation_load"] is None
    write_outputs(sweep, list(rows.values()), tmp_path / "o")
    summary = (tmp_path / "o" / "summary.md").read_text()
    assert "| beam:100 | P | 1 | 2.4675 N | 2.4675 N |" in summary
    assert "(bifurcation at 2.4675 N)" in summary
