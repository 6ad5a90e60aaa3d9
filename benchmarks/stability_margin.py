"""How far the stability rule's verdict is from round-off, over the resolution.

A clamped-free column (tests/scenes/euler_column.toml) is held straight 1 %
above and 1 % below Euler's load pi^2 EI / (4 L^2), and its tangent judged at
each beam resolution. Printed per N:

* ``lambda_min``: the tangent's eigenvalue nearest zero (N/mm and N mm mixed,
  as K is); ``|K|``: the spectral-radius bound a margin against |K| uses
  (the largest entry times 2b + 1);
* ``lambda/|K|``: what a rule "negative below -1e-12 |K|" compares with
  1e-12: it falls as N^-3 and hides the buckled state from about N = 400;
* ``pivot margin``: the critical pivot d_k over its own round-off bound
  gamma sigma_k (:mod:`flexval.reducedmodels.core.stability`), below the load
  (positive) and above it (negative); the rule counts a pivot whose margin is
  below -1, and the margin stays far from 1 in size while N grows;
* the rule's count above and below the load.

Usage::

    python benchmarks/stability_margin.py [--elements 5 10 20 ...]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

import flexval
from flexval.reducedmodels.core import stability
from flexval.reducedmodels.core.newton import FixedLoad, solve
from flexval.reducedmodels.models import build_system

COLUMN = Path(__file__).resolve().parents[1] / "tests" / "scenes" / "euler_column.toml"


def pivot_margins(band: np.ndarray) -> np.ndarray:
    """d_k / (gamma sigma_k) of every pivot of the band's LDL^T without interchanges (upper
    band form (b + 1, n)): the rule's own arithmetic, written out in numpy for inspection."""
    b, n = band.shape[0] - 1, band.shape[1]
    gamma = stability.tolerance(b + 2)
    work = np.zeros((n, b + 1))
    for t in range(b + 1):
        work[: n - t, t] = band[b - t, t:]
    scales = np.abs(work[:, 0]).copy()
    margins = np.empty(n)
    for k in range(n):
        d = work[k, 0]
        margins[k] = d / (gamma * scales[k])
        reach = min(b, n - 1 - k)
        a = work[k, 1 : reach + 1]
        scales[k + 1 : k + 1 + reach] += a * a / abs(d)
        for t in range(1, reach + 1):
            work[k + t, : reach + 1 - t] -= (a[t - 1] / d) * work[k, t : reach + 1]
    return margins


def band_of(tangent) -> np.ndarray:
    """The tangent's upper band form (b + 1, n): its own where it is banded, else under a
    reverse Cuthill-McKee order (a small, dense one)."""
    if hasattr(tangent, "storage"):
        return np.asarray(tangent.storage)
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    matrix = tangent.tosparse().tocsr()
    order = reverse_cuthill_mckee(matrix, symmetric_mode=True)
    dense = matrix[order][:, order].toarray()
    rows, cols = np.nonzero(dense)
    b = int(np.max(cols - rows, initial=0))
    band = np.zeros((b + 1, dense.shape[0]))
    for t in range(b + 1):
        band[b - t, t:] = np.diagonal(dense, t)
    return band


def straight_state(system, loads, factor: float):
    """The straight column's equilibrium at ``factor`` (Newton from rest: no imperfection)."""
    result = solve(FixedLoad(system, loads, factor), system.initial_state(), system.settings)
    return system.assemble(result.state, loads, factor)[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--elements", type=int, nargs="+", default=[5, 10, 20, 50, 100, 200, 400, 1000, 3000]
    )
    args = parser.parse_args()
    scene = flexval.load_scene(str(COLUMN))
    case = scene.load_cases[0]
    flexure = scene.mechanism.flexures[0]
    ei = flexure.bending_stiffness(scene.mechanism.material)
    euler = math.pi**2 * ei / (4.0 * flexure.shape.length**2) / case.magnitude
    print(f"clamped-free column, Euler's load factor {euler:.6f}; 1 % below and above it")
    print(
        f"{'N':>6} {'lambda_min':>11} {'|K|':>9} {'lambda/|K|':>11} "
        f"{'margin below':>13} {'margin above':>13} {'count below':>12} {'count above':>12}"
    )
    for n in args.elements:
        system = build_system(scene.mechanism, flexval.parse_model(f"beam:{n}"))
        loads = system.loads(case)
        row = []
        for factor in (0.99 * euler, 1.01 * euler):
            tangent = straight_state(system, loads, factor)
            margins = pivot_margins(band_of(tangent))
            row.append((tangent, margins[np.argmin(np.abs(margins))]))
        above = row[1][0]
        matrix = above.tosparse()
        (lowest,) = spla.eigsh(matrix, k=1, sigma=0.0, which="LM", return_eigenvectors=False)
        band = band_of(above)
        size = np.abs(band).max() * (2 * band.shape[0] - 1)
        print(
            f"{n:>6} {lowest:>11.3e} {size:>9.2e} {abs(lowest) / size:>11.2e} "
            f"{row[0][1]:>13.3e} {row[1][1]:>13.3e} "
            f"{row[0][0].negative_eigenvalues():>12} {row[1][0].negative_eigenvalues():>12}"
        )


if __name__ == "__main__":
    main()
