"""One flexure density for every analysis with masses: ``flexval modes``,
``flexval run --dynamic`` and the report's natural frequencies all go through
:func:`flexval.validation.studies.modes.choose_density`."""

from __future__ import annotations

import json

import pytest

from flexval.geometry import SceneError, load_scene
from flexval.geometry.inertia import PLA_DENSITY
from flexval.validation.cli import EXIT_INPUT, main
from flexval.validation.studies.modes import choose_density

#: a cantilever segment whose tip body has its own mass data and the material no density
MASSIVE_BODY = """
name = "tip_mass"
[material]
youngs_modulus = 2100.0
poisson_ratio = 0.35
[section]
depth = 1.0
thickness = 0.1
[ground]
name = "1"
points = [[0.0, 0.0]]
[target]
body = "2"
point = [10.0, 0.0]
[[flexures]]
name = "s"
bodies = ["1", "2"]
shape = "segment"
start = [0.0, 0.0]
end = [10.0, 0.0]
[[bodies]]
name = "2"
mass = 1.0e-9
inertia = 1.0e-8
center_of_mass = [11.0, 0.0]
[[load_cases]]
name = "m"
kind = "moment"
value = 1.0e-4
"""


def test_the_choice_and_its_source():
    """Scene's density, else --density (which replaces the scene's), else the
    default (the report's); a massless scene without any is refused naming --density
    with PLA's value as an example."""
    chain = load_scene("open_chain")  # no density, bodies without mass data
    assert chain.mechanism.inertia.density is None
    with pytest.raises(SceneError) as err:
        choose_density(chain, None, what="a modal analysis")
    assert err.value.field == "--density" and err.value.value is None
    assert f"--density {PLA_DENSITY:g} (PLA)" in str(err.value)
    assert "2, 3, 4" in str(err.value) and "material.density" in str(err.value)

    scene, choice = choose_density(chain, None, PLA_DENSITY)
    assert (choice.density, choice.source) == (PLA_DENSITY, "default")
    assert scene.mechanism.inertia.density == PLA_DENSITY
    assert "PLA" in choice.describe() and "default" in choice.describe()

    scene, choice = choose_density(chain, 2.0e-9)
    assert (choice.density, choice.source) == (2.0e-9, "--density")
    _, again = choose_density(scene, None, PLA_DENSITY)
    assert (again.density, again.source) == (2.0e-9, "scene")
    _, replaced = choose_density(scene, 3.0e-9, PLA_DENSITY)
    assert (replaced.density, replaced.source) == (3.0e-9, "--density")
    with pytest.raises(SceneError, match="'--density' = 1240"):
        choose_density(chain, 1240.0)


def test_bodies_with_mass_and_no_density_keep_massless_flexures(tmp_path):
    """Nothing is missing when every moving body has mass data: the command runs
    with massless flexures and says so; the report still assumes PLA."""
    path = tmp_path / "tip_mass.toml"
    path.write_text(MASSIVE_BODY, encoding="utf-8")
    scene = load_scene(path)
    same, choice = choose_density(scene, None)
    assert same is scene and (choice.density, choice.source) == (None, "none")
    out = tmp_path / "modes.json"
    assert main(["modes", str(path), "--model", "beam:4", "--count", "1", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["density"] == {"value": None, "source": "none"}
    assert choose_density(scene, None, PLA_DENSITY)[1].source == "default"


def test_modes_cli_and_report_agree_on_a_massless_scene(tmp_path, capsys):
    """``flexval modes open_chain --model dcmm:2`` refuses (exit 2, naming --density and
    PLA); with ``--density`` PLA it gives exactly the report's frequencies, and the
    report's section says which density it assumed, in the same words."""
    from flexval.validation.report import frequencies

    assert main(["modes", "open_chain", "--model", "dcmm:2"]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "field '--density' = None" in err and f"{PLA_DENSITY:g} (PLA)" in err, err
    assert "Traceback" not in err

    out = tmp_path / "modes.json"
    args = ["modes", "open_chain", "--model", "dcmm:2", "--count", "4", "--json", str(out)]
    assert main([*args, "--density", repr(PLA_DENSITY)]) == 0
    record = json.loads(out.read_text())
    assert record["density"] == {"value": PLA_DENSITY, "source": "--density"}
    assert "given by --density" in capsys.readouterr().out

    table = frequencies.frequency_data(load_scene("open_chain"), ["dcmm:2"], "dcmm:2")
    assert table.frequencies["dcmm:2"] == record["frequencies_hz"]
    assert (table.density.density, table.density.source) == (PLA_DENSITY, "default")
    text = "\n".join(frequencies.section(table))
    assert table.density.describe("t/mm³") in text
    assert "flexures of PLA (1.24e-09 t/mm³, the default: the scene gives no material.density)" in (
        text
    )


def test_dynamic_run_refuses_a_massless_scene_and_takes_density(capsys):
    """``flexval run --dynamic`` makes the same choice: refused naming --density before
    any output, run with it; ``--density`` without ``--dynamic`` is refused."""
    base = ["run", "open_chain", "--model", "dcmm:1", "--load-case", "m+", "--dynamic"]
    assert main([*base, "--duration", "0.01"]) == EXIT_INPUT
    captured = capsys.readouterr()
    assert "field '--density' = None" in captured.err and "a dynamic run" in captured.err
    assert captured.out == ""
    assert main([*base, "--duration", "0.01", "--density", "1.24e-9"]) == 0
    assert "given by --density" in capsys.readouterr().out
    assert main(base[:-1] + ["--density", "1.24e-9"]) == EXIT_INPUT
    assert "applies to --dynamic only" in capsys.readouterr().err
