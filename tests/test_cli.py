"""The flexval command line: info, plot and run, JSON output and exit codes."""

import json
from pathlib import Path

import numpy as np
import pytest

from flexval.reducedmodels import LoadPath
from flexval.validation.cli import main


@pytest.mark.parametrize("scene", ["open_chain", "closed_chain"])
def test_info_text_and_json(scene, tmp_path, capsys):
    out = tmp_path / "info.json"
    assert main(["info", scene, "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "e12" in text and "target" in text
    info = json.loads(out.read_text())
    assert info["scene"] == scene
    for f in info["flexures"]:
        assert {"w_per_Nmm", "C_mm", "a_mm", "b_mm"} <= set(f["ellipse"])
        assert f["length_mm"] > 0 and f["EI_Nmm2"] > 0


def test_plot_writes_png(tmp_path):
    out = tmp_path / "m.png"
    assert main(["plot", "closed_chain", "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_run_json_contract(tmp_path, capsys):
    out = tmp_path / "r.json"
    code = main(
        [
            "run",
            "open_chain",
            "--model",
            "ee",
            "--model",
            "dcmm:1",
            "--load-case",
            "f+",
            "--levels",
            "5",
            "--json",
            str(out),
        ]
    )
    assert code == 0
    data = json.loads(out.read_text())
    assert data["scene"] == "open_chain"
    assert [r["model"] for r in data["results"]] == ["ee", "dcmm:1"]
    for r in data["results"]:
        assert r["load_case"] == "f+" and r["converged"] is True
        assert len(r["load"]) == len(r["dx"]) == len(r["dy"]) == len(r["rotation"]) == 5
        np.testing.assert_allclose(r["load"], np.linspace(0, 3e-3, 5))
        assert r["seconds"] > 0 and isinstance(r["stats"], dict)
        lp = LoadPath.from_dict(r)
        assert LoadPath.from_json(lp.to_json()) == lp


def test_run_solver_failure_exit_3(monkeypatch, capsys):
    # a sub-step budget of 3 cannot follow the soft stretch of f-
    import flexval.reducedmodels.models as models
    from flexval.reducedmodels.core.settings import SolverSettings

    monkeypatch.setattr(models, "SolverSettings", lambda: SolverSettings(max_substeps=3))
    code = main(["run", "open_chain", "--model", "dcmm:1", "--load-case", "f-"])
    assert code == 3
    err = capsys.readouterr().err
    assert "last converged load" in err and "f-" in err and "sub-steps" in err


def test_run_writes_requested_continuum_fields(tmp_path):
    from importlib import resources

    text = resources.files("flexval.geometry").joinpath("scenes", "closed_chain.toml").read_text()
    scene = tmp_path / "s.toml"
    scene.write_text(
        text.replace('models = ["beam:100"', 'outputs = ["vtu", "png"]\nmodels = ["beam:100"')
    )
    out = tmp_path / "fields"
    assert (
        main(
            [
                "run",
                str(scene),
                "--model",
                "continuum:0",
                "--load-case",
                "f+",
                "--levels",
                "3",
                "--out-dir",
                str(out),
            ]
        )
        == 0
    )
    assert list(out.glob("*.vtu")) and list(out.glob("*.png"))
    # a beam model has no stress field to write: a named input error
    assert main(["run", str(scene), "--model", "beam:10", "--out-dir", str(out)]) == 2


def test_info_gives_the_masses_density_strengths_and_gravity(tmp_path, capsys):
    """A uniform leaf's mass is rho b h L (computed here by hand); a body's mass data and the
    material's strengths are shown as the scene gives them."""
    import json as _json

    text = (Path(__file__).parent / "scenes" / "leaf_guide.toml").read_text()
    text = text.replace(
        "[material]",
        "[material]\ndensity = 7.85e-9\nyield_strength = 1200.0\nfatigue_strength = 500.0",
    )
    scene = tmp_path / "heavy.toml"
    scene.write_text(text)
    out = tmp_path / "info.json"
    assert main(["info", str(scene), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "density = 7.85e-09 t/mm3" in printed and "yield strength = 1200 MPa" in printed
    assert "fatigue strength = 500 MPa" in printed and "flexure masses:" in printed
    info = _json.loads(out.read_text())
    assert info["material"]["yield_strength_MPa"] == 1200.0
    for f in info["flexures"]:
        assert f["mass_t"] == pytest.approx(
            7.85e-9 * f["b_mm"] * f["h_mm"] * f["length_mm"], rel=1e-12
        )


def test_run_prints_the_continuums_fibre_peak_on_a_notch_and_says_so(tmp_path, capsys):
    """On a notch hinge the continuum's printed peak is its surface fibre stress (the figure its
    first yield is judged by, in the JSON as ``fibre_stress``), not the beam formula of its
    section forces, and the line says which; a uniform flexure's peak is the beam formula."""
    import json as _json

    from flexval.validation.report.tables import sig

    out = tmp_path / "n.json"
    argv = ["run", "notch_fourbar", "--model", "continuum:0", "--load-case", "f+"]
    assert main([*argv, "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    lp = _json.loads(out.read_text())["results"][0]
    fibre = max(entry["path_stress"][-1] for entry in lp["fibre_stress"].values())
    beam = max(values[-1] for values in lp["peak_stress"].values())
    assert fibre > beam * 1.02  # the notch's stress concentration
    line = next(x for x in printed.splitlines() if x.startswith("continuum:0"))
    assert f"{sig(fibre)}*" in line and "surface fibre stress at the notch" in printed
    assert main(["run", "open_chain", "--model", "continuum:0", "--load-case", "m+"]) == 0
    assert "*" not in capsys.readouterr().out
