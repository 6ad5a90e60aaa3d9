"""Trace the copies of a tolerance study together: batched load paths from Python.

What it shows
-------------
* many copies of one mechanism, each with its own dimensions: the open chain with
  every arc's thickness h drawn from N(0.1, 0.002) mm (200 seeded draws);
* :func:`flexval.reducedmodels.core.batch.run_batch` tracing them with ``dcmm:1`` under
  f+ as one batch: one System, one assembly and one factorisation per Newton
  iteration for every copy, each copy's tests and step decisions its own;
* the same copies traced one by one give the same paths (to round-off: checked
  here on the first ten), in more time; a copy whose load steps part from the
  others' (a thin one takes smaller sub-steps) leaves the batch and is traced
  again with the others that left, so the largest batch holds most copies, not
  all;
* the spread of the target's displacement at full load over the draws, against
  its first-order estimate |d'(h)| std(h), with d' (and d'') from central
  differences of three more batched paths at h and h +- 1 % (std(h) the draws' own
  sample deviation, so that only the response's curvature separates the two).

Units: mm, N; times in ms.

Run: ``python examples/batch_tolerance.py``
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from flexval.geometry import load_scene
from flexval.reducedmodels import parse_model
from flexval.reducedmodels.core.batch import run_batch
from flexval.reducedmodels.models import run_reduced

DRAWS = 200
"""Copies in the study."""
MEAN, STD = 0.1, 0.002
"""The arcs' thickness h ~ N(MEAN, STD), mm (the built-in open_chain_tolerance sweep's)."""
SOLO = 10
"""Copies also traced one by one, for the comparison."""


def with_thickness(mechanism, h: float):
    """The mechanism with every flexure's thickness h (mm), its depth unchanged."""
    flexures = tuple(
        dataclasses.replace(f, section=dataclasses.replace(f.section, thickness=h))
        for f in mechanism.flexures
    )
    return dataclasses.replace(mechanism, flexures=flexures)


def end_displacement(path) -> float:
    """The target's displacement magnitude at full load, mm."""
    return float(np.hypot(path.dx[-1], path.dy[-1]))


def main() -> dict[str, float]:
    """Trace the study batched and (in part) one by one; its numbers."""
    scene = load_scene("open_chain")
    case = scene.load_case("f+")
    spec = parse_model("dcmm:1")
    h = np.random.default_rng(7).normal(MEAN, STD, DRAWS)
    mechanisms = [with_thickness(scene.mechanism, float(v)) for v in h]
    run_batch(mechanisms[:2], spec, [case] * 2)  # untimed: loads the compiled kernels
    run_reduced(mechanisms[0], spec, case)

    t0 = time.perf_counter()
    batched = run_batch(mechanisms, spec, [case] * DRAWS)
    batched_ms = 1e3 * (time.perf_counter() - t0) / DRAWS
    t0 = time.perf_counter()
    alone = [run_reduced(m, spec, case) for m in mechanisms[:SOLO]]
    alone_ms = 1e3 * (time.perf_counter() - t0) / SOLO
    worst = max(
        max(abs(a.dx[-1] - b.dx[-1]), abs(a.dy[-1] - b.dy[-1])) / end_displacement(a)
        for a, b in zip(alone, batched)
    )

    d = np.array([end_displacement(p) for p in batched])
    step = 0.01 * MEAN
    ends = [
        end_displacement(p)
        for p in run_batch(
            [with_thickness(scene.mechanism, MEAN + s) for s in (-step, 0.0, step)],
            spec,
            [case] * 3,
        )
    ]
    slope = (ends[2] - ends[0]) / (2 * step)  # mm / mm
    curvature = (ends[2] - 2 * ends[1] + ends[0]) / step**2  # mm / mm^2
    out = {
        "copies in the largest batch": float(max(p.stats["batch"] for p in batched)),
        "largest batch-solo difference (of |d|)": worst,
        "ms per path, batched": batched_ms,
        "ms per path, one by one": alone_ms,
        "mean |d| (mm)": float(d.mean()),
        "std |d| (mm)": float(d.std(ddof=1)),
        "first-order std (mm)": abs(slope) * float(h.std(ddof=1)),
        "d'(h) (mm/mm)": slope,
        "d''(h) (mm/mm^2)": curvature,
    }
    for name, value in out.items():
        print(f"{name:42s} {value:.6g}")
    return out


if __name__ == "__main__":
    main()
