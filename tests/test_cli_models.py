"""``flexval models`` lists the catalogue, and the commands' tables line up.

What ``flexval models`` must show is computed from the catalogue here, never
typed in: every registered family (a toy family registered by the test
included) with its id syntax, resolution range and default, every option with
its allowed values and default, and every capability. The tables of ``run``,
``converge``, ``modes`` and ``info`` are checked with long model ids, case
and flexure names: each column starts (text) or ends (numbers) at the same
place on every line.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from importlib import resources

import pytest

from flexval.reducedmodels.catalogue import (
    CAPABILITIES,
    Family,
    Option,
    Resolution,
    families,
    register,
    unregister,
)
from flexval.validation.cli import main
from flexval.validation.cli.modelinfo import CAPABILITY_DOCS
from flexval.validation.report.tables import Column, markdown_table, sig, text_row, text_table

TOY = Family(
    "toy-springs-with-a-long-name",
    "toy: a family registered by this test only",
    lambda *args, **kwargs: None,
    Resolution("K", "stiffness steps", 7, 3, 99, True, (3, 12)),
    (
        Option("stiffness-multiplier", "multiplies the stiffness", (("1", 1), ("10", 10)), "1"),
        Option.flag("damped", "adds damping"),
    ),
    frozenset(),
)


@pytest.fixture
def toy():
    register(TOY)
    yield TOY
    unregister(TOY.name)


def test_models_lists_every_family_option_and_capability(toy, tmp_path, capsys):
    out = tmp_path / "models.json"
    assert main(["models", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    lines = text.splitlines()
    words = " ".join(text.split())
    fams = families()
    assert TOY in fams
    for fam in fams:
        (row,) = [s for s in lines if s.split()[:2] == [fam.name, fam.syntax]]
        cells = row.split()
        res = fam.resolution
        if res is None:
            assert cells[2:5] == ["-", "-", "-"]
        else:
            assert cells[2:5] == [res.name, str(res.default), f"{res.low}..{res.high}"]
        assert " ".join(fam.summary.split()) in words
        for opt in fam.options:
            (orow,) = [s for s in lines if s.split()[:2] == [fam.name, opt.name]]
            assert orow.split()[2:4] == ["|".join(opt.allowed), opt.default]
            assert " ".join(opt.doc.split()) in words
        for cap in fam.capabilities:
            assert cap in row
    for cap in CAPABILITIES:
        assert any(s.startswith(cap) and CAPABILITY_DOCS[cap] in s for s in lines)

    record = json.loads(out.read_text())
    assert [f["name"] for f in record["families"]] == [f.name for f in fams]
    for fam, rec in zip(fams, record["families"]):
        assert rec["syntax"] == fam.syntax
        assert rec["capabilities"] == sorted(fam.capabilities)
        assert [o["name"] for o in rec["options"]] == [o.name for o in fam.options]
        assert [o["values"] for o in rec["options"]] == [list(o.allowed) for o in fam.options]
        assert [o["default"] for o in rec["options"]] == [o.default for o in fam.options]
        if fam.resolution is not None:
            r = fam.resolution
            assert rec["resolution"] == {
                "name": r.name,
                "meaning": r.meaning,
                "default": r.default,
                "low": r.low,
                "high": r.high,
            }
    assert set(record["capabilities"]) == set(CAPABILITIES)


def test_every_capability_is_explained():
    assert set(CAPABILITY_DOCS) == set(CAPABILITIES)


def test_models_tables_line_up_with_a_long_family(toy, capsys):
    assert main(["models"]) == 0
    lines = capsys.readouterr().out.splitlines()
    start = lines.index(next(s for s in lines if s.startswith("family") and "syntax" in s))
    table = lines[start : start + len(families()) + 1]
    _assert_columns_line_up(
        table, ["family", "id syntax", "resolution", "range", "options"], ["default"]
    )


def test_models_loads_no_solver():
    code = (
        "import sys, contextlib, io; from flexval.validation.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()): main(['models'])\n"
        "print(sorted(m for m in ('scipy', 'numba', 'skfem', 'gmsh', 'matplotlib', "
        "'flexval.reducedmodels.core.system') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"


# --- alignment -------------------------------------------------------------------------


def _assert_columns_line_up(lines: list[str], left: list[str], right: list[str]) -> None:
    """Every line of ``lines`` (a title line, then rows) has the cells of the ``left`` titled
    columns starting where their titles start, and those of ``right`` ending where theirs end.

    A cell starts at a non-blank character after a blank (or the line's start); it ends
    at a non-blank character before a blank (or the line's end).
    """
    head = lines[0]
    for title in left:
        at = head.index(title)
        for line in lines[1:]:
            assert line[at] != " " and (at == 0 or line[at - 1] == " "), (title, line)
    for title in right:
        end = head.index(title) + len(title)
        for line in lines[1:]:
            assert line[end - 1] != " " and line[end : end + 1] in ("", " "), (title, line)


def test_text_table_widens_columns_to_a_long_id():
    long_id = "continuum:1[law=neo-hookean,plane=strain]"
    cols = [Column("model", "<"), Column("case", "<"), Column("|d| mm"), Column("seconds")]
    rows = [
        ["ee", "f+", "7.4260", sig(0.00037, 3)],
        [long_id, "m+", "14.7082", sig(12.5, 3)],
        ["beam:100[shear]", "a-long-case", "-10.0000", sig(0.1234567, 3)],
    ]
    lines = text_table(cols, rows)
    assert len({len(s) for s in lines}) == 1  # the last column is right-aligned
    _assert_columns_line_up(lines, ["model", "case"], ["|d| mm", "seconds"])
    assert lines[2].startswith(long_id + " ")


def test_a_streamed_row_keeps_its_columns():
    cols = [Column("model", "<", width=25), Column("load", width=10), Column("unit", "<", 4)]
    lines = [text_row(cols, [c.title for c in cols])]
    lines += [text_row(cols, ["dcmm:2[frame=follower]", sig(-5e-4), "N mm"])]
    lines += [text_row(cols, ["ee", sig(3e-3), "N"])]
    _assert_columns_line_up(lines, ["model", "unit"], ["load"])


def test_markdown_table_lines_up_as_text():
    lines = markdown_table(
        [Column("model", "<"), Column("error (%)")],
        [["continuum:0[law=neo-hookean]", "1.23"], ["ee", "95.8"], ["a|b", "0.00100"]],
    )
    assert len({len(s) for s in lines}) == 1
    pipes = {tuple(m.start() for m in re.finditer(r"\|", s)) for s in lines}
    assert len(pipes) == 1 and len(next(iter(pipes))) == 3  # '|' inside a cell became '/'
    assert lines[1].startswith("| ---") and lines[1].endswith(": |")


@pytest.mark.parametrize(
    "value, text",
    [
        (3.0, "3.000"),
        (0.012, "0.01200"),
        (8.61, "8.610"),
        (1234.0, "1234"),
        (123456.0, "1.235e+05"),
        (-5e-4, "-0.0005000"),
        (None, "-"),
        (float("nan"), "nan"),
        (float("-inf"), "-inf"),
    ],
)
def test_sig_keeps_its_significant_digits(value, text):
    assert sig(value) == text


def _run_table(out: str) -> list[str]:
    return [s for s in out.splitlines() if s and not s.startswith(("  !", "note:"))]


def test_run_table_lines_up_with_long_ids(capsys):
    argv = ["run", "open_chain", "--levels", "3", "--load-case", "f+", "--load-case", "m+"]
    argv += ["--model", "dcmm:2[frame=follower]", "--model", "ee", "--model", "prbm"]
    assert main(argv) == 0
    lines = _run_table(capsys.readouterr().out)
    assert len(lines) == 1 + 3 * 2
    assert len({len(s) for s in lines}) == 1  # 'valid', the last column, is right-aligned
    _assert_columns_line_up(
        lines,
        ["model", "case", "unit"],
        ["load", "dx mm", "dy mm", "|d| mm", "rot deg", "peak MPa", "iters", "seconds", "valid"],
    )


def test_converge_table_lines_up_with_long_ids(capsys):
    argv = ["converge", "open_chain", "--model", "dcmm[frame=follower]", "--levels", "1:4"]
    assert main([*argv, "--load-case", "f+"]) == 0
    lines = capsys.readouterr().out.splitlines()
    table = lines[1:5]
    assert table[0].startswith("model") and table[-1].startswith("dcmm:4[frame=follower]")
    assert len({len(s) for s in table}) == 1
    _assert_columns_line_up(
        table, ["model"], ["unknowns", "seconds", "|d| mm", "rot deg", "peak MPa"]
    )


def test_info_tables_line_up_with_long_names(tmp_path, capsys):
    text = resources.files("flexval.geometry").joinpath("scenes", "open_chain.toml").read_text()
    scene = tmp_path / "long.toml"
    scene.write_text(
        text.replace('name = "e12"', 'name = "a_rather_long_flexure_name"').replace(
            'name = "f+"', 'name = "a-long-load-case"'
        )
    )
    assert main(["info", str(scene)]) == 0
    lines = capsys.readouterr().out.splitlines()
    start = lines.index("flexures") + 1
    flex = lines[start : start + 4]
    assert any("a_rather_long_flexure_name" in s for s in flex)
    assert len({len(s) for s in flex}) == 1
    _assert_columns_line_up(flex, ["name", "bodies"], ["L mm", "EI N mm2", "a mm", "b mm"])
    start = lines.index("load cases") + 1
    _assert_columns_line_up(lines[start : start + 5], ["name", "loads"], ["levels"])
