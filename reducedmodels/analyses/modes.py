"""Natural frequencies and mode shapes about an equilibrium (small vibrations).

About a static equilibrium q* (at some load level, with gravity if the
scene has it) the linearised equations of motion are M(q*) x'' + K(q*) x = 0
with K the consistent tangent of the total potential (elastic plus load
stiffness: a load that softens the mechanism lowers the frequencies, and a
limit point has a zero one) and M the mass matrix
(:class:`flexval.reducedmodels.core.inertia.MassModel`).

Coordinates without mass are of two kinds, both without inertia terms:
Lagrange multipliers (pins, the PRBM closure) and massless internal
coordinates (e.g. every flexure coordinate when the scene gives no
density). Their rows are static equations,
K_sm x_m + K_ss x_s = 0. With K_ss = U diag(w) U^T split into its regular
part (pseudo-inverse K_ss^+) and null space Z (the multipliers of
constraints on massive coordinates), the massive coordinates must satisfy
the constraints Z^T K_sm x_m = 0, i.e. x_m = T y with T an orthonormal basis
of that null space, and the reduced symmetric problem is

    T^T (K_mm - K_ms K_ss^+ K_sm) T y = omega^2 T^T M_mm T y

(the bordered problem with the constraints projected out and the massless
coordinates condensed statically), solved densely by ``scipy.linalg.eigh``.
A massless rigid-body coordinate is refused: it is a missing input, not a
modelling choice.

Units: Hz for frequencies; eigenvalues omega^2 in 1/s^2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexval.geometry import Force, LoadCase, Moment, SceneError

from ..core.inertia import MassModel, describe_massless
from ..core.loads import Loads
from ..core.settings import SolverError
from ..core.system import System, local_hessian
from ..core.tracer import LoadControl, TraceFailure, trace

SINGULAR_RELATIVE = 1e-12
"""Eigenvalues of the massless block below this fraction of its largest are its null space
(multiplier blocks are exactly zero; regular ones are many orders above round-off)."""


@dataclass
class Modes:
    """The lowest natural modes about one equilibrium.

    Attributes
    ----------
    eigenvalues : array (k,)
        omega^2, 1/s^2 (negative: an unstable equilibrium).
    shapes : array (k, n)
        Mode shapes over every coordinate of the System, mass-normalised
        (x^T M x = 1, t mm^2 units per coordinate kind).
    state : array (n,)
        The equilibrium q* (mm, rad).
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray
    state: np.ndarray

    @property
    def frequencies_hz(self) -> np.ndarray:
        """sqrt(omega^2) / 2 pi in Hz; negative (-sqrt(-omega^2) / 2 pi) where unstable."""
        lam = self.eigenvalues
        return np.sign(lam) * np.sqrt(np.abs(lam)) / (2.0 * math.pi)


def refuse_massless_bodies(system: System, massless: np.ndarray, what: str) -> None:
    """SceneError naming the massless body coordinates, if any (``what`` needs them)."""
    n_body = 3 * len(system.body_index)
    if massless[:n_body].any():
        names = describe_massless(
            system, np.concatenate([massless[:n_body], np.zeros(system.n_dofs - n_body, bool)])
        )
        body = names[0].split("'")[1]
        raise SceneError(
            system.mechanism.source,
            f"bodies.{body}.mass",
            None,
            f"{what} needs the mass of every moving body; massless: "
            f"{', '.join(names)} (give mass, inertia and center_of_mass, "
            "or an outline)",
        )


