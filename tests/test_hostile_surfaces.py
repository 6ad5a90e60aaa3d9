"""Hostile inputs on the newer surfaces: notch geometry, run-mode flags, output paths,
the Python API's model ids and run files (each refused with the field and value, exit 2, or
answered right; never a traceback)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flexval.geometry.shapes import largest_along
from flexval.validation.cli import main

SCENES = Path(__file__).parent / "scenes"


def test_a_circular_notch_taller_than_its_semicircle_is_refused(tmp_path, capsys):
    """H > t + L would need cut-outs larger than half a circle: the contour took the other
    branch of the circle and modelled a strip of thickness t (a taller blank came out more
    compliant). At H = t + L (semicircles) it is accepted."""
    text = (SCENES / "notch_hinge.toml").read_text()  # t = 0.1 mm, L = 2 mm, H = 1 mm
    for height, status in (("2.1", 0), ("2.5", 2), ("40.0", 2)):
        path = tmp_path / f"notch_{height}.toml"
        path.write_text(text.replace("height = 1.0", f"height = {height}"))
        assert main(["info", str(path)]) == status
        if status:
            err = capsys.readouterr().err
            assert "flexures.hinge.height" in err and "t + L = 2.1 mm" in err


@pytest.mark.parametrize(
    "flags, field",
    [
        (["--arclength", "--dynamic"], "--arclength"),
        (["--duration", "2"], "--duration"),
        (["--damping-ratio", "0.1"], "--damping-ratio"),
        (["--rayleigh", "1", "0"], "--rayleigh"),
        (["--rho-inf", "0.5"], "--rho-inf"),
        (["--error-tol", "1e-6"], "--error-tol"),
        (["--dynamic", "--rayleigh", "1", "0", "--damping-ratio", "0.1"], "--damping-ratio"),
    ],
)
def test_run_refuses_a_flag_it_would_drop(flags, field, capsys):
    assert main(["run", "open_chain", "--model", "ee", "--load-case", "m+", *flags]) == 2
    assert f"field '{field}'" in capsys.readouterr().err


def test_two_outputs_on_one_file_are_refused(tmp_path, capsys):
    same = str(tmp_path / "out.json")
    gates = tmp_path / "gates.toml"
    gates.write_text("")
    assert main(["gate", str(gates), "--json", same, "--junit", same]) == 2
    assert "field '--junit'" in capsys.readouterr().err
    plot = str(tmp_path / "m.png")
    assert main(["modes", "open_chain", "--model", "ee", "--json", plot, "--plot", plot]) == 2


def test_parse_model_knows_the_continuum_right_after_import():
    code = "import flexval; print(flexval.parse_model('continuum:1[plane=strain]').id)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "continuum:1[plane=strain]"


def test_a_run_file_with_first_yield_reads_back_as_load_paths(tmp_path):
    from flexval.reducedmodels import LoadPath

    scene = (SCENES / "euler_column.toml").read_text()
    scene = scene.replace("poisson_ratio = 0.3", "poisson_ratio = 0.3\nyield_strength = 300.0")
    (tmp_path / "c.toml").write_text(scene.replace("value = 3.0", "value = 1.0"))
    out = tmp_path / "run.json"
    assert main(["run", str(tmp_path / "c.toml"), "--model", "beam:10", "--json", str(out)]) == 0
    (result,) = json.loads(out.read_text())["results"]
    assert "first_yield" in result and "safety_factor" in result
    (path,) = LoadPath.read_run_json(out)
    assert path.model == "beam:10" and path.dy == result["dy"]
    with pytest.raises(ValueError, match="unknown keys"):
        LoadPath.from_dict({**result, "nonsense": 1})


def test_the_largest_value_along_a_curve_is_found_between_samples():
    """A peak 1000 times narrower than the sample spacing (a spline's tight loop)."""
    width = 1e-6
    at, top = largest_along(lambda s: 1.0 / (width + (s - 0.3217) ** 2), 1.0, 32)
    assert at == pytest.approx(0.3217, abs=1e-7) and top == pytest.approx(1.0 / width, rel=1e-6)
    at, top = largest_along(lambda s: np.sin(3.0 * s), 1.0, 4)
    assert top == pytest.approx(1.0, abs=1e-12)


def test_a_report_whose_load_case_no_model_finishes_writes_everything_and_exits_3(tmp_path, capsys):
    """The leaf guide pushed past its sway load: every model stops at the bifurcation. The
    report is written whole (text, figures, results, timings) and the command exits 3."""
    out = tmp_path / "report"
    argv = ["report", str(SCENES / "leaf_guide.toml"), "--out", str(out), "--quiet"]
    argv += ["--model", "beam:20", "--model", "prbm", "--no-bench", "--no-converge"]
    assert main([*argv, "--no-batch", "--no-cache"]) == 3
    assert "no model reached the full load" in capsys.readouterr().err
    for name in ("report.md", "results.json", "gates.json", "timings.md", "timings.json"):
        assert (out / name).is_file()
    assert "bifurcation" in (out / "report.md").read_text()


def test_a_sweep_asking_for_first_yield_without_a_yield_strength_is_refused(tmp_path, capsys):
    sweep = tmp_path / "s.toml"
    sweep.write_text(
        'name = "s"\nbase = "open_chain"\nmodels = ["ee"]\nreference = "dcmm:1"\n'
        'outputs = ["first_yield"]\n[[axes]]\npath = "section.thickness"\nvalues = [0.1, 0.11]\n'
    )
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "out")]) == 2
    assert "field 'outputs'" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_a_measurement_that_is_a_device_is_refused_before_it_is_read(capsys):
    argv = ["compare", "open_chain", "--measured", "/dev/zero", "--load-case", "m+"]
    assert main([*argv, "--model", "ee"]) == 2
    assert "not a regular file" in capsys.readouterr().err


