"""Continuum reference: flexures as 2D plane-stress hyperelastic solids (Gmsh + scikit-fem).

Each flexure is a structured quad9 mesh (:mod:`flexval.geometry.mesh`) whose end
faces move rigidly with the bodies they are attached to; it is a connector
of the multibody core (:mod:`.connector`), so the reference is solved by the
same Newton iteration and load stepping as the reduced models, open or
closed chain alike, and returns the same :class:`reducedmodels.LoadPath`.

Modules: :mod:`.family` (the ``continuum`` model family of the catalogue,
:data:`DEFAULT_LEVEL`), :mod:`.material` (hyperelastic laws), :mod:`.solid`
(total Lagrangian energy, forces and tangent of one mesh), :mod:`.connector`
(rigid end faces, chain rule to the body poses), :mod:`.run`
(:func:`run_continuum`), :mod:`.output` (VTU, PNG). The solver modules are
imported on first use of ``ContinuumConnector`` or ``run_continuum``, so
registering the family costs no scikit-fem import. Units: mm, N, MPa, N mm, rad.
"""

from .level import DEFAULT_LEVEL

__all__ = ["ContinuumConnector", "DEFAULT_LEVEL", "run_continuum"]


def __getattr__(name: str):
    """Import the solver modules on first use (PEP 562)."""
    if name == "ContinuumConnector":
        from .connector import ContinuumConnector

        return ContinuumConnector
    if name == "run_continuum":
        from .run import run_continuum

        return run_continuum
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
