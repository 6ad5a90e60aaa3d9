"""Geometry sweeps of a single flexure: slenderness h/r and arc angle.

A cantilever arc (radius ``R`` = 10 mm, depth b = 1 mm, E = 2000 MPa,
nu = 0.3) clamped at its start carries a dead tip force perpendicular to the
chord, scaled so that the linear (EE) tip rotation is ``rotation`` rad: the
same moderate nonlinearity at every geometry. Each model's end-of-ramp
displacement-vector and rotation errors (percent) are measured against the
continuum reference, which must not lock as h/r -> 0 (quadratic elements,
aspect ratio 1) and must meet the beam models' thin limit.

Units: mm, N, MPa, rad (widths in degrees at the interface).
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

from geometry import Arc, Force, LoadCase, Material, SceneError, Section, Segment
from geometry.mechanism import FlexureSpec, assemble
from reducedmodels.catalogue import parse_model
from reducedmodels import SolverError, run_reduced

from .compare import errors

R = 10.0
LEVELS = 6


def cantilever(width_deg: float, h: float, radius: float = R):
    """Mechanism and unit-free load case of a clamped arc (straight segment at width 0)."""
    if width_deg == 0.0:
        length = radius * math.radians(120.0)
        shape = Segment((0.0, 0.0), (length, 0.0))
    else:
        shape = Arc((0.0, 0.0), radius, math.pi / 2, math.radians(width_deg))
    spec = FlexureSpec("f", shape, ("g", "t"), Section(1.0, h), start_body="g")
    ends = shape.end_points
    mech = assemble([spec], "g", ends[0][None], Material(2000.0, 0.3), "t", ends[1])
    chord = ends[1] - ends[0]
    angle = math.atan2(chord[1], chord[0]) + math.pi / 2
    return mech, LoadCase("F", (Force("t", ends[1], angle, 1.0),), LEVELS)


def _scaled(mech, case: LoadCase, rotation: float) -> LoadCase:
    lin = run_reduced(mech, parse_model("ee"), case)
    scale = rotation / abs(lin.rotation[-1])
    f = case.components[0]
    return LoadCase(case.name, (Force(f.body, f.point, f.angle, scale),), case.levels)


def sweep(points: Sequence[tuple[float, float]], models: Sequence[str], level: int = 0,
          rotation: float = 0.3, progress: Callable[[str], None] | None = None) -> list[dict]:
    """Errors of ``models`` against ``continuum:level`` at each (width_deg, h/r) point."""
    from .continuum import run_continuum

    rows = []
    for width, ratio in points:
        mech, unit = cantilever(width, ratio * R)
        case = _scaled(mech, unit, rotation)
        if progress:
            progress(f"sweep width {width:g} deg, h/r {ratio:.4g}")
        row = {"width_deg": width, "h_over_r": ratio, "errors": {}, "failures": {}}
        try:
            ref = run_continuum(mech, case, level=level)
        except SolverError as exc:
            row["failures"][f"continuum:{level}"] = str(exc)
            rows.append(row)
            continue
        row["reference_seconds"] = ref.seconds
        for m in models:
            try:
                lp = run_reduced(mech, parse_model(m), case)
                e = errors(lp, ref)
                row["errors"][m] = {"disp": e["end_disp_vec"], "rot": e["end_rot"]}
            except (SolverError, SceneError) as exc:
                row["failures"][m] = str(exc)
        rows.append(row)
    return rows


def format_sweep(rows: list[dict], title: str) -> str:
    """Markdown table: one row per geometry, disp/rot error (%) per model."""
    models = sorted({m for r in rows for m in r["errors"]})
    lines = [f"### {title}", "",
             "| width (deg) | h/r | " + " | ".join(f"{m} disp / rot (%)" for m in models) + " |",
             "|---:|---:|" + "---:|" * len(models)]
    for r in rows:
        cells = [(f"{r['errors'][m]['disp']:.2f} / {r['errors'][m]['rot']:.2f}"
                  if m in r["errors"] else "failed") for m in models]
        lines.append(f"| {r['width_deg']:g} | {r['h_over_r']:.4g} | " + " | ".join(cells) + " |")
    fails = [f"- {m} at width {r['width_deg']:g}, h/r {r['h_over_r']:.4g}: {msg}"
             for r in rows for m, msg in r["failures"].items()]
    return "\n".join(lines + ([""] + fails if fails else [])) + "\n"


SLENDERNESS = tuple((120.0, q) for q in (1 / 3, 1 / 10, 1 / 30, 1 / 100, 1 / 300, 1 / 1000))
ARC_ANGLES = tuple((w, 1 / 30) for w in (0.0, 1.0, 30.0, 90.0, 180.0, 270.0, 330.0, 350.0))
