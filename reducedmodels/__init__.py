"""flexval.reducedmodels: the paper's reduced flexibility models on one multibody core.

Importing the package loads nothing: each name below is imported from its
module on first use (PEP 562), and the catalogue declares the model families
the first time it is asked for one, so a command that only reads the
catalogue does not load the solver core and scipy.

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

from importlib import import_module

_HOMES = {
    "Family": "catalogue",
    "ModelSpec": "catalogue",
    "Option": "catalogue",
    "Resolution": "catalogue",
    "family": "catalogue",
    "parse_model": "catalogue",
    "register": "catalogue",
    "Connector": "core.connector",
    "PluginFailure": "core.settings",
    "SolverError": "core.settings",
    "SolverSettings": "core.settings",
    "System": "core.system",
    "LoadPath": "core.loadpath",
    "Loads": "core.loads",
    "build_system": "models",
    "run_reduced": "models",
    "PathRecorder": "core.recorder",
    "solve_path": "core.recorder",
    "LoadControl": "core.tracer",
    "PathPoint": "core.tracer",
    "trace": "core.tracer",
}
"""Module (within the package) of each public name."""

__all__ = sorted(_HOMES)


def __getattr__(name: str):
    """Import a public name from its module on first use (PEP 562)."""
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(f".{_HOMES[name]}", __name__), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
