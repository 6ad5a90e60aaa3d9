"""The installed flexval is one import namespace: ``flexval.*`` and nothing else at the top."""

from __future__ import annotations

import subprocess
import sys
from importlib import metadata

import flexval

PROBE = """
import importlib, json
out = {}
for name in ("flexval.geometry", "flexval.reducedmodels", "flexval.validation",
             "geometry", "reducedmodels", "validation"):
    try:
        importlib.import_module(name)
        out[name] = True
    except ImportError:
        out[name] = False
print(json.dumps(out))
"""


def test_only_the_flexval_namespace_imports_outside_the_checkout(tmp_path):
    """From a folder outside the checkout the parts import as flexval.*, the bare names fail."""
    done = subprocess.run(
        [sys.executable, "-c", PROBE], cwd=tmp_path, capture_output=True, text=True, check=True
    )
    imported = __import__("json").loads(done.stdout)
    assert imported == {
        "flexval.geometry": True,
        "flexval.reducedmodels": True,
        "flexval.validation": True,
        "geometry": False,
        "reducedmodels": False,
        "validation": False,
    }


def test_distribution_declares_one_top_level_package():
    """The installed distribution puts one package at the top of sys.path: flexval.

    A wheel lists its top-level packages in ``top_level.txt``; an editable
    install maps them in its import finder, which must map ``flexval`` alone
    (to the checkout's root).
    """
    dist = metadata.distribution("flexval")
    assert (dist.read_text("top_level.txt") or "").split() == ["flexval"]
    finders = [f for f in dist.files or [] if f.name.endswith("_finder.py")]
    for finder in finders:
        text = finder.read_text()
        mapping = text[text.index("MAPPING") : text.index("\n", text.index("MAPPING"))]
        assert "'flexval'" in mapping and mapping.count(": '") == 1, mapping


def test_version_is_the_distribution_version_and_the_cli_prints_it():
    assert flexval.__version__ == metadata.version("flexval")
    done = subprocess.run(
        [sys.executable, "-m", "flexval.validation.cli", "--version"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert done.stdout.strip() == f"flexval {flexval.__version__}"


def test_top_level_names_resolve_lazily_to_their_modules():
    """The names a first call needs are the package modules' own objects."""
    from flexval.geometry.scene import load_scene
    from flexval.reducedmodels.catalogue import parse_model
    from flexval.reducedmodels.core.loadpath import LoadPath
    from flexval.validation.run import run_model

    assert flexval.load_scene is load_scene
    assert flexval.parse_model is parse_model
    assert flexval.LoadPath is LoadPath
    assert flexval.run_model is run_model
    assert set(flexval.__all__) >= {"load_scene", "parse_model", "LoadPath", "run_model"}