def modes_at(
    system: System, mass: MassModel, q: np.ndarray, tangent: np.ndarray, count: int
) -> Modes:
    """The ``count`` lowest modes of (tangent, M(q)) with massless coordinates handled.

    Parameters
    ----------
    tangent : array (n, n)
        Consistent tangent of the total potential at q (N/mm, N, N mm).
    """
    massless = mass.massless()
    refuse_massless_bodies(system, massless, "a modal analysis")
    K = 0.5 * (tangent + tangent.T)
    M = mass.matrix(q).toarray()
    m, s = np.flatnonzero(~massless), np.flatnonzero(massless)
    Kmm, Kms, Kss = K[np.ix_(m, m)], K[np.ix_(m, s)], K[np.ix_(s, s)]
    if s.size:
        w, U = la.eigh(Kss)
        regular = np.abs(w) > SINGULAR_RELATIVE * max(float(np.abs(w).max()), 1e-300)
        R, Z = U[:, regular], U[:, ~regular]
        condense = R @ ((R.T @ Kms.T) / w[regular, None])  # K_ss^+ K_sm
        Kmm = Kmm - Kms @ condense
        T = la.null_space(Z.T @ Kms.T) if Z.shape[1] else np.eye(m.size)
    else:
        condense, T = np.zeros((0, m.size)), np.eye(m.size)
    Kr = T.T @ Kmm @ T
    Mr = T.T @ M[np.ix_(m, m)] @ T
    k = min(count, Kr.shape[0])
    lam, y = la.eigh(0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T), subset_by_index=[0, k - 1])
    xm = T @ y
    shapes = np.zeros((k, system.n_dofs))
    shapes[:, m] = xm.T
    shapes[:, s] = -(condense @ xm).T
    return Modes(lam, shapes, q)


DENSE_MODES_LIMIT = 600
"""Above this many coordinates the modes come from sparse shift-invert Lanczos (ARPACK)
instead of dense ``eigh``: a 4000-coordinate continuum took 50 s dense."""
LANCZOS_START_SEED = 0
"""Seed of the Lanczos starting vector. ARPACK's default start is drawn from the operating
system's entropy, and the frequencies it converges to then differ in the 9th digit from
process to process (beam:100, open chain); a ramp time in periods of them carried that
into every dynamic run of ``benchmarks/paper_protocol.py``. A seeded start keeps the
vector generic (no wanted mode is missed) and the modes bit-reproducible."""


def sparse_tangent(system: System, q: np.ndarray, loads: Loads, factor: float) -> sp.csc_matrix:
    """The System's tangent at q (N/mm, N, N mm) in sparse storage, whatever its usual one.

    Each connector's Hessian (:func:`flexval.reducedmodels.core.system.local_hessian`) is
    scattered through its local-to-global map (ground rows and columns
    dropped), and the loads add their diagonal (:meth:`Loads.add_to`), as in
    :meth:`System.assemble`.
    """
    n = system.n_dofs
    rows, cols, vals = [], [], []
    for c, idx, local in zip(system.connectors, system.local_to_global, system.local_states(q)):
        h = sp.coo_matrix(local_hessian(c, c.evaluate(*local)[2]))
        r, cc = idx[h.row], idx[h.col]
        keep = (r >= 0) & (cc >= 0)
        rows.append(r[keep]), cols.append(cc[keep]), vals.append(h.data[keep])
    diagonal = np.zeros(n)
    loads.add_to(q, factor, np.zeros(n), diagonal)
    rows.append(np.arange(n)), cols.append(np.arange(n)), vals.append(diagonal)
    return sp.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    )