def test_a_measurement_of_too_many_rows_is_refused_without_reading_it_all(tmp_path, capsys):
    """A million rows: refused at the first row past the limit (the file is parsed no
    further), and a file larger than the byte bound before it is parsed at all."""
    from flexval.geometry.measured import MAX_BYTES, MAX_ROWS

    rows = tmp_path / "rows.csv"
    with rows.open("w") as out:
        out.write("load,dx\n")
        out.writelines(f"{k * 1e-9:.6e},{k * 1e-6:.6e}\n" for k in range(1, 1_000_001))
    argv = ["compare", "open_chain", "--load-case", "m+", "--model", "ee", "--measured"]
    assert main([*argv, str(rows)]) == 2
    assert f"line {MAX_ROWS + 2}" in capsys.readouterr().err
    large = tmp_path / "large.csv"
    with large.open("wb") as out:
        out.write(b"load,dx\n")
        out.truncate(MAX_BYTES + 1)
    assert main([*argv, str(large)]) == 2
    assert "larger than" in capsys.readouterr().err


def _two_notches(tmp_path, offset: float, extra: str = "") -> Path:
    """The notch hinge scene with a second, equal notch ``offset`` mm above the first."""
    text = (SCENES / "notch_hinge.toml").read_text()
    hinge = text[text.index("[[flexures]]") : text.index("[[load_cases]]")]
    twin = hinge.replace('name = "hinge"', f'name = "twin"{extra}')
    twin = twin.replace("start = [0.0, 0.0]", f"start = [0.0, {offset}]")
    twin = twin.replace("end = [2.0, 0.0]", f"end = [2.0, {offset}]")
    text = text.replace("[[load_cases]]", twin + "\n[[load_cases]]", 1)
    if offset:
        text = text.replace("points = [[0.0, 0.0]]", f"points = [[0.0, 0.0], [0.0, {offset}]]")
    path = tmp_path / f"twin_{offset}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("offset, status", [(0.0, 2), (0.5, 2), (1.2, 0)])
def test_notches_whose_outlines_overlap_are_refused(tmp_path, capsys, offset, status):
    """A notch on top of another (material counted twice) and one whose blank overlaps the
    other's (H = 1 mm, 0.5 mm apart) are refused; 1.2 mm apart they are two hinges."""
    assert main(["info", str(_two_notches(tmp_path, offset))]) == status
    if status:
        err = capsys.readouterr().err
        assert "flexures.twin" in err and "outline overlaps flexure 'hinge'" in err


def test_segments_crossing_at_a_sample_point_are_refused_unless_declared(tmp_path, capsys):
    """The cross-axis pivot's leaves cross at their midpoints, exactly at a sample of both
    centre lines: refused without ``crosses`` (the test was strict there), accepted with it;
    ``crosses`` naming no flexure is refused."""
    text = (SCENES / "cross_pivot.toml").read_text()
    plain = tmp_path / "plain.toml"
    plain.write_text(text.replace('crosses = ["a"]', ""))
    assert main(["info", str(plain)]) == 2
    assert "crosses flexure 'a' at (0, 10) mm" in capsys.readouterr().err
    assert main(["info", str(SCENES / "cross_pivot.toml")]) == 0
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(text.replace('crosses = ["a"]', 'crosses = ["c"]'))
    assert main(["info", str(wrong)]) == 2
    assert "flexures.b.crosses" in capsys.readouterr().err


