"""Hardening around the computation: argument ranges, output paths, atomic writes, strict JSON.

Every class of bad input is tried with several values; each must end in the
documented exit code with a message naming the option and the value, and
before any computation (the compute entry points are replaced by functions
that fail the test if called).
"""

import dataclasses
import errno
import json
import os
import threading

import numpy as np
import pytest

import flexval.geometry.files
import flexval.validation.report.data
import flexval.validation.report.writer
import flexval.validation.run
import flexval.validation.studies.bench
import flexval.validation.studies.convergence
import flexval.validation.studies.stress
from flexval.geometry import load_scene
from flexval.geometry.files import OutputError, atomic_path
from flexval.validation.cli import EXIT_INPUT, EXIT_OUTPUT, main
from flexval.validation.outputs import (
    check_file,
    check_folder,
    inside,
    json_safe,
    output_path,
    safe_name,
    write_json,
)


def _strict_loads(text: str):
    """json.loads that refuses NaN / Infinity tokens."""

    def refuse(token):
        raise ValueError(f"non-standard JSON token {token}")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if any computation starts."""

    def forbidden(*args, **kwargs):
        raise AssertionError("computation started before the arguments were checked")

    for module, name in (
        (flexval.validation.run, "run_model"),
        (flexval.validation.studies.convergence, "study"),
        (flexval.validation.report.writer, "build_report"),
        (flexval.validation.studies.bench, "runtime_vs_error"),
        (flexval.validation.studies.stress, "stress_report"),
    ):
        monkeypatch.setattr(module, name, forbidden)


def _exit_code(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:  # argparse's own range errors
        return exc.code


# ---------------------------------------------------------------- numeric arguments


@pytest.mark.parametrize(
    "argv, shown",
    [
        (["converge", "open_chain", "--model", "dcmm", "--levels", "0:4"], "0:4"),
        (["converge", "open_chain", "--model", "beam", "--levels", "0:8"], "0:8"),
        (["converge", "open_chain", "--model", "beam", "--levels", "0:0"], "0:0"),
        (["converge", "open_chain", "--model", "beam", "--levels", "3:1"], "3:1"),
        (["converge", "open_chain", "--model", "dcmm", "--levels=-4:2"], "-4:2"),
        (["converge", "open_chain", "--model", "beam", "--levels", "5:1000000000"], "5:1000000000"),
        (["converge", "open_chain", "--model", "continuum", "--levels", "0:9"], "0:9"),
        (["converge", "open_chain", "--model", "continuum", "--levels=-1:2"], "-1:2"),
        (["converge", "open_chain", "--model", "beam", "--levels", "8,4"], "8,4"),
        (["converge", "open_chain", "--model", "beam", "--levels", "4,4"], "4,4"),
        (["converge", "open_chain", "--model", "beam", "--levels", "0,4"], "0,4"),
        (["converge", "open_chain", "--model", "beam", "--levels", "1:2:3"], "1:2:3"),
        (["converge", "open_chain", "--model", "beam", "--levels", "a:b"], "a:b"),
        (["run", "open_chain", "--model", "ee", "--levels", "20001"], "20001"),
        (["run", "open_chain", "--model", "ee", "--levels", "1000000000"], "1000000000"),
        (["run", "open_chain", "--model", "ee", "--levels", "1"], "1"),
        (["run", "open_chain", "--model", "ee", "--levels", "0"], "0"),
        (["run", "open_chain", "--model", "ee", "--levels=-3"], "-3"),
        (["report", "--repeats", "0", "--out", "{tmp}"], "0"),
        (["report", "--repeats=-2", "--out", "{tmp}"], "-2"),
        (["report", "--repeats", "1001", "--out", "{tmp}"], "1001"),
        (["bench", "open_chain", "--repeats", "0", "--out", "{tmp}"], "0"),
        (["bench", "open_chain", "--repeats", "x", "--out", "{tmp}"], "x"),
    ],
)
def test_numeric_arguments_checked_before_work(argv, shown, tmp_path, no_work, capsys):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert _exit_code(argv) == EXIT_INPUT
    err = capsys.readouterr().err
    option = next(a.split("=")[0] for a in argv if a.startswith(("--levels", "--repeats")))
    assert option in err and shown in err and "Traceback" not in err


# ---------------------------------------------------------------- output paths


def _bad_file_targets(tmp_path):
    regular = tmp_path / "regular.txt"
    regular.write_text("x")
    return {
        "missing folder": tmp_path / "missing" / "out.json",
        "a folder": tmp_path,
        "trailing slash": f"{tmp_path}/",
        "under a regular file": regular / "out.json",
        "a device (/dev/full)": "/dev/full",
        "read-only place (/proc)": "/proc/flexval-out.json",
    }


def _bad_folder_targets(tmp_path):
    regular = tmp_path / "regular.txt"
    regular.write_text("x")
    return {
        "a regular file": regular,
        "under a regular file": regular / "sub",
        "a device (/dev/full)": "/dev/full",
        "read-only place (/proc)": "/proc/flexval-out",
    }


FILE_COMMANDS = [
    ["info", "open_chain", "--json"],
    ["plot", "open_chain", "-o"],
    ["run", "open_chain", "--model", "ee", "--json"],
    ["converge", "open_chain", "--model", "dcmm", "--json"],
]
FOLDER_COMMANDS = [
    ["report", "open_chain", "--out"],
    ["bench", "open_chain", "--out"],
    ["stress", "open_chain", "--out"],
]


@pytest.mark.parametrize("command", FILE_COMMANDS, ids=lambda c: c[0])
@pytest.mark.parametrize(
    "kind",
    [
        "missing folder",
        "a folder",
        "trailing slash",
        "under a regular file",
        "a device (/dev/full)",
        "read-only place (/proc)",
    ],
)
def test_bad_output_file_refused_before_work(command, kind, tmp_path, no_work, capsys, monkeypatch):
    import flexval.validation.report.drawing

    monkeypatch.setattr(
        flexval.validation.report.drawing,
        "plot_mechanism",
        lambda *a: pytest.fail("plotted before checking the output"),
    )
    target = str(_bad_file_targets(tmp_path)[kind])
    assert _exit_code(command + [target]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert command[-1] in err and target in err and "Traceback" not in err
    assert not any(p.name.startswith(".") for p in tmp_path.iterdir())  # no temp files left


@pytest.mark.parametrize("command", FOLDER_COMMANDS, ids=lambda c: c[0])
@pytest.mark.parametrize(
    "kind",
    ["a regular file", "under a regular file", "a device (/dev/full)", "read-only place (/proc)"],
)
def test_bad_output_folder_refused_before_work(command, kind, tmp_path, no_work, capsys):
    target = str(_bad_folder_targets(tmp_path)[kind])
    assert _exit_code(command + [target]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "--out" in err and target in err and "Traceback" not in err


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write into a read-only folder")
@pytest.mark.parametrize(
    "check",
    [lambda p: check_file(p / "x.json", "--json"), lambda p: check_folder(p / "sub", "--out")],
)
def test_read_only_folder_refused(check, tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        with pytest.raises(Exception, match="--json|--out"):
            check(ro)
    finally:
        ro.chmod(0o755)


def test_missing_output_folder_is_created(tmp_path):
    folder = tmp_path / "a" / "b"
    assert check_folder(folder, "--out") == folder and folder.is_dir()
    assert list(folder.iterdir()) == []  # the probe file is gone


def test_write_failure_after_check_is_exit_4(tmp_path, monkeypatch, capsys):
    """A write that fails once the work is done (here: ENOSPC at fsync) exits 4, no temp left."""
    out = tmp_path / "r.json"
    out.write_text("previous")

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(flexval.geometry.files.os, "fsync", full)
    code = main(
        [
            "run",
            "open_chain",
            "--model",
            "ee",
            "--load-case",
            "f+",
            "--levels",
            "3",
            "--json",
            str(out),
        ]
    )
    assert code == EXIT_OUTPUT
    err = capsys.readouterr().err
    assert str(out) in err and os.strerror(errno.ENOSPC) in err
    assert out.read_text() == "previous"  # target untouched
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]  # temp file removed


@pytest.mark.parametrize("error", [KeyboardInterrupt, ValueError, OSError])
def test_atomic_path_leaves_target_and_no_temp_on_failure(error, tmp_path):
    target = tmp_path / "t.txt"
    target.write_text("old")
    with pytest.raises((error, OutputError)):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise error("boom")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["t.txt"]


def test_atomic_path_concurrent_writers_use_distinct_temporaries(tmp_path):
    target = tmp_path / "same.json"
    barrier, temps, errors = threading.Barrier(8), [], []

    def writer(k):
        try:
            with atomic_path(target) as tmp:
                temps.append(tmp)
                barrier.wait()
                tmp.write_text(json.dumps({"writer": k}))
        except Exception as exc:  # noqa: BLE001 - collected and asserted below
            errors.append(exc)

    threads = [threading.Thread(target=writer, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and len(set(temps)) == 8
    assert _strict_loads(target.read_text())["writer"] in range(8)
    assert [p.name for p in tmp_path.iterdir()] == ["same.json"]


def test_written_file_has_umask_permissions(tmp_path):
    mask = os.umask(0o022)
    try:
        path = write_json(tmp_path / "p.json", {"a": 1})
    finally:
        os.umask(mask)
    assert path.stat().st_mode & 0o777 == 0o644


# ---------------------------------------------------------------- strict JSON


@pytest.mark.parametrize(
    "bad",
    [
        float("nan"),
        float("inf"),
        -float("inf"),
        np.float64("nan"),
        np.float32("inf"),
        np.array([1.0, np.nan]),
    ],
)
def test_json_writer_turns_non_finite_into_null(bad, tmp_path):
    data = {"x": bad, "nested": [{"y": bad}, (bad, 1.5)], "ok": np.int64(3)}
    text = write_json(tmp_path / "d.json", data).read_text()
    got = _strict_loads(text)
    assert got["ok"] == 3 and got["nested"][1][1] == 1.5
    flat = json.dumps(got)
    assert "NaN" not in flat and "Infinity" not in flat and "null" in flat
    assert json_safe(1.25) == 1.25


@pytest.mark.parametrize("levels", ["1,3,4", "1,2,5", "1,2,6"])
def test_converge_json_is_strict_and_ratio_null_when_undefined(levels, tmp_path):
    out = tmp_path / "c.json"
    assert (
        main(
            [
                "converge",
                "open_chain",
                "--model",
                "dcmm",
                "--levels",
                levels,
                "--load-case",
                "m+",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    study = _strict_loads(out.read_text())["studies"][0]
    assert study["ratio"] is None
    assert len(study["rows"]) == len(levels.split(","))


# ---------------------------------------------------------------- safe file names

HOSTILE = [
    "../escaped",
    "a/b",
    "/etc/passwd",
    "..",
    ".",
    "",
    "~",
    "a\x00b",
    "..\\..\\x",
    "-rf",
    ".hidden",
    "x" * 300,
    "über näme",
    "a/../../b",
    "CON",
    "f+",
]


@pytest.mark.parametrize("name", HOSTILE)
def test_safe_name_is_one_harmless_component(name, tmp_path):
    s = safe_name(name)
    assert s and "/" not in s and "\\" not in s and "\x00" not in s
    assert s not in (".", "..") and not s.startswith((".", "-"))
    assert len(s.encode()) <= 100
    path = output_path(tmp_path, f"{name}_paths", ".png")
    assert path.parent == tmp_path.resolve()


def test_safe_names_keep_plain_names_and_stay_distinct():
    for plain in ("open_chain", "closed_chain", "f+", "m-", "bench_open_chain"):
        assert safe_name(plain) == plain
    assert len({safe_name(n) for n in HOSTILE}) == len(HOSTILE)
    assert safe_name("a/b") != safe_name("a_b")


def test_inside_refuses_symlinks_and_dotdot(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "link").symlink_to(tmp_path)
    for name in ("link/x.png", "../x.png", "/tmp/x.png"):
        with pytest.raises(OutputError, match="outside"):
            inside(out, name)


def _hostile_scene(name: str, case_name: str):
    sc = load_scene("open_chain")
    cases = tuple(
        dataclasses.replace(lc, name=f"{case_name}{k}", levels=3)
        for k, lc in enumerate(sc.load_cases[:2])
    )
    return dataclasses.replace(sc, name=name, load_cases=cases)


@pytest.mark.parametrize(
    "name, case_name", [("../escaped", "../c"), ("a/b", "x/y"), ("/abs/olute", ".."), ("..", "/")]
)
def test_report_writes_only_inside_its_folder(name, case_name, tmp_path, monkeypatch):
    scene = _hostile_scene(name, case_name)
    monkeypatch.setattr(flexval.validation.report.data, "load_scene", lambda _: scene)
    out = tmp_path / "deep" / "out"
    md = flexval.validation.report.writer.build_report(
        ["hostile"],
        out,
        ["beam:20", "ee"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    assert md.parent == out
    written = {p for p in tmp_path.rglob("*") if p.is_file()}
    assert written and all(out in p.parents for p in written)
    pngs = [p for p in written if p.suffix == ".png"]
    assert len(pngs) >= 3
    text = md.read_text()
    for p in pngs:  # every figure is linked under its safe name
        assert f"({p.name})" in text


@pytest.mark.parametrize("name", ["../escaped", "a/b", ".."])
def test_bench_and_stress_files_stay_inside(name, tmp_path, monkeypatch):
    scene = _hostile_scene(name, "c")
    out = tmp_path / "out"
    rows = [{"model": "ee", "seconds": 1e-3, "error": 1.0, "per_case": {}}]
    md = flexval.validation.studies.bench.write_bench(scene, rows, "beam:20", out)
    report = {"scene": name, "models": {}}
    monkeypatch.setattr(
        flexval.validation.studies.stress, "format_markdown", lambda r: "# stress\n"
    )
    smd, sjs = flexval.validation.studies.stress.write_stress(report, out)
    for p in tmp_path.rglob("*"):
        if p.is_file():
            assert out in p.parents
    assert md.parent == out.resolve() and smd.parent == out.resolve()
    assert _strict_loads(sjs.read_text())["scene"] == name


@pytest.mark.parametrize("name", ["m.xyz", "m.png.exe", "m.json"])
def test_plot_refuses_unknown_picture_formats(name, tmp_path, capsys, monkeypatch):
    import flexval.validation.report.drawing

    monkeypatch.setattr(
        flexval.validation.report.drawing,
        "plot_mechanism",
        lambda *a: pytest.fail("plotted before checking the output"),
    )
    assert main(["plot", "open_chain", "-o", str(tmp_path / name)]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "--output" in err and name in err and "format" in err


@pytest.mark.parametrize("name", ["m.svg", "m.pdf", "m"])
def test_plot_writes_other_known_formats(name, tmp_path):
    assert main(["plot", "open_chain", "-o", str(tmp_path / name)]) == 0
    assert (tmp_path / name).stat().st_size > 0
    assert [p.name for p in tmp_path.iterdir()] == [name]


@pytest.mark.parametrize(
    "kind",
    ["a regular file", "under a regular file", "a device (/dev/full)", "read-only place (/proc)"],
)
def test_run_out_dir_for_fields_refused_before_work(kind, tmp_path, no_work, capsys):
    from importlib import resources

    text = resources.files("flexval.geometry").joinpath("scenes", "closed_chain.toml").read_text()
    scene = tmp_path / "s.toml"
    scene.write_text(
        text.replace('models = ["beam:100"', 'outputs = ["vtu", "png"]\nmodels = ["beam:100"')
    )
    target = str(_bad_folder_targets(tmp_path)[kind])
    assert main(["run", str(scene), "--model", "continuum:0", "--out-dir", target]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "--out-dir" in err and target in err


@pytest.mark.parametrize(
    "command",
    [
        ["report", "no_such_scene"],
        ["bench", "no_such_scene"],
        ["stress", "open_chain", "--model", "nonsense:3"],
    ],
    ids=lambda c: c[0],
)
def test_bad_input_creates_no_output_folder(command, tmp_path, no_work):
    out = tmp_path / "new" / "out"
    assert main(command + ["--out", str(out)]) == EXIT_INPUT
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize(
    "option, name", [("--json", "x/none.json"), ("--plot", "m.xyz"), ("--plot", "x/none.png")]
)
def test_modes_outputs_refused_before_work(option, name, tmp_path, capsys, monkeypatch):
    import flexval.validation.studies.modes

    monkeypatch.setattr(
        flexval.validation.studies.modes,
        "run_modes",
        lambda *a: pytest.fail("computed before checking the output"),
    )
    target = str(tmp_path / name)
    assert main(["modes", "open_chain", "--model", "ee", option, target]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert option in err and target in err
