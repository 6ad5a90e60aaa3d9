"""Cubic spline interpolation of a tabulated function of one variable (not-a-knot ends).

The PRBM's fitted parameter rho is tabulated against the arc angle and read
between the rows by this spline (:func:`flexval.reducedmodels.prbm.parameters.table_parameters`).
It is the spline of ``scipy.interpolate.CubicSpline`` with its default
not-a-knot ends, computed the same way (slopes from one tridiagonal solve,
``scipy.linalg.solve_banded``, then cubic Hermite pieces evaluated by
increasing powers), so it gives the same numbers; it exists because importing
``scipy.interpolate`` also imports scipy's optimisation, special-function and
spatial packages, about 0.1-0.2 s of CPU time that every process running a
PRBM paid for one table look-up.
"""

from __future__ import annotations

import bisect

import numpy as np


class NotAKnotSpline:
    """The C2 cubic spline through ``(x[i], y[i])`` whose third derivative is continuous at
    the second and the last-but-one knot (so it reproduces every cubic polynomial exactly).

    Parameters
    ----------
    x : array (n,)
        Strictly increasing abscissae, n >= 4 (any unit; the call takes the same unit).
    y : array (n,)
        Values at ``x`` (any unit; the call returns the same unit).
    """

    def __init__(self, x, y):
        from scipy.linalg import solve_banded

        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if x.ndim != 1 or x.shape != y.shape or x.size < 4:
            raise ValueError(
                f"need two 1-D arrays of one length >= 4, got shapes {x.shape} and {y.shape}"
            )
        dx = np.diff(x)
        if not np.all(dx > 0.0):
            raise ValueError("the abscissae must increase strictly")
        slope = np.diff(y) / dx
        # slopes s at the knots: A s = b, A tridiagonal in LAPACK band storage (rows: upper
        # diagonal, diagonal, lower diagonal); interior rows are C2 continuity
        band = np.zeros((3, x.size))
        band[1, 1:-1] = 2 * (dx[:-1] + dx[1:])
        band[0, 2:] = dx[:-1]
        band[2, :-2] = dx[1:]
        rhs = np.empty(x.size)
        rhs[1:-1] = 3 * (dx[1:] * slope[:-1] + dx[:-1] * slope[1:])
        # not-a-knot rows: the first two and the last two pieces are one cubic each
        d = x[2] - x[0]
        band[1, 0], band[0, 1] = dx[1], d
        rhs[0] = ((dx[0] + 2 * d) * dx[1] * slope[0] + dx[0] ** 2 * slope[1]) / d
        d = x[-1] - x[-3]
        band[1, -1], band[2, -2] = dx[-2], d
        rhs[-1] = (dx[-1] ** 2 * slope[-2] + (2 * d + dx[-1]) * dx[-2] * slope[-1]) / d
        s = solve_banded((1, 1), band, rhs)
        # piece i: y[i] + s[i] u + c2[i] u^2 + c3[i] u^3, u = x - x[i]
        t = (s[:-1] + s[1:] - 2 * slope) / dx
        # the knots and each piece's coefficients, as floats (read by every call)
        self._knots = x.tolist()
        self._pieces = np.stack((y[:-1], s[:-1], (slope - s[:-1]) / dx - t, t / dx), 1).tolist()

    def __call__(self, x: float) -> float:
        """The spline at ``x``; outside the knots, the end piece's cubic continued."""
        i = bisect.bisect_right(self._knots, x) - 1  # np.searchsorted's "right" side
        i = min(max(i, 0), len(self._knots) - 2)
        u = float(x) - self._knots[i]
        c0, c1, c2, c3 = self._pieces[i]
        return c0 + c1 * u + c2 * (u * u) + c3 * (u * u * u)
