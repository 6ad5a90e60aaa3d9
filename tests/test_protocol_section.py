"""The report's dynamics-protocol section, rendered from a small synthetic ``protocol.json``.

The grid below is built so that the answers are known by construction:
beam:20's paper figure (10.7 %) is closest to its 9.5 % cell (1.2 points
away; the 12.0 % cell is 1.3 away and a failed cell has no error), dcmm:1's
paper figure (19.3 %) is 4.0 points from its closest cell (23.3 %), so only
beam:20 is reproduced within the 2 points. A missing, unreadable or foreign
file, and one computed by another code version, must each say so in the
section instead of failing the report.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from flexval.validation.outputs import write_json
from flexval.validation.report.protocol import (
    PROTOCOL_FORMAT,
    Cell,
    closest_cell,
    protocol_section,
    read_protocol,
)

CODE = "0123456789abcdef"


def _cell(model, ramp, ratio, disp, rot, failure=None):
    return {
        "model": model,
        "ramp_periods": ramp,
        "ramp_s": ramp * 0.05,
        "damping_ratio": ratio,
        "disp": disp,
        "rot": rot,
        "failure": failure,
    }


def _document(code: str = CODE) -> dict:
    return {
        "format": PROTOCOL_FORMAT,
        "code_version": code,
        "scene": "open_chain",
        "case": "f-",
        "reference": "beam:100",
        "match_points": 2.0,
        "table": "protocol.md",
        "paper": {"beam:20": {"disp": 10.7, "rot": 8.5}, "dcmm:1": {"disp": 19.3, "rot": 13.5}},
        "static": {"beam:20": {"disp": 0.5, "rot": 0.5}, "dcmm:1": {"disp": 5.7, "rot": 5.9}},
        "cells": [
            _cell("beam:20", 2.0, 0.05, 50.0, 40.0),
            _cell("dcmm:1", 2.0, 0.05, 80.0, 60.0),
            _cell("beam:20", 4.0, 0.05, 12.0, 11.0),
            _cell("dcmm:1", 4.0, 0.05, 23.3, 20.0),
            _cell("beam:20", 8.0, 0.2, 9.5, 8.0),
            _cell("dcmm:1", 8.0, 0.2, 30.0, 25.0),
            _cell("beam:20", 16.0, 1.0, None, None, "no convergence at 40 % of the load"),
            _cell("dcmm:1", 16.0, 1.0, 1.0, 1.0),
        ],
    }


@pytest.fixture
def files(tmp_path):
    """reports/dynamics/protocol.json (+ its table) and the report folder reports/paper."""
    dynamics, paper = tmp_path / "reports" / "dynamics", tmp_path / "reports" / "paper"
    dynamics.mkdir(parents=True)
    paper.mkdir()
    (dynamics / "protocol.md").write_text("# full table\n")
    return dynamics / "protocol.json", paper


def _text(path: Path | None, out: Path, code: str = CODE) -> str:
    return "\n".join(protocol_section(path, out, code))


def test_closest_cell_skips_failed_runs_and_breaks_ties_in_grid_order():
    cells = [
        Cell("m", 1.0, 0.1, 0.1, 3.0, 3.0, None),
        Cell("m", 2.0, 0.1, 0.2, 5.0, 5.0, None),
        Cell("m", 3.0, 0.1, 0.3, None, None, "failed"),
        Cell("o", 4.0, 0.1, 0.4, 4.0, 4.0, None),
    ]
    assert closest_cell(cells, "m", 4.0).ramp_periods == 1.0  # 3 and 5 tie: the first
    assert closest_cell(cells, "m", 6.0).ramp_periods == 2.0
    assert closest_cell(cells, "x", 6.0) is None


def test_section_names_the_closest_cells_and_the_verdicts(files):
    path, out = files
    write_json(path, _document())
    text = _text(path, out)
    beam = next(line for line in text.splitlines() if line.startswith("- **beam:20**"))
    assert "(paper 10.7 % disp, 8.5 % rot; static 0.5 % / 0.5 %)" in beam
    assert "closest ramp 8 T1 (0.400 s), damping ratio 0.2: 9.5 % disp, 8.0 % rot" in beam
    assert "**reproduced** (disp within 2 points; rot too), by 2 of the grid's cells" in beam
    dcmm = next(line for line in text.splitlines() if line.startswith("- **dcmm:1**"))
    assert "closest ramp 4 T1 (0.200 s), damping ratio 0.05: 23.3 % disp, 20.0 % rot" in dcmm
    assert "**not reproduced** (no cell within 2 points)" in dcmm
    assert "One protocol for every model at once (as the paper ran it): no grid cell." in text
    assert "- 1 of 8 runs failed" in text
    assert "Stale" not in text and "Not available" not in text


def test_link_to_the_full_table_works_from_the_report_folder(files):
    path, out = files
    write_json(path, _document())
    text = _text(path, out)
    assert "[../dynamics/protocol.md](../dynamics/protocol.md)" in text
    assert (out / "../dynamics/protocol.md").resolve().read_text() == "# full table\n"


def test_a_common_reproducing_cell_is_named(files):
    path, out = files
    doc = _document()
    doc["paper"]["dcmm:1"]["disp"] = 29.0  # now the 8 T1 / 0.2 cell matches both
    write_json(path, doc)
    assert "One protocol for every model at once (as the paper ran it): 8 T1 / ratio 0.2." in _text(
        path, out
    )


def test_results_of_another_code_version_are_called_stale(files):
    path, out = files
    write_json(path, _document(code="fedcba9876543210"))
    text = _text(path, out)
    assert (
        "**Stale:** these results were computed by flexval code fedcba9876543210, "
        f"this report by {CODE}"
    ) in text
    assert "**reproduced**" in text  # still shown, with the warning


@pytest.mark.parametrize(
    "content, reason",
    [
        (None, "does not exist"),
        ("{not json", "is unreadable (JSONDecodeError)"),
        ('{"format": "something-else/1"}', f"is not a {PROTOCOL_FORMAT} file"),
        (f'{{"format": "{PROTOCOL_FORMAT}", "cells": []}}', "lacks code_version, case, reference"),
        (
            f'{{"format": "{PROTOCOL_FORMAT}", "code_version": "x", "case": "f-", '
            '"reference": "r", "match_points": 2, "paper": {}, "static": {}, '
            '"cells": [{"model": "m"}]}',
            "has a malformed entry (KeyError",
        ),
    ],
)
def test_an_unusable_file_says_why_and_how_to_produce_it(files, content, reason):
    path, out = files
    if content is not None:
        path.write_text(content)
    doc, why = read_protocol(path)
    assert doc is None and reason in why
    text = _text(path, out)
    assert f"Not available: `{path.as_posix()}` {reason}" in text
    assert "python benchmarks/paper_protocol.py" in text
    assert "--protocol reports/dynamics/protocol.json" in text


def test_no_file_given_says_how_to_include_it(files):
    _, out = files
    text = _text(None, out)
    assert "Not included in this report (no `--protocol` file)" in text
    assert "python benchmarks/paper_protocol.py" in text
