"""A small report on a tiny scene: its tables must agree with the LoadPaths it
wrote to results.json, and every figure it links must exist."""

import json
import re

import pytest

from reducedmodels import LoadPath
from validation.compare import errors
from validation.report import build_report

TINY = """
name = "tiny"
description = "one arc cantilever with a link"
[material]
youngs_modulus = 2000.0
poisson_ratio = 0.3
[section]
depth = 1.0
thickness = 0.2
[ground]
name = "g"
points = [[0.0, 0.0]]
[target]
body = "t"
point = [6.0, 0.0]
[[flexures]]
name = "a"
bodies = ["g", "t"]
center = [2.0, 0.0]
radius = 2.0
axis_deg = 90.0
width_deg = 180.0
[[load_cases]]
name = "up"
kind = "force"
angle_deg = 90.0
value = 0.01
levels = 6
[[load_cases]]
name = "twist"
kind = "moment"
body = "t"
value = 0.02
levels = 6
"""


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    d = tmp_path_factory.mktemp("rep")
    scene = d / "tiny.toml"
    scene.write_text(TINY)
    md = build_report([str(scene)], d / "out", ["beam:100", "beam:10", "dcmm:1", "ee"],
                      repeats=1, use_cache=False, progress=False, bench=False, converge=False)
    return md


def test_tables_match_results_json(report):
    text = report.read_text()
    data = json.loads((report.parent / "results.json").read_text())
    paths = {(r["model"], r["load_case"]): LoadPath.from_dict(r)
             for r in data["scenes"]["tiny"]["results"]}
    rows = re.findall(r"^\| (\S+) \| (up|twist) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \| "
                      r"([\d.]+) \| ([\d.]+) \|$", text, flags=re.M)
    assert len(rows) == 3 * 2          # three models against beam:100, two cases
    for model, case, *vals in rows:
        e = errors(paths[(model, case)], paths[("beam:100", case)])
        expect = [e[k] for k in ("end_disp_vec", "end_disp", "end_rot", "path_disp", "path_rot")]
        for got, ref in zip(map(float, vals), expect):
            assert got == pytest.approx(ref, abs=0.006)   # printed with 2 decimals
    # timing table: our seconds are the LoadPaths' seconds
    for (model, case), lp in paths.items():
        assert f"{lp.seconds:.4f}" in text


def test_linked_figures_exist(report):
    text = report.read_text()
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert links
    for name in links:
        assert (report.parent / name).is_file(), name
