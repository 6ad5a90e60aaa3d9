"""flexval.validation: the continuum reference and everything that compares models.

Its rooms: :mod:`.continuum` (the reference), :mod:`.studies` (what is
compared and measured), :mod:`.report` (the validation report, one module
per section), :mod:`.sweep` (design and tolerance studies), :mod:`.cli` (the
``flexval`` command, one module per command); at the top, what they share
(running a model, the result cache, safe outputs, resources, interruption,
the VTU series and the plotting API).

Units: mm, N, N mm, MPa, rad (degrees only at the edges: files, CLI, reports).
"""

from __future__ import annotations

__all__ = ["run_model"]


def __getattr__(name: str):
    """``run_model`` from :mod:`.run`, imported on first use (PEP 562)."""
    if name == "run_model":
        from .run import run_model

        globals()[name] = run_model
        return run_model
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
