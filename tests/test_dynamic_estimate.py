"""Estimates before a dynamic run: its time steps from the duration, the lowest natural
frequency at rest and the error tolerance (:data:`flexval.validation.studies.dynamic.STEPS_FIT`),
its
time from one timed Newton iteration; above the long-work threshold the estimate is printed
and each run shows a progress line per 1/20 of its duration; the results are the same."""

import json

import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels import parse_model
from flexval.validation.cli import EXIT_INPUT, main
from flexval.validation.studies.dynamic import (
    PROGRESS_UNITS,
    estimate_dynamic,
    run_dynamic,
)
from flexval.validation.studies.modes import choose_density

DENSITY = 1.24e-9
"""t/mm^3: the open chain's flexures in PLA (lowest mode 21.6 Hz at rest)."""
RUN = ["run", "open_chain", "--model", "dcmm:1", "--dynamic", "--density", str(DENSITY)]
RUN += ["--load-case", "f-", "--duration", "0.25"]


def _final(path) -> list:
    """Every result's numbers but its run time."""
    results = json.loads(path.read_text())["results"]
    return [{k: v for k, v in r.items() if k not in ("seconds", "stats")} for r in results]


def test_a_long_dynamic_run_prints_its_estimate_and_progress(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("FLEXVAL_LONG_SECONDS", "0")
    assert main([*RUN, "--json", str(tmp_path / "long.json")]) == 0
    err = capsys.readouterr().err
    assert "estimate: about" in err and "steps over 0.25 s" in err and "Hz at rest" in err
    lines = [x for x in err.splitlines() if "dcmm:1 on f-: t " in x]
    assert len(lines) == PROGRESS_UNITS, err
    assert lines[-1].split("]")[1].split()[0] == f"{PROGRESS_UNITS}/{PROGRESS_UNITS}"
    assert "t 0.25 of 0.25 s" in lines[-1] and "s left" in lines[-1]
    monkeypatch.delenv("FLEXVAL_LONG_SECONDS")
    assert main([*RUN, "--json", str(tmp_path / "short.json")]) == 0
    err = capsys.readouterr().err
    assert "estimate" not in err and " t 0." not in err  # a run of a second: no progress
    assert _final(tmp_path / "long.json") == _final(tmp_path / "short.json")


@pytest.mark.parametrize(
    "case,duration,tol", [("f-", 0.25, 1e-4), ("f-", 1.25, 1e-6), ("m+", 1.25, 1e-5)]
)
def test_the_step_estimate_holds_within_its_measured_spread(case, duration, tol):
    """Runs inside the fit's range take 0.3 to 4.8 times the estimated steps (the spread
    over the 104 fitted runs: estimate over measured 0.21 to 3.34)."""
    scene, _ = choose_density(load_scene("open_chain"), DENSITY, what="a dynamic run")
    spec = parse_model("dcmm:1")
    lp = run_dynamic(scene, spec, scene.load_case(case), duration, error_tol=tol)
    e = estimate_dynamic(scene, spec, scene.load_case(case), duration, tol)
    assert e.duration == duration and 21.0 < e.frequency < 22.0
    assert 0.21 <= e.steps / lp.stats["steps"] <= 3.34, (e.steps, lp.stats["steps"])
    assert e.iteration > 0.0 and e.seconds > 0.0


def test_a_dynamic_continuum_run_goes_through_the_memory_check(capsys):
    """The static path's memory check covers the dynamic run (one effective tangent
    factorised per iteration, as a static Newton iteration): refused before any meshing."""
    argv = ["run", "open_chain", "--model", "continuum:8", "--dynamic", "--density", "1e-9"]
    assert main(argv) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "continuum:8" in err and "of memory" in err and "use a lower LEVEL" in err
