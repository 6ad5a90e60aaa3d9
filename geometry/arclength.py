"""The exact arc-length parameterisation of a smooth parametric plane curve.

A curve r(u) given with its derivative r'(u) on [u_0, u_end] (any
parameter, here a spline's chord length) is re-parameterised by its true
arc length s(u) = ∫ |r'(v)| dv from u_0. The parameter interval is cut
into panels, refined by bisection until a 16-point Gauss-Legendre rule on
each panel agrees with the same rule on its two halves to
:data:`PANEL_TOLERANCE` of the curve's length; s at any u is the panels'
cumulative lengths plus the rule on the part of its panel before u, and
u(s) is found by Newton's method on that s(u), kept inside the panel's
bracket (monotone: |r'| > 0 on a regular curve), to :data:`INVERSE_TOLERANCE`.

Units: lengths mm, the parameter in its own unit (mm for chord length).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

GAUSS_ORDER = 16
"""Gauss-Legendre points per panel."""

PANEL_TOLERANCE = 1e-15
"""Panel refinement stops when one panel's and its halves' lengths agree to this fraction of
the curve's length (about the rounding of the cumulative sum)."""

INVERSE_TOLERANCE = 1e-13
"""u(s) is accepted when s(u) matches to this fraction of the curve's length (1e-12 mm on
a curve of 10 mm)."""

MAX_BISECTIONS = 12
"""Deepest refinement of a panel (1/4096 of its parameter interval)."""

_X, _W = np.polynomial.legendre.leggauss(GAUSS_ORDER)


class ArcLengthMap:
    """s(u) and u(s) of a regular curve given by its derivative r'(u).

    Parameters
    ----------
    derivative : callable
        ``derivative(u) -> r'(u)``, shape (..., 2), on arrays of parameter values
        (mm per parameter unit); a picklable object (a spline's derivative), so
        that shapes travel to worker processes.
    breaks : array (k + 1,)
        Increasing parameter values where the curve is cut into pieces
        (a spline's knots: the speed is smooth on each piece).

    Raises
    ------
    ValueError
        If the speed vanishes or is not finite at a quadrature node (a cusp).
    """

    def __init__(self, derivative: Callable[[np.ndarray], np.ndarray], breaks: np.ndarray):
        self._derivative = derivative
        breaks = np.asarray(breaks, float)
        pieces = [self._panel_length(a, b) for a, b in zip(breaks[:-1], breaks[1:])]
        total = float(sum(pieces))
        if not (np.isfinite(total) and total > 0.0):
            raise ValueError(f"the curve's length is {total!r}: not a regular curve")
        edges = [float(breaks[0])]
        lengths = []
        for a, b in zip(breaks[:-1], breaks[1:]):
            self._refine(float(a), float(b), PANEL_TOLERANCE * total, 0, edges, lengths)
        self.edges = np.array(edges)
        """Panel boundaries in the parameter, (m + 1,)."""
        self.cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
        """Arc length at each panel boundary, mm, (m + 1,)."""
        self.length = float(self.cumulative[-1])
        """Total arc length, mm."""

    def _speed(self, u: np.ndarray) -> np.ndarray:
        d = self._derivative(u)
        return np.hypot(d[..., 0], d[..., 1])

    def _panel_length(self, a: float, b: float) -> float:
        half = 0.5 * (b - a)
        values = self._speed(a + half * (_X + 1.0))
        if not np.all(np.isfinite(values) & (values > 0.0)):
            raise ValueError(
                f"the curve's speed |dr/du| vanishes or is not finite on [{a:.6g}, {b:.6g}] "
                "(a cusp): not a regular curve"
            )
        return float(half * (_W @ values))

    def _refine(
        self, a: float, b: float, tol: float, depth: int, edges: list, lengths: list
    ) -> None:
        whole = self._panel_length(a, b)
        mid = 0.5 * (a + b)
        halves = self._panel_length(a, mid) + self._panel_length(mid, b)
        if abs(whole - halves) <= tol or depth >= MAX_BISECTIONS:
            edges.append(b)
            lengths.append(halves)
            return
        self._refine(a, mid, tol, depth + 1, edges, lengths)
        self._refine(mid, b, tol, depth + 1, edges, lengths)

    def _panel_of_parameter(self, u: np.ndarray) -> np.ndarray:
        return np.clip(np.searchsorted(self.edges, u, side="right") - 1, 0, self.edges.size - 2)

    def arc_length(self, u: np.ndarray | float) -> np.ndarray:
        """s(u), mm, for parameter values in the curve's interval."""
        u = np.asarray(u, float)
        k = self._panel_of_parameter(u)
        return self._from_panel(u, k)

    def _from_panel(self, u: np.ndarray, k: np.ndarray) -> np.ndarray:
        """Arc length at u, counted from the start of panel k (its cumulative length added)."""
        a = self.edges[k]
        half = 0.5 * (u - a)
        nodes = a[..., None] + half[..., None] * (_X + 1.0)
        return self.cumulative[k] + half * (self._speed(nodes) @ _W)

    def parameter(self, s: np.ndarray | float) -> np.ndarray:
        """u(s) for arc lengths s (mm), clipped to [0, length]."""
        s = np.clip(np.asarray(s, float), 0.0, self.length)
        k = np.clip(np.searchsorted(self.cumulative, s, side="right") - 1, 0, self.edges.size - 2)
        lo, hi = self.edges[k], self.edges[k + 1]
        s_lo, s_hi = self.cumulative[k], self.cumulative[k + 1]
        u = lo + (hi - lo) * np.where(s_hi > s_lo, (s - s_lo) / (s_hi - s_lo), 0.0)
        tol = INVERSE_TOLERANCE * self.length
        for _ in range(60):
            gap = self._from_panel(u, k) - s
            open_ = np.abs(gap) > tol
            if not np.any(open_):
                break
            lo = np.where(open_ & (gap < 0.0), u, lo)  # keep the root bracketed
            hi = np.where(open_ & (gap > 0.0), u, hi)
            step = u - gap / self._speed(u)
            inside = (step >= lo) & (step <= hi)
            u = np.where(open_, np.where(inside, step, 0.5 * (lo + hi)), u)
        return u
