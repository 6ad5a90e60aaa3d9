"""Fixtures shared by the test modules."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def private_mesh_cache(tmp_path_factory):
    """Point FLEXVAL_CACHE at a fresh temporary folder for one test module.

    Modules that mesh flexures use it (``pytestmark =
    pytest.mark.usefixtures("private_mesh_cache")``) so that their meshes and
    results go to a temporary cache, never the user's.
    """
    mp = pytest.MonkeyPatch()
    mp.setenv("FLEXVAL_CACHE", str(tmp_path_factory.mktemp("flexval_cache")))
    yield
    mp.undo()
