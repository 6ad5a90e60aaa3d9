"""How the cost of reading and checking a scene grows with the number of flexures.

Builds a valid open chain of n arcs (radius 1 mm, 120 deg, apex up), each
starting where the previous one ends (the body between them holds both ends
at one point), as parsed TOML data and times
:func:`flexval.geometry.scene.parse_scene` on it: field checks, end ownership, the
body-graph walk, the overlap check (a bounding-box sweep, then polyline
crossings of the candidate pairs), degenerate magnitudes and the structure
check. Prints, per n, the median wall time over the repeats, the time per
flexure and the number of flexure pairs the overlap check tests (neighbours'
bounding boxes touch at the shared point: n - 1), against all n (n - 1) / 2.

Usage::

    python benchmarks/bench_scene_validation.py [--sizes 10 100 1000] [--repeats 3]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from flexval.geometry.overlap import SAMPLES, candidate_pairs
from flexval.geometry.scene import parse_scene

SIZES = (10, 100, 1000)
RADIUS, WIDTH_DEG = 1.0, 120.0  # mm, deg
PITCH = 2.0 * RADIUS * math.sin(math.radians(WIDTH_DEG / 2))  # the chord, mm: ends meet


def chain_scene(n: int) -> dict:
    """Scene data of an open chain of n arcs along x: body k holds arc k's left end,
    which is also arc k-1's right end."""
    half = math.radians(WIDTH_DEG / 2)
    left = np.array([-RADIUS * math.sin(half), RADIUS * math.cos(half)])  # relative to the centre
    flexures = [
        {
            "name": f"e{k}",
            "bodies": [str(k), str(k + 1)],
            "center": [PITCH * k, 0.0],
            "radius": RADIUS,
            "axis_deg": 90.0,
            "width_deg": WIDTH_DEG,
        }
        for k in range(n)
    ]
    tip = [PITCH * (n - 1) - left[0], left[1]]
    return {
        "name": f"chain{n}",
        "material": {"youngs_modulus": 2100.0, "poisson_ratio": 0.3},
        "section": {"depth": 1.0, "thickness": 0.1},
        "ground": {"name": "0", "points": [left.tolist()]},
        "target": {"body": str(n), "point": tip},
        "flexures": flexures,
        "load_cases": [{"name": "m", "kind": "moment", "value": 1e-3}],
    }


def measure(n: int, repeats: int) -> tuple[float, int]:
    """Median wall seconds of parse_scene on the n-arc chain, and the overlap candidate pairs."""
    data = chain_scene(n)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        scene = parse_scene(data, f"<chain {n}>")
        times.append(time.perf_counter() - t0)
    lines = [
        f.shape.point(np.linspace(0.0, f.shape.length, SAMPLES + 1))
        for f in scene.mechanism.flexures
    ]
    return statistics.median(times), len(candidate_pairs(lines))


def main() -> None:
    """Print the scaling table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=SIZES, help="flexure counts n")
    parser.add_argument("--repeats", type=int, default=3, help="runs per n; the median is shown")
    args = parser.parse_args()
    print(f"open chain of n arcs, parse_scene, median of {args.repeats} runs")
    print(f"{'n':>6} {'seconds':>9} {'ms/flexure':>11} {'pairs tested':>13} {'all pairs':>10}")
    for n in args.sizes:
        seconds, pairs = measure(n, args.repeats)
        print(
            f"{n:>6} {seconds:>9.3f} {1e3 * seconds / n:>11.3f} {pairs:>13} {n * (n - 1) // 2:>10}"
        )


if __name__ == "__main__":
    main()
