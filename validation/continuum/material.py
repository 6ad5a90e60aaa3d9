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

Lame constants come from the 3D E and nu (:func:`lame`).

A law is a :class:`Law` object: called with C it gives (W, S, CC), and its
:meth:`Law.tangent_blocks` contracts CC with the deformation gradient into
the blocks of the element tangent (:mod:`.solid`); the Saint Venant-Kirchhoff
law, whose CC is constant, does that in closed form. Units: MPa.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

LAWS = ("svk", "neo-hookean")
PLANES = ("stress", "strain")

_I2 = np.eye(2)
_SYM = 0.5 * (np.einsum("ik,jl->ijkl", _I2, _I2) + np.einsum("il,jk->ijkl", _I2, _I2))
_IXI = np.einsum("ij,kl->ijkl", _I2, _I2)
BLOCK_ROWS, BLOCK_COLS = np.array([0, 0, 1]), np.array([0, 1, 1])
"""The (i, k) pairs of the tangent blocks, in the order of :meth:`Law.tangent_blocks`."""


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
    W = 0.5 * lam * tr**2 + mu * (
        E[..., 0, 0] ** 2 + E[..., 0, 1] ** 2 + E[..., 1, 0] ** 2 + E[..., 1, 1] ** 2
    )
    S = 2.0 * mu * E  # + lam tr I, added on the diagonal (keeps C's layout)
    S[..., 0, 0] += lam * tr
    S[..., 1, 1] += lam * tr
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
    s = -lam / (lam + 2.0 * mu) * logdet  # small-strain value
    for _ in range(50):
        es = np.exp(s)
        ds = -(mu * (es - 1.0) + 0.5 * lam * (logdet + s)) / (mu * es + 0.5 * lam)
        s = s + ds
        if np.all(np.abs(ds) <= 1e-15 * (1.0 + np.abs(s))):
            return np.exp(s)
    raise ArithmeticError("plane-stress neo-Hookean: C33 did not converge")


def neo_hookean(
    C: np.ndarray, lam: float, mu: float, plane: str = "stress"
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
    sym = 0.5 * (
        np.einsum("...ik,...jl->...ijkl", Ci, Ci) + np.einsum("...il,...jk->...ijkl", Ci, Ci)
    )
    coef = lam - lam**2 / (lam + 2.0 * mu * c33) if plane == "stress" else np.full_like(det, lam)
    CC = (
        coef[..., None, None, None, None] * cixci
        + (2.0 * (mu - lam * logJ))[..., None, None, None, None] * sym
    )
    return W, S, CC


class Law(ABC):
    """A hyperelastic law: C -> (W, S, CC) (see the module docstring), in MPa.

    Parameters
    ----------
    lam, mu : float
        Its Lame constants, MPa (which ones: see the subclasses).
    """

    def __init__(self, lam: float, mu: float):
        self.lam, self.mu = float(lam), float(mu)

    @abstractmethod
    def __call__(self, C: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """W (...), S (..., 2, 2) and CC (..., 2, 2, 2, 2) at C (..., 2, 2)."""

    def tangent_blocks(self, F: np.ndarray, CC: np.ndarray, weight: np.ndarray) -> np.ndarray:
        """The material part of the first elasticity tensor, weighted, as 2 x 2 blocks (MPa mm^3).

        ``A[..., J, c, L] = weight * sum_MN F_iM F_kN CC_MJNL`` for the pairs
        c = (i, k) of ``BLOCK_ROWS``, ``BLOCK_COLS``, i.e. (0, 0), (0, 1),
        (1, 1) (the pair (1, 0) is the transpose of (0, 1)); F is (..., 2, 2),
        CC as :meth:`__call__` gives it, ``weight`` (...) the integration
        weights (mm^3). Shape (..., 2, 3, 2).
        """
        shape = F.shape[:-2]
        pairs = (
            F[..., BLOCK_ROWS, :, None]
            * F[..., BLOCK_COLS, None, :]
            * weight[..., None, None, None]
        ).reshape(shape + (3, 4))  # c, (M, N)
        by_mn = CC.transpose(*range(len(shape)), -4, -2, -3, -1).reshape(shape + (4, 4))
        blocks = np.matmul(pairs, by_mn).reshape(shape + (3, 2, 2))  # c, J, L
        return np.ascontiguousarray(np.swapaxes(blocks, -3, -2))


class SvkLaw(Law):
    """Saint Venant-Kirchhoff with the in-plane constants lam' and mu (see :func:`svk`)."""

    def __call__(self, C: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return svk(C, self.lam, self.mu)

    def tangent_blocks(self, F: np.ndarray, CC: np.ndarray, weight: np.ndarray) -> np.ndarray:
        """:meth:`Law.tangent_blocks` in closed form (CC is constant, ``CC`` is not read).

        With CC_MJNL = lam d_MJ d_NL + mu (d_MN d_JL + d_ML d_JN) the block
        of (i, k) is ``lam F_iJ F_kL + mu F_kJ F_iL + mu (F F^T)_ik d_JL``
        times the weight: a few products per point instead of the general
        contraction (which the tests check it against). Computed component
        by component into an array whose components are contiguous (the
        result is a transposed view of it).
        """
        lam, mu = self.lam, self.mu
        f = [[F[..., i, J] for J in (0, 1)] for i in (0, 1)]
        wf = [[weight * f[i][J] for J in (0, 1)] for i in (0, 1)]
        shape = F.shape[:-2]
        blocks = np.empty((2, 3, 2) + shape)  # [J, c, L, ...]
        for c, (i, k) in enumerate(zip(BLOCK_ROWS, BLOCK_COLS)):
            gram = mu * (wf[i][0] * f[k][0] + wf[i][1] * f[k][1])  # mu (F F^T)_ik w
            for J in (0, 1):
                for L in (0, 1):
                    value = lam * wf[i][J] * f[k][L] + mu * wf[k][J] * f[i][L]
                    blocks[J, c, L] = value + gram if J == L else value
        return np.moveaxis(blocks, (0, 1, 2), (-3, -2, -1))


class NeoHookeanLaw(Law):
    """Compressible neo-Hookean with the 3D lam and mu (see :func:`neo_hookean`).

    Parameters
    ----------
    lam, mu : float
        3D Lame constants, MPa.
    plane : {'stress', 'strain'}
    """

    def __init__(self, lam: float, mu: float, plane: str):
        super().__init__(lam, mu)
        self.plane = plane

    def __call__(self, C: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return neo_hookean(C, self.lam, self.mu, self.plane)


def make_law(name: str, plane: str, youngs_modulus: float, poisson_ratio: float) -> Law:
    """The law ``name`` ('svk' or 'neo-hookean') for ``plane`` ('stress' or 'strain')."""
    if name not in LAWS:
        raise ValueError(f"unknown hyperelastic law {name!r}; expected one of {LAWS}")
    if plane not in PLANES:
        raise ValueError(f"unknown plane assumption {plane!r}; expected one of {PLANES}")
    lam, mu = lame(youngs_modulus, poisson_ratio)
    if name == "svk":
        return SvkLaw(2.0 * lam * mu / (lam + 2.0 * mu) if plane == "stress" else lam, mu)
    return NeoHookeanLaw(lam, mu, plane)


def out_of_plane(
    name: str, plane: str, youngs_modulus: float, poisson_ratio: float, C: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
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
