"""Hyperelastic laws for 2D solids, as plain functions of the right Cauchy-Green tensor.

Every law maps C = F^T F (in-plane, shape (..., 2, 2)) to the strain energy
per unit reference volume W (MPa = N mm / mm^3), the second Piola-Kirchhoff
stress S = 2 dW/dC (MPa) and the material tangent CC = 4 d^2W/dC dC (MPa,
shape (..., 2, 2, 2, 2), with both minor and major symmetries).

* Saint Venant-Kirchhoff (the default): W = lam'/2 (tr E)^2 + mu E:E with
  E = (C - I)/2. In plane stress the 3D law with S33 = 0 eliminates E33
  exactly (it is linear in E), which gives lam' = 2 lam mu / (lam + 2 mu);
  in plane strain lam' = lam.
* Compressible neo-Hookean: W = mu/2 (I1 - 3) - mu ln J + lam/2 (ln J)^2.
  Plane strain sets C33 = 1. Plane stress finds C33 from S33 = 0,
  mu (C33 - 1) + lam ln J = 0 with ln J = (ln det C + ln C33)/2, by a
  vectorised Newton solve at every point, and condenses the tangent:
  CC = CC_3D - lam^2 / (lam + 2 mu C33) C^-1 (x) C^-1.

Lame constants come from the 3D E and nu (:func:`lame`). Units: MPa.
"""

from __future__ import annotations

from functools import partial
from typing import Callable

import numpy as np

LAWS = ("svk", "neo-hookean")
PLANES = ("stress", "strain")

Law = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]
"""C (..., 2, 2) -> (W (...), S (..., 2, 2), CC (..., 2, 2, 2, 2))."""

_I2 = np.eye(2)
_SYM = 0.5 * (np.einsum("ik,jl->ijkl", _I2, _I2) + np.einsum("il,jk->ijkl", _I2, _I2))
_IXI = np.einsum("ij,kl->ijkl", _I2, _I2)


def lame(youngs_modulus: float, poisson_ratio: float) -> tuple[float, float]:
    """3D Lame constants (lambda, mu) in MPa from E (MPa) and nu."""
    E, nu = youngs_modulus, poisson_ratio
    return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


def svk(C: np.ndarray, lam: float, mu: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Saint Venant-Kirchhoff with the in-plane constants (lam', mu) given.

    Parameters
    ----------
    C : array (..., 2, 2)
        Right Cauchy-Green tensor.
    lam, mu : float
        lam' (lam for plane strain, 2 lam mu/(lam + 2 mu) for plane stress) and mu, MPa.
    """
    E = 0.5 * (C - _I2)
    tr = E[..., 0, 0] + E[..., 1, 1]
    W = 0.5 * lam * tr**2 + mu * np.einsum("...ij,...ij->...", E, E)
    S = lam * tr[..., None, None] * _I2 + 2.0 * mu * E
    CC = np.broadcast_to(lam * _IXI + 2.0 * mu * _SYM, C.shape[:-2] + (2, 2, 2, 2))
    return W, S, CC


def _inverse_det(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    det = C[..., 0, 0] * C[..., 1, 1] - C[..., 0, 1] * C[..., 1, 0]
    inv = np.empty_like(C)
    inv[..., 0, 0], inv[..., 1, 1] = C[..., 1, 1] / det, C[..., 0, 0] / det
    inv[..., 0, 1], inv[..., 1, 0] = -C[..., 0, 1] / det, -C[..., 1, 0] / det
    return inv, det


def neo_hookean_c33(C: np.ndarray, lam: float, mu: float) -> np.ndarray:
    """Out-of-plane C33 making S33 = 0 (plane stress), by Newton on s = ln C33.

    g(s) = mu (e^s - 1) + lam/2 (ln det C + s) is increasing and convex, so
    Newton from any start converges monotonically after its first step.
    """
    _, det = _inverse_det(C)
    logdet = np.log(det)
    s = -lam / (lam + 2.0 * mu) * logdet          # small-strain value
    for _ in range(50):
        es = np.exp(s)
        ds = -(mu * (es - 1.0) + 0.5 * lam * (logdet + s)) / (mu * es + 0.5 * lam)
        s = s + ds
        if np.all(np.abs(ds) <= 1e-15 * (1.0 + np.abs(s))):
            return np.exp(s)
    raise ArithmeticError("plane-stress neo-Hookean: C33 did not converge")


def neo_hookean(C: np.ndarray, lam: float, mu: float, plane: str = "stress"
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Compressible neo-Hookean in plane stress or plane strain (3D lam, mu in MPa).

    Parameters
    ----------
    C : array (..., 2, 2)
        In-plane right Cauchy-Green tensor.
    lam, mu : float
        3D Lame constants, MPa.
    plane : {'stress', 'strain'}
    """
    Ci, det = _inverse_det(C)
    c33 = neo_hookean_c33(C, lam, mu) if plane == "stress" else np.ones_like(det)
    logJ = 0.5 * (np.log(det) + np.log(c33))
    W = 0.5 * mu * (C[..., 0, 0] + C[..., 1, 1] + c33 - 3.0) - mu * logJ + 0.5 * lam * logJ**2
    S = mu * (_I2 - Ci) + (lam * logJ)[..., None, None] * Ci
    cixci = np.einsum("...ij,...kl->...ijkl", Ci, Ci)
    sym = 0.5 * (np.einsum("...ik,...jl->...ijkl", Ci, Ci)
                 + np.einsum("...il,...jk->...ijkl", Ci, Ci))
    coef = lam - lam**2 / (lam + 2.0 * mu * c33) if plane == "stress" else np.full_like(det, lam)
    CC = coef[..., None, None, None, None] * cixci \
        + (2.0 * (mu - lam * logJ))[..., None, None, None, None] * sym
    return W, S, CC


def make_law(name: str, plane: str, youngs_modulus: float, poisson_ratio: float) -> Law:
    """The law ``name`` ('svk' or 'neo-hookean') for ``plane`` ('stress' or 'strain')."""
    if name not in LAWS:
        raise ValueError(f"unknown hyperelastic law {name!r}; expected one of {LAWS}")
    if plane not in PLANES:
        raise ValueError(f"unknown plane assumption {plane!r}; expected one of {PLANES}")
    lam, mu = lame(youngs_modulus, poisson_ratio)
    if name == "svk":
        return partial(svk, lam=2.0 * lam * mu / (lam + 2.0 * mu) if plane == "stress" else lam,
                       mu=mu)
    return partial(neo_hookean, lam=lam, mu=mu, plane=plane)


def out_of_plane(name: str, plane: str, youngs_modulus: float, poisson_ratio: float,
                 C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Out-of-plane C33 and S33 (MPa) of law ``name`` at C (for stress post-processing)."""
    lam, mu = lame(youngs_modulus, poisson_ratio)
    tr = 0.5 * (C[..., 0, 0] + C[..., 1, 1] - 2.0)
    if name == "svk":
        if plane == "stress":
            return 1.0 - 2.0 * lam / (lam + 2.0 * mu) * tr, np.zeros_like(tr)
        return np.ones_like(tr), lam * tr
    if plane == "stress":
        return neo_hookean_c33(C, lam, mu), np.zeros_like(tr)
    _, det = _inverse_det(C)
    return np.ones_like(tr), 0.5 * lam * np.log(det)
