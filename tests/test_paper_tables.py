"""The paper's Tables 2 and 5: every reduced model on both built-in scenes
against beam:100 (the paper's convention), our percentages beside the paper's.

The table is written to ``$FLEXVAL_TABLE_OUT`` (default: pytest's tmp dir) and
printed (``pytest -s``). The assertions check properties that follow from the
models, not the paper's numbers: FEM20 is within the O(1/N^2) discretisation
error of FEM100, DCMM_n improves with n on force loads, DCMM gets pure-moment
rotations exactly, and the one metric choice (end displacement *vector*
error) reproduces the paper's DCMM moment-case figure. The paper's figures
are read from ``validation/data/paper_results.toml``, never typed in here.

Known differences from the paper (see reports/paper/report.md):
- open chain f-: the paper's FEM20 (10.7 %) and DCMM (19.3 %) errors are far
  above ours at the end of the ramp; they match our *path* maxima for DCMM
  (largest error inside the soft stretch between 80 % and 90 % of the load),
  which a dynamic quasi-static run traverses late. FEM20 vs FEM100 is a pure
  discretisation difference here (0.5 %).
- closed chain DCMM_1: the paper reports 31.1/46.0 % (f+) and 18.7/8.6 % (f-),
  we get about 8/14 % and 29/51 %. DCMM_1 sub-arcs rotate by up to ~30 deg
  relative to their leading body, where the result depends on how the
  relative displacement is measured (leader frame here, as the paper states;
  RecurDyn's force element is not documented). DCMM_n converges to the beam
  (dcmm:8 within 0.03 % of beam:100 on the closed chain), which shows ours
  is consistent.
"""

import os
from pathlib import Path

import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.report.writer import SceneResults, _paper_table
from flexval.validation.studies.campaign import run_campaign
from flexval.validation.studies.compare import paper_percent

MODELS = ["beam:100", "beam:20", "prbm", "dcmm:1", "dcmm:2", "dcmm:3", "ee"]


@pytest.fixture(scope="module")
def tables():
    out = {}
    for name in ("open_chain", "closed_chain"):
        scene = load_scene(name)
        specs = [parse_model(m) for m in MODELS]
        paths, failures = run_campaign(scene, specs, list(scene.load_cases), 1, None)
        assert not failures, failures
        out[name] = SceneResults(scene, paths, failures, [s.id for s in specs])
    return out


def test_write_table_beside_the_paper(tables, tmp_path):
    target = Path(os.environ.get("FLEXVAL_TABLE_OUT", tmp_path / "paper_tables.md"))
    lines = ["# Percent differences from beam:100 (paper's values in parentheses)", ""]
    for name, res in tables.items():
        lines += [f"## {name}", ""] + _paper_table(res) + [""]
    target.write_text("\n".join(lines))
    print("\n".join(lines))
    # each cell, found by row (model) and column (case, metric), holds our error and,
    # in parentheses, the paper's figure from validation/data/paper_results.toml
    checked = 0
    for name, res in tables.items():
        ours, paper = res.error_table("beam:100"), paper_percent(name, res.cases)
        rows = {
            line.split("|")[1].strip(): [c.strip() for c in line.strip("|").split("|")[1:]]
            for line in _paper_table(res)[2:]
        }
        for model, cells in rows.items():
            for k, case in enumerate(res.cases):
                for j, (key, pk) in enumerate((("end_disp_vec", "disp"), ("end_rot", "rot"))):
                    cell = cells[2 * k + j]
                    value = cell.split(" (")[0]
                    assert float(value) == pytest.approx(ours[model][case][key], abs=0.051)
                    expect = paper.get(model, {}).get(case)
                    if expect is None:
                        assert "(" not in cell, (name, model, case, cell)
                    else:
                        assert cell.endswith(f"({expect[pk]:.1f})"), (name, model, case, cell)
                        checked += 1
    # every figure of the data file's two tables appears beside ours
    assert checked == sum(
        2 * len(per) for name in tables for per in paper_percent(name, tables[name].cases).values()
    )


def test_fem20_is_within_discretisation_error(tables):
    for res in tables.values():
        for case, e in res.error_table("beam:100")["beam:20"].items():
            # O(1/N^2) beam error: (100/20)^2 * ~0.02 % of FEM100's own error ~ 0.5 %
            assert e["path_disp"] < 1.0 and e["path_rot"] < 1.0, (res.scene.name, case, e)


def test_dcmm_improves_with_subdivision_on_force_loads(tables):
    for res in tables.values():
        t = res.error_table("beam:100")
        for case in res.cases:
            if not case.startswith("f"):
                continue
            errs = [t[f"dcmm:{n}"][case]["end_disp_vec"] for n in (1, 2, 3)]
            assert errs[0] > errs[1] > errs[2], (res.scene.name, case, errs)


def test_dcmm_moment_rotation_exact_and_paper_displacement_reproduced(tables):
    t = tables["open_chain"].error_table("beam:100")
    for case in ("m+", "m-"):
        for n in (1, 2, 3):
            # beam:100's own rotation error is O(1e-4): DCMM's is exact
            assert t[f"dcmm:{n}"][case]["end_rot"] < 0.05
        # the paper prints 0.1-point figures; ours are 1.26 (m+) and 1.19 (m-)
        paper = paper_percent("open_chain", tables["open_chain"].cases)["dcmm:1"][case]["disp"]
        assert t["dcmm:1"][case]["end_disp_vec"] == pytest.approx(paper, abs=0.1)


def test_prbm_is_within_a_few_percent(tables):
    for res in tables.values():
        for case, e in res.error_table("beam:100")["prbm"].items():
            assert e["end_disp_vec"] < 6.0 and e["end_rot"] < 6.0, (res.scene.name, case, e)