@pytest.mark.parametrize(
    "ratio, thin_at_tip, rel",
    [
        (10.0, True, 1e-9),
        (1e2, True, 1e-9),
        (1e4, True, 1e-9),
        (10.0, False, 1e-9),
        (1e2, False, 1e-9),
        # thin at the clamped end the compliance integral is exact too; the linear solve of
        # the mechanism then meets stiffnesses 10^12 apart (measured 3.7e-5)
        (1e4, False, 1e-4),
    ],
)
def test_a_steep_taper_has_its_exact_compliance(tmp_path, ratio, thin_at_tip, rel):
    """ee's rotation under an end moment is M int ds / EI; for h linear from h0 to h1 over
    L, int ds / h^3 = L (1/h0^2 - 1/h1^2) / (2 (h1 - h0)). A taper of ratio 10^4 put 1/h^3
    through 12 decades inside the Gauss rule's first panel; split where h doubles, the
    integral is exact to round-off at every ratio."""
    h0, h1 = (1.0, 1.0 / ratio) if thin_at_tip else (1.0 / ratio, 1.0)
    text = (SCENES / "euler_column.toml").read_text()
    text = text.replace('name = "column"', f'name = "column"\nthickness = [{h0!r}, {h1!r}]', 1)
    text = text.replace(
        'kind = "force"\nbody = "tip"\npoint = [0.0, 100.0]\nangle_deg = -90.0\nvalue = 3.0',
        'kind = "moment"\nbody = "tip"\nvalue = 1e-12',
    )
    scene, out = tmp_path / "taper.toml", tmp_path / "out.json"
    scene.write_text(text)
    assert main(["run", str(scene), "--model", "ee", "--json", str(out)]) == 0
    (result,) = json.loads(out.read_text())["results"]
    e, depth, length, moment = 10000.0, 12.0, 100.0, 1e-12
    exact = moment * 12 / (e * depth) * length * (1 / h0**2 - 1 / h1**2) / (2 * (h1 - h0))
    assert result["rotation"][-1] == pytest.approx(exact, rel=rel)


def test_a_taper_steeper_than_the_arithmetic_resolves_is_refused(tmp_path, capsys):
    """10^5 : 1 put stiffnesses 10^15 apart (ee 2e-3 off M int ds / EI measured)."""
    text = (SCENES / "euler_column.toml").read_text()
    scene = tmp_path / "taper.toml"
    scene.write_text(text.replace('name = "column"', 'name = "column"\nthickness = [1e-5, 1.0]', 1))
    assert main(["info", str(scene)]) == 2
    assert "flexures.column.thickness" in capsys.readouterr().err


def test_another_sweep_over_the_same_folder_is_refused(tmp_path, capsys):
    """A sweep's folder keeps its identity (sweep.json): a changed sweep file over the same
    --out would mix two sweeps' rows; refused naming what differs. The same sweep again
    resumes (nothing run twice)."""
    first = tmp_path / "first.toml"
    first.write_text(
        'name = "s"\nbase = "open_chain"\nmodels = ["ee"]\nreference = "dcmm:1"\n'
        'load_cases = ["m+"]\n[[axes]]\npath = "section.thickness"\nvalues = [0.1, 0.11]\n'
    )
    out = tmp_path / "out"
    argv = ["--out", str(out), "--workers", "1", "--quiet"]
    assert main(["sweep", str(first), *argv]) == 0
    assert json.loads((out / "sweep.json").read_text())["models"] == ["ee"]
    capsys.readouterr()
    assert main(["sweep", str(first), *argv]) == 0
    assert "0 rows written" in capsys.readouterr().err
    second = tmp_path / "second.toml"
    second.write_text(first.read_text().replace('models = ["ee"]', 'models = ["prbm"]'))
    assert main(["sweep", str(second), *argv]) == 2
    assert "its models differ" in capsys.readouterr().err


def test_report_bench_and_stress_take_a_load_case_filter(tmp_path, capsys):
    out = tmp_path / "report"
    argv = ["report", "open_chain", "--load-case", "m+", "--out", str(out), "--quiet"]
    argv += ["--model", "beam:20", "--model", "ee", "--no-bench", "--no-converge", "--no-batch"]
    assert main(argv) == 0
    results = json.loads((out / "results.json").read_text())["scenes"]["open_chain"]["results"]
    assert {r["load_case"] for r in results} == {"m+"}
    for command in ("report", "bench", "stress"):
        assert main([command, "open_chain", "--load-case", "m0", "--out", str(tmp_path / "x")]) == 2
        assert "field '--load-case' = 'm0'" in capsys.readouterr().err
        assert not (tmp_path / "x").exists()
