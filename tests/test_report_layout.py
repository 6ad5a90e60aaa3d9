"""The report's committed files change only when a result does.

Run times live in timings.md / timings.json; report.md, results.json and
gates.json hold results only. Checked by rendering one computed report twice,
the second time with every run time of the data multiplied by an odd factor
(as a loaded machine would): the result files must be byte-identical, the
timings must differ. And computing the report on two worker processes gives
the same files as computing it on one.
"""

from __future__ import annotations

import copy
import json
import re

import pytest
from test_report import TINY

from flexval.validation.report.data import LEFT_OUT, TIMING_STATS, compute_report, read_results
from flexval.validation.report.writer import write_report
from flexval.validation.studies.peers import PeerRow

MODELS = ["continuum:0", "beam:100", "beam:10", "dcmm:1", "ee"]
RESULT_FILES = ("report.md", "results.json", "gates.json")
#: a time printed with its unit (0.0123 s, 4.5 ms) or a speed-up (12.4x): never in report.md
TIMING = re.compile(r"\d\s*(s|ms)\b|\d(\.\d+)?x\b|\bseconds\b|\(s\)")


def _scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("layout") / "tiny.toml"
    path.write_text(TINY)
    return str(path)


@pytest.fixture(scope="module")
def computed(tmp_path_factory):
    scene = _scene(tmp_path_factory)
    data = compute_report(
        [scene], MODELS, repeats=2, use_cache=False, progress=False, bench=True, converge=True
    )
    return scene, data


def _slower(data, factor: float):
    """``data`` with every run time multiplied by ``factor``."""
    data = copy.deepcopy(data)
    for res in data.scenes:
        for lp in list(res.paths.values()) + (
            list(res.bracket.paths.values()) if res.bracket else []
        ):
            lp.seconds *= factor
            lp.stats["seconds_samples"] = [s * factor for s in lp.stats["seconds_samples"]]
        for row in res.bench_rows:
            row["seconds"] *= factor
        for st in res.convergence:
            for row in st.rows:
                row["seconds"] *= factor
    data.wall_seconds = {k: v * factor for k, v in data.wall_seconds.items()}
    return data


def test_run_times_change_only_the_timings_files(computed, tmp_path):
    _, data = computed
    a, b = tmp_path / "a", tmp_path / "b"
    write_report(data, a)
    write_report(_slower(data, 7.3), b)
    figures = [p.name for p in a.glob("*.png") if not p.name.startswith("bench_")]
    assert len(figures) >= 8
    for name in RESULT_FILES + tuple(figures):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    assert (a / "timings.md").read_text() != (b / "timings.md").read_text()
    times_a = json.loads((a / "timings.json").read_text())["scenes"]["tiny"]["paths"]
    times_b = json.loads((b / "timings.json").read_text())["scenes"]["tiny"]["paths"]
    for ta, tb in zip(times_a, times_b):
        assert tb["seconds"] == pytest.approx(7.3 * ta["seconds"], rel=1e-12)


def test_the_opensees_comparison_goes_to_the_run_times_only(computed, tmp_path):
    _, data = computed
    write_report(data, tmp_path / "without")
    timed = copy.deepcopy(data)
    fast, slow = (0.004, 0.005, 0.006), (0.05, 0.06, 0.07)
    timed.scenes[0].peers = [
        PeerRow("F", 1, fast, slow, fast, slow, fast, slow, 1e-4),
        PeerRow("G", None, reason="OpenSees did not converge"),
    ]
    write_report(timed, tmp_path / "with")
    for name in RESULT_FILES:
        assert (tmp_path / "without" / name).read_bytes() == (
            tmp_path / "with" / name
        ).read_bytes(), name
    md = (tmp_path / "with" / "timings.md").read_text()
    assert "### beam:100 against OpenSeesPy" in md
    assert "| F | 5.0 | 60.0 | 1 | 12.00x | 12.00x | 0.0001 |" in md  # medians: 60 / 5
    assert "| G | – | – | – | OpenSees did not converge |" in md
    peers = json.loads((tmp_path / "with" / "timings.json").read_text())["scenes"]["tiny"]["peers"]
    assert peers[0]["ratio"] == pytest.approx(12.0) and peers[1] == {
        "load_case": "G",
        "substeps": None,
        "reason": "OpenSees did not converge",
    }
    timed.scenes[0].peers = "OpenSeesPy is missing or does not load (no module)"
    write_report(timed, tmp_path / "missing")
    assert (
        "Not timed: OpenSeesPy is missing or does not load (no module)."
        in (tmp_path / "missing" / "timings.md").read_text()
    )


def test_report_md_prints_no_run_time(computed, tmp_path):
    _, data = computed
    md = write_report(data, tmp_path).read_text()
    assert not [m.group(0) for m in TIMING.finditer(md)]
    assert "[timings.md](timings.md)" in md
    # the pattern does find the run times where they are
    assert TIMING.search((tmp_path / "timings.md").read_text())


def test_no_protocol_section_without_the_open_chain(computed, tmp_path):
    _, data = computed
    assert "## Dynamics" not in write_report(data, tmp_path).read_text()


def test_results_json_holds_no_time_nor_drawing_data(computed, tmp_path):
    _, data = computed
    write_report(data, tmp_path)
    results = json.loads((tmp_path / "results.json").read_text())["scenes"]["tiny"]
    for r in results["results"]:
        assert not set(LEFT_OUT) & set(r) and not set(TIMING_STATS) & set(r["stats"])
    assert all("seconds" not in row for row in results["bench"]) and results["bench"]
    # read back with the times of timings.json: the computed paths, less what is left out
    back = read_results(tmp_path)["tiny"]
    (res,) = data.scenes
    assert set(back) == set(res.paths)
    for key, lp in res.paths.items():
        assert back[key].seconds == lp.seconds
        assert (back[key].dx, back[key].rotation, back[key].poses) == (lp.dx, lp.rotation, lp.poses)


def test_two_workers_write_what_one_writes(computed, tmp_path):
    """Paths computed ahead on two processes: the same results, tables and order."""
    scene, data = computed
    two = compute_report(
        [scene],
        MODELS,
        repeats=2,
        use_cache=False,
        progress=False,
        bench=True,
        converge=True,
        workers=2,
    )
    assert two.workers == 2
    write_report(data, tmp_path / "one")
    write_report(two, tmp_path / "two")  # figures drawn on two processes too
    figures = sorted(p.name for p in (tmp_path / "one").glob("*.png"))
    assert figures == sorted(p.name for p in (tmp_path / "two").glob("*.png"))
    for name in RESULT_FILES + tuple(f for f in figures if not f.startswith("bench_")):
        assert (tmp_path / "one" / name).read_bytes() == (tmp_path / "two" / name).read_bytes()


def test_a_path_computed_in_this_run_is_not_called_cached(computed, tmp_path):
    """beam:100 runs in the campaign and again (from memory) in the bench: computed once,
    and timings.json says it was computed, not read from the disk cache."""
    _, data = computed
    write_report(data, tmp_path)
    paths = json.loads((tmp_path / "timings.json").read_text())["scenes"]["tiny"]["paths"]
    assert paths and not any(p["cached"] for p in paths)
