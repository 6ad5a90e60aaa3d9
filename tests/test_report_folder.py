"""Where `flexval report` writes: a folder named after its scenes, never another scene's report,
and its run times apart when asked (the results beside them are the same from run to run)."""

from __future__ import annotations

from flexval.validation.cli import main

QUICK = ["--model", "ee", "--model", "dcmm:1", "--no-bench", "--no-converge", "--no-batch"]
QUICK += ["--quiet", "--load-case", "m+", "--jobs", "1"]


def test_without_out_the_report_goes_to_a_folder_named_after_its_scene(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["report", "open_chain", *QUICK]) == 0
    assert (tmp_path / "open_chain_report" / "report.md").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["open_chain_report"]


def test_a_folder_holding_another_scenes_report_is_refused_without_force(tmp_path, capsys):
    out = tmp_path / "mine"
    assert main(["report", "open_chain", *QUICK, "--out", str(out)]) == 0
    before = (out / "report.md").read_bytes()
    argv = ["report", "closed_chain", *QUICK[:-4], "--quiet", "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "holds the report of open_chain" in err and "--force" in err
    assert (out / "report.md").read_bytes() == before  # nothing written
    assert main([*argv, "--force"]) == 0
    assert "closed_chain" in (out / "report.md").read_text()
    assert main(["report", "closed_chain", *QUICK[:-4], "--quiet", "--out", str(out)]) == 0


def test_run_times_go_apart_and_the_results_are_the_same_from_run_to_run(tmp_path):
    """What a repository commits (report.md, results.json, gates.json, figures) comes out byte
    for byte the same twice; the run times, which do not, go to --timings."""
    out, first, second = tmp_path / "report", tmp_path / "t1", tmp_path / "t2"
    assert main(["report", "open_chain", *QUICK, "--out", str(out), "--timings", str(first)]) == 0
    kept = {p.name: p.read_bytes() for p in out.iterdir()}
    assert "timings.md" not in kept and "timings.json" not in kept
    assert {"report.md", "results.json", "gates.json"} <= set(kept)
    assert (first / "timings.md").is_file() and (first / "timings.json").is_file()
    argv = ["report", "open_chain", *QUICK, "--out", str(out), "--timings", str(second)]
    assert main([*argv, "--no-cache"]) == 0
    assert {p.name: p.read_bytes() for p in out.iterdir()} == kept
