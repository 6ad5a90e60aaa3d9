"""flexval: validation of flexibility models of planar compliant mechanisms.

The package's parts are :mod:`flexval.geometry` (what a mechanism is),
:mod:`flexval.reducedmodels` (the multibody core and the reduced models) and
:mod:`flexval.validation` (the continuum reference, comparisons, reports and
the ``flexval`` command). The names below are the ones a first Python call
needs; each is imported from its module on first use, so ``import flexval``
stays cheap.

Units everywhere: mm, N, MPa, N mm, s, t (mass), rad (degrees only in scene
files, on the command line and in reports).

Examples
--------
>>> import flexval
>>> scene = flexval.load_scene("open_chain")
>>> path = flexval.run_model(scene, flexval.parse_model("dcmm:2"), scene.load_cases[0])
>>> round(path.rotation[-1], 3)            # doctest: +SKIP
"""

from __future__ import annotations

from importlib import import_module

__version__ = "0.2.0"

_HOMES = {
    "load_scene": "flexval.geometry.scene",
    "Scene": "flexval.geometry.scene",
    "parse_model": "flexval.reducedmodels.catalogue",
    "LoadPath": "flexval.reducedmodels.core.loadpath",
    "read_results": "flexval.reducedmodels.core.loadpath",
    "run_model": "flexval.validation.run",
}
"""Module of each name the package offers at its top."""

_MODULES = {"plot": "flexval.validation.plotting"}
"""Modules the package offers at its top: ``flexval.plot`` draws onto Matplotlib axes."""

__all__ = ["__version__", *sorted([*_HOMES, *_MODULES])]


def __getattr__(name: str):
    """Import a top-level name from its module on first use (PEP 562)."""
    if name in _MODULES:
        value = import_module(_MODULES[name])
        globals()[name] = value
        return value
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(_HOMES[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
