"""Polynomial extrapolation weights of the load-control predictor (in floats, closed form).

:meth:`flexval.reducedmodels.core.system.System.predict` combines the last
converged states with these weights: a Lagrange polynomial through them, or
a Hermite one that also matches the slope at the last state. Dimensionless.
"""

from __future__ import annotations

from collections.abc import Sequence


def hermite_weights(factors: Sequence[float], factor: float) -> tuple[list[float], float]:
    """Weights of the polynomial through values at ``factors`` and the slope at the last one.

    Returns (one weight per value, the slope's weight): the polynomial of
    degree len(factors) evaluated at ``factor`` is sum(w_i q_i) + w_s q'.
    It is the Lagrange polynomial through the values plus c w(x), with
    w(x) = prod(x - x_j) vanishing at every factor and c set by the slope at
    the last factor m: w_i = L_i(x) - w(x) L_i'(x_m) / w'(x_m) and
    w_s = w(x) / w'(x_m), where L_i'(x_m) / w'(x_m) = 1 / ((x_m - x_i) d_i)
    for i != m (d_i = prod over j != i of (x_i - x_j); w'(x_m) = d_m) and
    sum over j != m of 1 / (x_m - x_j), over d_m, for i = m. Closed form in
    floats: a linear solve would cost as much as a Newton iteration of a
    small model.
    """
    m = len(factors) - 1
    last = factors[m]
    node = 1.0  # w(x)
    for f in factors:
        node *= factor - f
    weights, spread = [], []
    for i, fi in enumerate(factors):
        basis, d = 1.0, 1.0
        for j, fj in enumerate(factors):
            if j != i:
                basis *= factor - fj
                d *= fi - fj
        weights.append(basis / d)
        spread.append(d)
    for i, fi in enumerate(factors[:m]):
        weights[i] -= node / ((last - fi) * spread[i])
    weights[m] -= node * sum(1.0 / (last - f) for f in factors[:m]) / spread[m]
    return weights, node / spread[m]


def lagrange_weights(factors: Sequence[float], factor: float) -> list[float]:
    """Weights of the Lagrange polynomial through ``factors`` evaluated at ``factor`` (sum 1)."""
    weights = []
    for i, li in enumerate(factors):
        w = 1.0
        for j, lj in enumerate(factors):
            if j != i:
                w *= (factor - lj) / (li - lj)
        weights.append(w)
    return weights
