"""Linearised buckling: critical load factors and buckling modes about an equilibrium.

Along a load path q(lambda) the tangent is K(lambda) = K(q(lambda), lambda).
About the equilibrium at load factor a it is linearised as
K(a + mu) ~ K_a + mu K'_a, with K'_a = dK/dlambda along the path's slope
dq/dlambda = K_a^-1 f (f: the load vector at unit factor). The path loses
stability where K_a + mu K'_a turns singular, the generalised eigenproblem

    K_a phi = -mu K'_a phi,

whose smallest positive mu gives the critical load factor a + mu and the
buckling mode phi. About the rest state (a = 0) with a stiffness independent
of the load this is the classical linear buckling analysis (K'_0 the
geometric stiffness); about a preloaded state it follows the prebuckling
deformation. K'_a is the central difference of the System's own tangents a
load step :data:`DIFFERENCE_STEP` either side along the slope, so every
family (and a plug-in) gets it from its connectors without a formula of its
own. A linear model (``ee``) has no geometric stiffness and no critical load.

Units: load factors dimensionless (1 is the load case's full value); modes
in the System's coordinates (mm, rad), unit length in scaled coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse.linalg as spla

from ..core.loads import Loads
from ..core.system import System

DIFFERENCE_STEP = 1e-4
"""Load-factor step of the central difference K'_a (relative to the full load): the tangent
of a geometrically nonlinear model is smooth in the load, so the difference's error,
O(step^2) of the curvature of K along the path, is below 1e-8 of K'; round-off, about
u |K| / step, stays 1e-12 of |K| (a column's critical factor is the same to 1e-7 with
steps of 1e-3 and 1e-5)."""

DENSE_LIMIT = 600
"""Largest System whose eigenproblem is solved dense (LAPACK's generalised eig); larger ones
by shift-invert Arnoldi (ARPACK) on K_a^-1 K'_a."""

LANCZOS_START_SEED = 0
"""Seed of ARPACK's starting vector, so that the modes are the same in every process."""


@dataclass
class Buckling:
    """The lowest critical load factors about one equilibrium and their modes.

    Attributes
    ----------
    factors : array (k,)
        Critical load factors a + mu, ascending (dimensionless).
    shapes : array (k, n)
        Buckling modes over the System's coordinates (mm, rad), each of unit length in
        scaled coordinates (:meth:`System.scaled`), its largest entry positive.
    state : array (n,)
        The equilibrium the analysis is made about (mm, rad).
    at : float
        Its load factor a.
    """

    factors: np.ndarray
    shapes: np.ndarray
    state: np.ndarray
    at: float


def path_derivative(
    system: System, q: np.ndarray, loads: Loads, factor: float
) -> tuple[np.ndarray, np.ndarray]:
    """(K_a, K'_a) as sparse-or-dense arrays: the tangent at q and its derivative along the path.

    Both as dense arrays for systems up to :data:`DENSE_LIMIT` unknowns, else
    as sparse CSC matrices (N/mm, N, N mm per unit load factor).
    """
    _, _, tangent = system.assemble(q, loads, factor)
    slope = tangent.solve(loads.vector(q))
    h = DIFFERENCE_STEP
    ahead = system.assemble(system.update(q, slope * h), loads, factor + h)[2]
    behind = system.assemble(system.update(q, -slope * h), loads, factor - h)[2]
    dense = system.n_dofs <= DENSE_LIMIT
    convert = (lambda t: t.toarray()) if dense else (lambda t: t.tosparse())
    return convert(tangent), (convert(ahead) - convert(behind)) / (2.0 * h)


def critical_factors(
    system: System, q: np.ndarray, loads: Loads, at: float, count: int
) -> Buckling:
    """The ``count`` lowest critical load factors above ``at`` about the equilibrium q there.

    Raises
    ------
    numpy.linalg.LinAlgError
        When the tangent at q is singular (the state is itself critical).
    """
    K, dK = path_derivative(system, q, loads, at)
    if isinstance(K, np.ndarray):
        mu, vectors = la.eig(0.5 * (K + K.T), -0.5 * (dK + dK.T))
    else:
        lu = spla.splu((0.5 * (K + K.T)).tocsc())
        symmetric = (0.5 * (dK + dK.T)).tocsr()
        operator = spla.LinearOperator(
            K.shape, matvec=lambda x: lu.solve(symmetric @ x), dtype=float
        )
        start = np.random.default_rng(LANCZOS_START_SEED).uniform(-1.0, 1.0, K.shape[0])
        k = min(max(2 * count, count + 4), K.shape[0] - 2)
        nu, vectors = spla.eigs(operator, k=k, which="LM", v0=start)
        with np.errstate(divide="ignore"):
            mu = -1.0 / nu
    real = np.isfinite(mu) & (np.abs(np.imag(mu)) <= 1e-8 * np.abs(mu)) & (np.real(mu) > 0.0)
    mu, vectors = np.real(mu[real]), np.real(vectors[:, real])
    order = np.argsort(mu)[:count]
    shapes = []
    for k in order.tolist():
        mode = vectors[:, k] / max(float(np.linalg.norm(system.scaled(vectors[:, k]))), 1e-300)
        shapes.append(mode if mode[np.argmax(np.abs(mode))] > 0.0 else -mode)
    return Buckling(at + mu[order], np.array(shapes).reshape(len(shapes), system.n_dofs), q, at)
