"""The not-a-knot cubic spline of the PRBM table (flexval.reducedmodels.prbm.spline).

References: scipy.interpolate.CubicSpline (same spline, its default ends);
the exact reproduction of cubic polynomials, which the not-a-knot ends
guarantee whatever the implementation.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from flexval.reducedmodels.prbm.parameters import load_table
from flexval.reducedmodels.prbm.spline import NotAKnotSpline


def _values(spline: NotAKnotSpline, xs: np.ndarray) -> np.ndarray:
    return np.array([spline(x) for x in xs])


def test_equals_scipy_on_the_prbm_table():
    """The shipped rho(arc angle) read anywhere in range, the knots included, and past the
    ends: the same numbers as scipy's CubicSpline (measured: bit-identical on 100 000
    points; 2 ulp allowed for a LAPACK build that rounds the tridiagonal solve differently)."""
    rows = load_table()["table"]
    widths = np.radians([row["width_deg"] for row in rows])
    rho = [row["rho"] for row in rows]
    xs = np.concatenate([np.linspace(-0.1, widths[-1] + 0.1, 20_001), widths])
    np.testing.assert_array_max_ulp(
        _values(NotAKnotSpline(widths, rho), xs), CubicSpline(widths, rho)(xs), maxulp=2
    )


@pytest.mark.parametrize("seed", range(5))
def test_equals_scipy_on_random_data(seed):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.uniform(0.1, 2.0, rng.integers(4, 30)))
    y = rng.normal(size=x.size)
    xs = np.linspace(x[0] - 1.0, x[-1] + 1.0, 2001)
    np.testing.assert_array_max_ulp(
        _values(NotAKnotSpline(x, y), xs), CubicSpline(x, y)(xs), maxulp=2
    )


def test_reproduces_a_cubic_and_passes_through_the_knots():
    """Not-a-knot ends make any cubic its own spline (round-off: 1e-12 of values ~ 1e2)."""
    x = np.array([-1.0, -0.3, 0.2, 1.1, 1.5, 2.9])

    def cubic(t):
        return 2.0 - 3.0 * t + 0.5 * t**2 + 1.25 * t**3

    spline = NotAKnotSpline(x, cubic(x))
    xs = np.linspace(-2.0, 4.0, 301)
    np.testing.assert_allclose(_values(spline, xs), cubic(xs), rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(_values(spline, x), cubic(x), rtol=0.0, atol=1e-14)


@pytest.mark.parametrize(
    "x, y",
    [
        ([0.0, 1.0, 2.0], [1.0, 2.0, 3.0]),
        ([0.0, 1.0, 1.0, 2.0], [0.0, 1.0, 2.0, 3.0]),
        ([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 2.0]),
    ],
)
def test_bad_tables_are_refused(x, y):
    with pytest.raises(ValueError):
        NotAKnotSpline(x, y)
