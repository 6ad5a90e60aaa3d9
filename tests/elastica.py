"""Closed-form and quadrature references for planar cantilevers (used by test_beam).

* The Bisshopp-Drucker (1945) elliptic-integral solution of an inextensible
  Euler-Bernoulli cantilever under a dead tip force perpendicular to it.
* The exact circle an initially circular (or straight) cantilever bends into
  under a pure end moment, and the closed-form solution of the *discretised*
  corotational chain under the same moment.
* The linear tip compliance of a circular-arc cantilever by Castigliano's
  theorem (bending, axial and optionally shear complementary energy).
* The large-deflection end pose of an initially curved (or straight)
  inextensible cantilever under dead end loads, as a boundary-value problem
  solved by collocation (scipy's ``solve_bvp``), independent of the shooting
  solver of the PRBM calibration (``benchmarks/calibrate_prbm.py``).

Units: mm, N, N mm, rad. The cantilevers are clamped at the shape's start.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

from flexval.geometry import Arc, Segment


def _length_parameter(m: float) -> float:
    """sqrt(P/EI) L = K(k) - F(psi1, k) for the parameter m = k^2, with sin psi1 = 1/(k sqrt 2)."""
    psi1 = np.arcsin(np.sqrt(0.5 / m))
    return float(ellipk(m) - ellipkinc(psi1, m))


def cantilever_tip_force(load_parameter: float) -> tuple[float, float, float]:
    """Tip of an inextensible cantilever under a dead force normal to its initial axis.

    The beam lies along +x from a clamp at the origin; the force P acts
    along +y at the tip. With the tip slope phi0, k^2 = (1 + sin phi0)/2 and
    the substitution 1 + sin phi = 2 k^2 sin^2 psi, the elastica
    EI phi'' = -P cos phi, phi(0) = 0, phi'(L) = 0 integrates to

        alpha = sqrt(P L^2 / EI) = K(k) - F(psi1, k),   sin psi1 = 1 / (k sqrt 2),
        y_L / L = 1 - 2 (E(k) - E(psi1, k)) / alpha,
        x_L / L = sqrt(2 sin phi0) / alpha,

    (Bisshopp and Drucker 1945); k is found from the first line by bracketing.

    Parameters
    ----------
    load_parameter : float
        P L^2 / EI (> 0), dimensionless.

    Returns
    -------
    x_tip, y_tip : float
        Tip position over L (dimensionless).
    phi0 : float
        Tip rotation, rad.
    """
    alpha = np.sqrt(load_parameter)
    m = brentq(
        lambda mm: _length_parameter(mm) - alpha,
        0.5 + 1e-15,
        1.0 - 1e-15,
        xtol=1e-15,
        rtol=4 * np.finfo(float).eps,
    )
    psi1 = np.arcsin(np.sqrt(0.5 / m))
    phi0 = float(np.arcsin(2.0 * m - 1.0))
    y_tip = 1.0 - 2.0 * (ellipe(m) - ellipeinc(psi1, m)) / alpha
    x_tip = np.sqrt(2.0 * np.sin(phi0)) / alpha
    return float(x_tip), float(y_tip), phi0


def circle_under_end_moment(
    shape: Arc | Segment, EI: float, moment: float
) -> tuple[np.ndarray, float]:
    """Exact end point (mm) and end rotation (rad) of a cantilever under an end moment.

    A pure end moment M leaves no force resultant, so the axial and shear
    forces vanish, the length is kept and the curvature changes uniformly
    by M / EI: the centre line becomes a circle of curvature
    kappa = kappa0 + M/EI through the clamped start with its initial tangent.
    """
    L = shape.length
    kappa = shape.curvature + moment / EI
    t0 = float(shape.tangent_angle(0.0))
    start = shape.point(0.0)
    if abs(kappa) * L < 1e-8:
        chord = L * np.array([np.cos(t0), np.sin(t0)])
    else:
        t1 = t0 + kappa * L
        chord = np.array([np.sin(t1) - np.sin(t0), np.cos(t0) - np.cos(t1)]) / kappa
    return start + chord, moment * L / EI


def corotational_chain_under_end_moment(
    shape: Arc | Segment, EI: float, moment: float, n_elements: int
) -> tuple[np.ndarray, float]:
    """End point (mm) and rotation (rad) of the N-element corotational model under an end moment.

    With no force anywhere every chord keeps its length l0 and carries the
    end moments (-M, M), so the local rotations are a2 = -a1 = M l0 / (2 EI)
    (for the Euler-Bernoulli and the Timoshenko local stiffness alike, since
    k11 - k12 = 2 EI / l0 in both). Node k then turns by k M l0 / EI and
    chord k by theta_k + M l0 / (2 EI): the discrete solution in closed form.
    """
    nodes = shape.point(np.linspace(0.0, shape.length, n_elements + 1))
    chords = np.diff(nodes, axis=0)
    l0 = np.hypot(chords[:, 0], chords[:, 1])
    beta0 = np.arctan2(chords[:, 1], chords[:, 0])
    beta = beta0 + (np.arange(n_elements) + 0.5) * moment * l0 / EI
    end = nodes[0] + np.sum(l0[:, None] * np.column_stack([np.cos(beta), np.sin(beta)]), axis=0)
    return end, float(moment * l0.sum() / EI)


def arc_tip_compliance(
    shape: Arc | Segment,
    EI: float,
    EA: float,
    shear_stiffness: float | None = None,
    points: int = 64,
) -> np.ndarray:
    """Linear tip compliance (3, 3) of a cantilever clamped at the shape's start.

    For tip loads (Fx, Fy, M0) applied at the end point P_L, the section at
    arc length s carries (on the part beyond s) the axial force
    N = F . t(s), the shear V = F . n(s) with n = (-t_y, t_x), and the moment
    M = M0 + (P_L - P(s)) x F. Castigliano's theorem on the complementary
    energy U* = int [M^2/(2 EI) + N^2/(2 EA) + V^2/(2 kGA)] ds gives
    (dx, dy, rot) = C (Fx, Fy, M0) with

        C = int [b_M b_M^T / EI + b_N b_N^T / EA + b_V b_V^T / kGA] ds,
        b_M = (-(P_L - P)_y, (P_L - P)_x, 1), b_N = (t_x, t_y, 0), b_V = (-t_y, t_x, 0).

    The integrands are trigonometric polynomials of low degree in s, so
    Gauss-Legendre quadrature with ``points`` nodes is exact to rounding.

    Units: mm/N, 1/N, 1/(N mm) by block.
    """
    xg, wg = np.polynomial.legendre.leggauss(points)
    L = shape.length
    s = 0.5 * L * (xg + 1.0)
    w = 0.5 * L * wg
    lever = shape.point(L) - shape.point(s)
    tangent_angle = shape.tangent_angle(s)
    t = np.column_stack([np.cos(tangent_angle), np.sin(tangent_angle)])
    b_m = np.column_stack([-lever[:, 1], lever[:, 0], np.ones_like(s)])
    b_n = np.column_stack([t, np.zeros_like(s)])
    b_v = np.column_stack([-t[:, 1], t[:, 0], np.zeros_like(s)])
    parts = [(b_m, EI), (b_n, EA)] + ([(b_v, shear_stiffness)] if shear_stiffness else [])
    return sum(np.einsum("k,ki,kj->ij", w, b, b) / k for b, k in parts)


def curved_cantilever(
    width: float, load: np.ndarray, steps: int = 8, tol: float = 1e-8
) -> np.ndarray:
    """End pose change of a uniformly curved inextensible cantilever under dead end loads.

    Dimensionless: length L = 1, EI = 1, initial curvature ``width`` (the arc
    angle, rad; 0 is straight), clamped at the origin along +x and bending
    towards +y. The end load ``load`` = (Fx, Fy, M) is in EI/L^2 and EI/L.
    With the internal moment m(s) = M + (p(1) - p(s)) x F the Kirchhoff
    elastica is the first-order system

        x' = cos theta,  y' = sin theta,  theta' = width + m,
        m' = Fx sin theta - Fy cos theta,

    with x = y = theta = 0 at s = 0 and m(1) = M: a two-point problem solved by
    collocation (residual tolerance ``tol``). The load is ramped from the
    unloaded arc in ``steps`` equal increments, each solution the next one's
    guess (an increment the collocation cannot take is halved), so the
    stable branch is followed.

    Returns
    -------
    numpy.ndarray
        (dx, dy, dtheta): end displacement over L and end rotation (rad).

    Raises
    ------
    RuntimeError
        If the collocation fails even on an increment of 1/1000 of the load.
    """
    load = np.asarray(load, dtype=float)
    s = np.linspace(0.0, 1.0, 101)
    theta0 = width * s
    if abs(width) > 1e-12:
        x0, y0 = np.sin(theta0) / width, (1.0 - np.cos(theta0)) / width
    else:
        x0, y0 = s, 0.0 * s
    rest = np.array([x0[-1], y0[-1], width])
    guess = np.vstack([x0, y0, theta0, 0.0 * s])
    lam, dlam, end = 0.0, 1.0 / steps, rest
    while lam < 1.0:
        trial = min(1.0, lam + dlam)
        fx, fy, m_end = trial * load

        def rhs(_s, u, fx=fx, fy=fy):
            c, sn = np.cos(u[2]), np.sin(u[2])
            return np.vstack([c, sn, width + u[3], fx * sn - fy * c])

        def bc(ua, ub, m_end=m_end):
            return np.array([ua[0], ua[1], ua[2], ub[3] - m_end])

        sol = solve_bvp(rhs, bc, s, guess, tol=tol, max_nodes=5000)
        if not sol.success:
            dlam *= 0.5
            if dlam < 1e-3:
                raise RuntimeError(
                    f"elastica collocation failed at {trial:.3f} of the load: {sol.message}"
                )
            continue
        # the next guess on the initial mesh: collocation only ever adds nodes
        lam, guess, end = trial, sol.sol(s), sol.y[:3, -1]
    return end - rest
