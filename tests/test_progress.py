"""Progress of long work: ``flexval run`` shows one line per converged load level.

Work estimated (:func:`flexval.validation.resources.check_models`) to take longer than
the threshold (60 s, or ``$FLEXVAL_LONG_SECONDS``) prints its estimate and, on a static
load-control path, a line on stderr per converged level. The threshold is forced to 0
here so that a small continuum run counts as long; the lines must appear, one per level
of each path in order, and the results must be those of the same run without them.
"""

from __future__ import annotations

import json
import re

import pytest

from flexval.validation.cli import main
from flexval.validation.resources import LONG_ENV

ARGS = ["run", "open_chain", "--model", "continuum:0", "--model", "ee", "--load-case", "m+"]
LEVELS = 4
RESULT_FIELDS = (
    "load",
    "dx",
    "dy",
    "rotation",
    "valid",
    "stress",
    "stress_profile",
    "fibre_stress",
)


def _run(tmp_path, capsys, name: str) -> tuple[list[dict], str]:
    out = tmp_path / f"{name}.json"
    capsys.readouterr()
    assert main([*ARGS, "--levels", str(LEVELS), "--json", str(out)]) == 0
    results = json.loads(out.read_text())["results"]
    return [{k: r.get(k) for k in RESULT_FIELDS} for r in results], capsys.readouterr().err


def test_long_work_shows_a_line_per_level_and_the_same_results(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv(LONG_ENV, raising=False)
    quiet, err = _run(tmp_path, capsys, "quiet")
    assert "estimate" not in err and "level" not in err  # continuum:0 takes well under 60 s
    monkeypatch.setenv(LONG_ENV, "0")
    shown, err = _run(tmp_path, capsys, "shown")
    assert shown == quiet
    assert err.startswith("estimate: about ")
    lines = [line for line in err.splitlines() if " level " in line]
    # ee is linear (no traced path): only the continuum's levels, each once and in order
    assert len(lines) == LEVELS
    for k, line in enumerate(lines, start=1):
        match = re.search(
            rf"\] +{k}/{LEVELS} +[\d.]+ s, about \d+ s left  continuum:0 on m\+: "
            rf"level {k}/{LEVELS}, load (\S+) N mm$",
            line,
        )
        assert match, line
        assert float(match.group(1)) == pytest.approx(shown[0]["load"][k - 1], rel=1e-3, abs=1e-9)


@pytest.mark.parametrize("value", ["soon", "-1", "nan", "inf"])
def test_a_bad_threshold_names_the_variable(capsys, monkeypatch, value):
    monkeypatch.setenv(LONG_ENV, value)
    assert main([*ARGS, "--levels", "2"]) == 2
    err = capsys.readouterr().err
    assert LONG_ENV in err and value in err and "Traceback" not in err
