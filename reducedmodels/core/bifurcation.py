"""Bifurcation points: where the tangent's inertia changes while the load does not turn.

Along a traced path an eigenvalue of the tangent K crosses zero at a limit
point (the load turns) and at a bifurcation point (another branch crosses
the path, the load goes on). The two are told apart by the critical mode
phi (the eigenvector of K's eigenvalue mu nearest zero) and the direction dq
the path travels there: differentiating K dq = f dlambda along the path (f:
the load vector at unit factor) and multiplying by phi gives
mu phi^T dq = phi^T f dlambda. At a limit point the load does work on the
mode (phi^T f != 0) and dlambda vanishes with mu: the path runs along the
mode. At a bifurcation phi^T f = 0: the traced branch goes on across the
mode (the crossing branch runs along it). The cosine of the angle between
dq and phi (in the scaled coordinates of :meth:`System.scaled`) decides:
below :data:`MODE_COSINE` a bifurcation, above it a limit point. (The slope
K^-1 f would tell the same in exact arithmetic, but next to the crossing
its phi-component, the round-off of phi^T f over a vanishing mu, is noise.)

Units: mm, N, N mm, rad; load factors are dimensionless.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .tangent import Tangent

if TYPE_CHECKING:
    from .system import System

BIFURCATION_RTOL = 1e-6
"""Relative width in load factor to which a bifurcation is bracketed by bisection."""

MODE_COSINE = 0.5
"""Cosine between the path's direction and the critical mode above which a crossing of
zero is a limit point (measured values in tests/test_bifurcations.py)."""

DENSE_MODES = 3000
"""Largest tangent whose critical mode is taken from a dense symmetric eigensolver;
larger (sparse) ones use shift-invert Lanczos about zero."""


def critical_mode(tangent: Tangent) -> tuple[float, np.ndarray]:
    """The eigenvalue of ``tangent`` nearest zero and its unit eigenvector.

    The eigenvector's sign is fixed: its largest entry in size is positive.
    """
    if tangent.n <= DENSE_MODES:
        values, vectors = np.linalg.eigh(tangent.toarray())
        k = int(np.argmin(np.abs(values)))
        value, mode = float(values[k]), vectors[:, k]
    else:
        import scipy.sparse.linalg as spla

        values, vectors = spla.eigsh(tangent.tosparse(), k=1, sigma=0.0, which="LM")
        value, mode = float(values[0]), vectors[:, 0]
    mode = mode / np.linalg.norm(mode)
    return value, mode if mode[np.argmax(np.abs(mode))] > 0.0 else -mode


def mode_cosine(
    system: System, tangent: Tangent, direction: np.ndarray
) -> tuple[float, np.ndarray]:
    """|cos| of the angle between the path's direction and the critical mode, and the mode.

    Parameters
    ----------
    system : System
    tangent : Tangent
        The tangent at a state next to the crossing (mu small).
    direction : array
        The path's direction there, e.g. the difference of two states on
        either side of the crossing (mm, rad).

    Returns
    -------
    (float, array)
        The cosine (in scaled coordinates; 1 when it cannot be judged) and
        the mode (unit, unscaled coordinates).
    """
    _, mode = critical_mode(tangent)
    a, b = system.scaled(direction), system.scaled(mode)
    size = float(np.linalg.norm(a) * np.linalg.norm(b))
    if not (np.isfinite(size) and size > 0.0):
        return 1.0, mode
    return abs(float(a @ b)) / size, mode


def classify(system: System, tangent: Tangent, direction: np.ndarray) -> tuple[bool, np.ndarray]:
    """Whether the zero crossing next to ``tangent`` is a bifurcation, and its critical mode.

    True when the path's ``direction`` (mm, rad) makes a cosine below
    :data:`MODE_COSINE` with the critical mode (see :func:`mode_cosine`).
    """
    cosine, mode = mode_cosine(system, tangent, direction)
    return cosine < MODE_COSINE, mode
