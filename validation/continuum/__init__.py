"""Continuum reference: flexures as 2D plane-stress hyperelastic solids (Gmsh + scikit-fem).

Each flexure is a structured quad9 mesh (:mod:`geometry.mesh`) whose end
faces move rigidly with the bodies they are attached to; it is a connector
of the multibody core (:mod:`.connector`), so the reference is solved by the
same Newton iteration and load stepping as the reduced models, open or
closed chain alike, and returns the same :class:`reducedmodels.LoadPath`.

Modules: :mod:`.material` (hyperelastic laws), :mod:`.solid` (total
Lagrangian energy, forces and tangent of one mesh), :mod:`.connector`
(rigid end faces, chain rule to the body poses), :mod:`.run`
(:func:`run_continuum`, :data:`DEFAULT_LEVEL`), :mod:`.output` (VTU, PNG).
Units: mm, N, MPa, N mm, rad.
"""

from .connector import ContinuumConnector
from .run import DEFAULT_LEVEL, run_continuum

__all__ = ["ContinuumConnector", "DEFAULT_LEVEL", "run_continuum"]