def sparse_modes(
    system: System, mass: MassModel, q: np.ndarray, tangent: sp.spmatrix, count: int
) -> Modes:
    """The ``count`` lowest modes by Lanczos on the flexibility of the massive coordinates.

    With G = [K^-1]_mm the massive block of the inverse of the (bordered)
    tangent, the massless rows are satisfied exactly (static condensation
    and constraints at once) and the problem is G M_mm x = x / omega^2, i.e.
    the symmetric-definite G y = mu M_mm^-1 y with y = M_mm x and
    mu = 1 / omega^2, solved by ARPACK for the largest |mu| (the omega^2
    nearest zero, of either sign). The full shape follows as
    x = K^-1 (M x) omega^2, normalised to x^T M x = 1. The Lanczos start is seeded
    (:data:`LANCZOS_START_SEED`): the same System gives the same bits in every process.
    """
    massless = mass.massless()
    refuse_massless_bodies(system, massless, "a modal analysis")
    M = mass.matrix(q).tocsc()
    m = np.flatnonzero(~massless)
    lu = spla.splu((0.5 * (tangent + tangent.T)).tocsc())
    m_mm = M[m][:, m].tocsc()
    m_lu = spla.splu(m_mm)

    def embed(v: np.ndarray) -> np.ndarray:
        full = np.zeros(system.n_dofs)
        full[m] = v
        return full

    shape = (m.size, m.size)
    flexibility = spla.LinearOperator(shape, matvec=lambda y: lu.solve(embed(y))[m], dtype=float)
    inverse_mass = spla.LinearOperator(shape, matvec=m_lu.solve, dtype=float)
    apply_mass = spla.LinearOperator(shape, matvec=lambda v: m_mm @ v, dtype=float)
    start = np.random.default_rng(LANCZOS_START_SEED).uniform(-1.0, 1.0, m.size)
    mu, y = spla.eigsh(
        flexibility, k=min(count, m.size - 1), M=inverse_mass, Minv=apply_mass, which="LM", v0=start
    )
    lam = 1.0 / mu
    order = np.argsort(lam)
    lam, y = lam[order], y[:, order]
    x = np.column_stack([lu.solve(embed(y[:, k])) * lam[k] for k in range(lam.size)])
    x /= np.sqrt(np.einsum("ik,ik->k", x, M @ x))
    return Modes(lam, x.T, q)


def scaled_case(
    system: System, case: LoadCase | None, fraction: float, levels: int = 11
) -> LoadCase:
    """``case`` at ``fraction`` (0..1) of its value, traced in ``levels`` levels.

    Without a case (or at 0) a zero moment on the target body: the state
    is then the rest state, or the equilibrium under gravity.
    """
    if case is None or fraction == 0.0:
        return LoadCase("rest", (Moment(system.mechanism.target_body, 0.0),), 2)
    comps = tuple(
        Force(c.body, c.point, c.angle, fraction * c.value)
        if isinstance(c, Force)
        else Moment(c.body, fraction * c.value)
        for c in case.components
    )
    return LoadCase(case.name, comps, levels)


def equilibrium(system: System, case: LoadCase) -> np.ndarray:
    """The equilibrium state at full ``case`` (gravity, if any, included), traced from rest
    by load control through the case's levels.

    Raises
    ------
    flexval.reducedmodels.core.settings.SolverError
        If it is not reached (e.g. past a limit point); carries the load factor reached.
    """
    state = None
    try:
        for point in trace(system, system.loads(case), LoadControl(case.factors())):
            state = point.state
    except TraceFailure as exc:
        raise SolverError(
            f"equilibrium for the modal analysis on load case '{case.name}': "
            f"{exc.reason}; last converged at {100 * exc.factor:.2f} % of the "
            "requested level",
            exc.factor,
        ) from None
    return state


def natural_modes(
    system: System, case: LoadCase | None = None, fraction: float = 0.0, count: int = 6
) -> Modes:
    """The ``count`` lowest natural modes about the equilibrium at ``fraction`` of ``case``.

    Raises
    ------
    SceneError
        If a moving body has no mass.
    flexval.reducedmodels.core.settings.SolverError
        If the equilibrium cannot be reached.
    """
    mass = MassModel(system)
    refuse_massless_bodies(system, mass.massless(), "a modal analysis")
    scaled = scaled_case(system, case, fraction)
    q = equilibrium(system, scaled)
    loads = system.loads(scaled)
    if system.n_dofs > DENSE_MODES_LIMIT:
        return sparse_modes(system, mass, q, sparse_tangent(system, q, loads, 1.0), count)
    _, _, K = system.assemble(q, loads, 1.0)
    return modes_at(system, mass, q, K.toarray(), count)
