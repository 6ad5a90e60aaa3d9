"""Model families from installed packages (entry-point group ``flexval.families``).

The plug-in package of ``tests/plugin_example/`` (its ``pyproject.toml`` and
module) is "installed" in a subprocess by putting its distribution metadata,
a ``*.dist-info`` folder with the ``entry_points.txt`` that ``pip install``
would write, on ``sys.path``: ``importlib.metadata`` finds it as it finds an
installed package. Checked: ``flexval models`` lists the family with its
package, ``flexval gate`` gates it, and a plug-in that clashes with a
built-in family or fails to load exits 2 naming its package.

The plug-in's spring is the ellipse of elasticity with linearised rigid
motions: under the open chain's pure end moment its rotation is linear in the
load and equals the linear ``ee`` model's to round-off
(``examples/custom_family.py``), which the gate checks.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PLUGIN = ROOT / "tests" / "plugin_example"
PACKAGE = "flexval-ellipse-spring"


def _install(site: Path, package: str, entry_points: str) -> None:
    """Write the distribution metadata of ``package`` into the folder ``site``."""
    info = site / f"{package.replace('-', '_')}-0.1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {package}\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text(f"[flexval.families]\n{entry_points}\n")


def _flexval(site: Path, tmp_path: Path, *argv: str) -> subprocess.CompletedProcess:
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), str(PLUGIN)]),
        "FLEXVAL_CACHE": str(tmp_path / "cache"),
        "OPENBLAS_NUM_THREADS": "1",
    }
    return subprocess.run(
        [sys.executable, "-m", "flexval.validation.cli", *argv],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
    )


def _entry_point_of_the_example() -> str:
    """The ``[project.entry-points."flexval.families"]`` line of the example's pyproject."""
    import tomllib

    project = tomllib.loads((PLUGIN / "pyproject.toml").read_text())["project"]
    assert project["name"] == PACKAGE
    ((name, value),) = project["entry-points"]["flexval.families"].items()
    return f"{name} = {value}"


def test_an_installed_plugin_is_listed_and_gated(tmp_path):
    site = tmp_path / "site"
    _install(site, PACKAGE, _entry_point_of_the_example())
    listing = tmp_path / "models.json"
    proc = _flexval(site, tmp_path, "models", "--json", str(listing))
    assert proc.returncode == 0, proc.stderr
    assert "ellipse-spring" in proc.stdout and PACKAGE in proc.stdout
    records = {f["name"]: f for f in json.loads(listing.read_text())["families"]}
    assert records["ellipse-spring"]["plugin"] == PACKAGE
    assert records["beam"]["plugin"] is None

    (tmp_path / "gates.toml").write_text(
        'reference = "ee"\nscenes = ["open_chain"]\nload_cases = ["m+", "m-"]\n'
        '[[gates]]\nmodel = "ellipse-spring"\nend_rot = 1e-9\npath_rot = 1e-9\n'
    )
    proc = _flexval(site, tmp_path, "gate", "gates.toml", "--json", "g.json", "--workers", "1")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = json.loads((tmp_path / "g.json").read_text())["results"]
    assert len(rows) == 4 and all(r["passed"] for r in rows)
    # the plug-in's paths are never cached (the cache key holds flexval's code, not theirs)
    entries = list((tmp_path / "cache" / "results").iterdir())
    assert len(entries) == 2  # the reference's two paths


def test_a_plugin_clashing_with_a_builtin_family_exits_2_naming_its_package(tmp_path):
    site = tmp_path / "site"
    (site / "clash_plugin.py").parent.mkdir(parents=True)
    (site / "clash_plugin.py").write_text(
        "from flexval.reducedmodels import Family, register\n"
        "register(Family('beam', 'not the beam', lambda *a, **k: None))\n"
    )
    _install(site, "flexval-clash", "beam = clash_plugin")
    for argv in (["models"], ["run", "open_chain", "--model", "no-such-family"]):
        proc = _flexval(site, tmp_path, *argv)
        assert proc.returncode == 2, proc.stderr
        assert "flexval-clash" in proc.stderr and "built-in family" in proc.stderr
        assert "Traceback" not in proc.stderr


def test_a_plugin_that_fails_to_load_exits_2_naming_its_package(tmp_path):
    site = tmp_path / "site"
    _install(site, "flexval-broken", "broken = no_such_module_anywhere")
    proc = _flexval(site, tmp_path, "models")
    assert proc.returncode == 2
    assert "flexval-broken" in proc.stderr and "no_such_module_anywhere" in proc.stderr
    assert "Traceback" not in proc.stderr
    # a command naming built-in models only never looks at the plug-ins
    proc = _flexval(site, tmp_path, "run", "open_chain", "--model", "ee", "--load-case", "m+")
    assert proc.returncode == 0, proc.stderr


def test_a_plugin_that_exits_or_interrupts_on_import_never_makes_a_command_succeed(tmp_path):
    """``sys.exit(0)`` or a raised ``KeyboardInterrupt`` in a plug-in's module: exit 2 naming
    the package, never 0 (a gate that checked nothing must not pass) and no traceback."""
    for name, body in (
        ("exits", "import sys\nsys.exit(0)\n"),
        ("stops", "raise KeyboardInterrupt\n"),
    ):
        site = tmp_path / name
        (site / f"plugin_{name}.py").parent.mkdir(parents=True, exist_ok=True)
        (site / f"plugin_{name}.py").write_text(body)
        _install(site, f"flexval-{name}", f"{name} = plugin_{name}")
        proc = _flexval(site, tmp_path, "models")
        assert proc.returncode == 2, proc.stderr
        assert f"flexval-{name}" in proc.stderr and "Traceback" not in proc.stderr


def test_a_plugin_family_that_raises_on_a_scene_is_a_solver_failure_naming_its_package(
    tmp_path,
):
    """The example spring refuses straight flexures (an error raised by its connector): on
    a scene of straight leaves ``flexval run`` exits 3 naming the package, and so does
    ``flexval gate``, with no verdict (exit 1 would say the model was judged and failed);
    never a traceback."""
    site = tmp_path / "site"
    _install(site, PACKAGE, _entry_point_of_the_example())
    guide = str(ROOT / "tests" / "scenes" / "leaf_guide.toml")
    proc = _flexval(site, tmp_path, "run", guide, "--model", "ellipse-spring")
    assert proc.returncode == 3, proc.stderr
    assert PACKAGE in proc.stderr and "Traceback" not in proc.stderr
    light = tmp_path / "guide.toml"  # below its sway load: the reference reaches full load
    light.write_text(Path(guide).read_text().replace("value = 150.0", "value = 10.0"))
    (tmp_path / "gates.toml").write_text(
        f'reference = "beam:20"\nscenes = ["{light}"]\n'
        '[[gates]]\nmodel = "ellipse-spring"\nend_rot = 1e-9\n'
    )
    proc = _flexval(site, tmp_path, "gate", "gates.toml", "--workers", "1", "--json", "g.json")
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert PACKAGE in proc.stderr and "solver failure" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "g.json").exists()  # no verdict on a model whose code broke
