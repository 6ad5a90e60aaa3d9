"""Built-in sweeps: the open-chain example and tolerance study, the cantilever geometry sweeps
and the notch chart.

``open_chain_arcs`` and ``open_chain_tolerance`` (a tolerance study: the thickness
drawn from a normal distribution, the reference on a subsample) are sweep files shipped
in ``validation/data/sweeps``.
``slenderness`` and ``arc_angle`` sweep a single clamped arc (radius
:data:`RADIUS`, depth 1 mm, E = 2000 MPa, nu = 0.3) carrying a dead tip
force perpendicular to its chord, scaled at every point so that the linear
(ee) tip rotation is :data:`LINEAR_ROTATION`: the same moderate nonlinearity
at every geometry. Their base scene and axis values are computed here (the
arc starts at the origin, where it is clamped, whatever its angle), and
they run through the same engine as any sweep file.

``notch_ratio`` is the design chart of circular notch hinges: one hinge of
axis length L = 2 R (:data:`NOTCH_RADIUS`), clamped at one end and carrying
a lever, its neck thickness t swept over :data:`NOTCH_RATIOS` of R with the
blank H = t + 2 R (semicircular cut-outs of radius R), under an end moment
and a transverse force at the lever's tip, each scaled to the same small
linear rotation (:data:`NOTCH_ROTATION`, inside an aluminium hinge's
elastic range): where do ``beam:N``, ``dcmm:N``, the one-pivot ``prbm`` and
``ee`` stay within 1 % / 5 % of the continuum?

Units: mm, MPa, N, degrees (scene-file convention), rad for the rotation.
"""

from __future__ import annotations

import math
import tomllib
from importlib import resources

import numpy as np

RADIUS = 10.0  # mm
DEPTH = 1.0  # mm
LINEAR_ROTATION = 0.3  # rad
LEVELS = 6
SLENDERNESS_RATIOS = (1 / 3, 1 / 10, 1 / 30, 1 / 100, 1 / 300, 1 / 1000)
"""h / R of the slenderness sweep (120 deg arc)."""
SLENDERNESS_WIDTH = 120.0  # deg
ARC_WIDTHS = (30.0, 90.0, 180.0, 270.0, 330.0, 350.0)
"""Arc angles (deg) of the arc-angle sweep (h / R = :data:`ARC_RATIO`); a much shorter arc
would be a stub thicker than its length, which the scene loader refuses."""
ARC_RATIO = 1 / 30
CANTILEVER_MODELS = ("beam:40", "dcmm:1", "dcmm:2", "prbm", "ee")
NOTCH_RADIUS = 2.5  # mm
NOTCH_LEVER = 10.0  # mm, from the hinge's free end to the loaded tip
NOTCH_RATIOS = (0.05, 0.1, 0.2, 0.5, 1.0)
"""t / R of the notch sweep: from a slender neck to one as thick as the cut-outs' radius."""
NOTCH_ROTATION = 0.02  # rad
NOTCH_MODELS = ("beam:20", "dcmm:1", "dcmm:2", "prbm", "ee", "beam:20[eb]")
"""The notch chart's models: the calibrated defaults, and beam theory's plain hinge beside them."""
FILE_SWEEPS = ("open_chain_arcs", "open_chain_tolerance")
BUILTIN_SWEEPS = FILE_SWEEPS + ("slenderness", "arc_angle", "notch_ratio")


def _tip(width_deg: float) -> tuple[list[float], float]:
    """Tip point (mm) of the arc clamped at the origin and the force angle (deg) normal
    to its chord."""
    w = math.radians(width_deg)
    tip = [RADIUS * math.sin(w), RADIUS * (1.0 - math.cos(w))]
    return tip, 90.0 + width_deg / 2.0


def cantilever_scene(width_deg: float, thickness: float) -> dict:
    """Scene data (parsed-TOML form) of the clamped arc: centre (0, R), starting at the
    origin (angle -90 deg) and turning counterclockwise by ``width_deg``; thickness mm."""
    tip, angle = _tip(width_deg)
    return {
        "name": "cantilever",
        "description": f"Clamped arc, R = {RADIUS:g} mm, tip force normal to the chord",
        "material": {"youngs_modulus": 2000.0, "poisson_ratio": 0.3},
        "section": {"depth": DEPTH, "thickness": thickness},
        "ground": {"name": "g", "points": [[0.0, 0.0]]},
        "target": {"body": "t", "point": tip},
        "flexures": [
            {
                "name": "f",
                "bodies": ["g", "t"],
                "start_body": "g",
                "center": [0.0, RADIUS],
                "radius": RADIUS,
                "axis_deg": -90.0 + width_deg / 2.0,
                "width_deg": width_deg,
            }
        ],
        "load_cases": [
            {
                "name": "F",
                "kind": "force",
                "body": "t",
                "angle_deg": angle,
                "value": 1.0,
                "levels": LEVELS,
            }
        ],
    }


def _cantilever_sweep(name: str, description: str, axes: list[dict], combine: str) -> dict:
    width = SLENDERNESS_WIDTH if name == "slenderness" else ARC_WIDTHS[0]
    return {
        "name": name,
        "description": description,
        "base": cantilever_scene(width, ARC_RATIO * RADIUS),
        "models": list(CANTILEVER_MODELS),
        "reference": "continuum:0",
        "combine": combine,
        "linear_rotation": LINEAR_ROTATION,
        "axes": axes,
    }


def notch_scene(t_over_r: float) -> dict:
    """Scene data (parsed-TOML form) of the clamped circular notch hinge with a lever.

    Axis from the origin along x, L = 2 R, neck t = ``t_over_r`` R, blank
    H = t + 2 R; aluminium (E = 71700 MPa, nu = 0.33, density 2.81e-9 t/mm^3),
    depth 5 mm; the lever's tip L + :data:`NOTCH_LEVER` from the clamp.
    """
    t = t_over_r * NOTCH_RADIUS
    length = 2.0 * NOTCH_RADIUS
    tip = [length + NOTCH_LEVER, 0.0]
    return {
        "name": "notch",
        "description": f"Clamped circular notch hinge, R = {NOTCH_RADIUS:g} mm, lever "
        f"{NOTCH_LEVER:g} mm",
        "material": {"youngs_modulus": 71700.0, "poisson_ratio": 0.33},
        "section": {"depth": 5.0, "thickness": t},
        "ground": {"name": "g", "points": [[0.0, 0.0]]},
        "target": {"body": "lever", "point": tip},
        "flexures": [
            {
                "name": "h",
                "bodies": ["g", "lever"],
                "shape": "notch",
                "start": [0.0, 0.0],
                "end": [length, 0.0],
                "contour": "circular",
                "thickness": t,
                "height": t + 2.0 * NOTCH_RADIUS,
            }
        ],
        "load_cases": [
            {"name": "M", "kind": "moment", "body": "lever", "value": 1.0, "levels": LEVELS},
            {
                "name": "F",
                "kind": "force",
                "body": "lever",
                "point": tip,
                "angle_deg": 90.0,
                "value": 1.0,
                "levels": LEVELS,
            },
        ],
    }


def _notch_sweep() -> dict:
    ratios = np.array(NOTCH_RATIOS)
    return {
        "name": "notch_ratio",
        "description": f"Neck thickness t/R of a circular notch hinge (R = {NOTCH_RADIUS:g} mm, "
        "H = t + 2 R)",
        "base": notch_scene(NOTCH_RATIOS[0]),
        "models": list(NOTCH_MODELS),
        "reference": "continuum:2",
        "combine": "zip",
        "linear_rotation": NOTCH_ROTATION,
        "outputs": ["peak_stress"],
        "axes": [
            {"path": "flexures.h.thickness", "values": (ratios * NOTCH_RADIUS).tolist()},
            {"path": "flexures.h.height", "values": ((ratios + 2.0) * NOTCH_RADIUS).tolist()},
        ],
    }


def builtin_sweep(name: str) -> dict:
    """The sweep data (parsed-TOML form) of the built-in sweep ``name``."""
    if name in FILE_SWEEPS:
        text = resources.files("flexval.validation").joinpath("data", "sweeps", f"{name}.toml")
        return tomllib.loads(text.read_text(encoding="utf-8"))
    if name == "slenderness":
        return _cantilever_sweep(
            name,
            f"Slenderness h/R of a {SLENDERNESS_WIDTH:g} deg cantilever arc",
            [{"path": "section.thickness", "values": [q * RADIUS for q in SLENDERNESS_RATIOS]}],
            "grid",
        )
    if name == "arc_angle":
        widths = np.array(ARC_WIDTHS)
        tips = [_tip(w) for w in ARC_WIDTHS]
        return _cantilever_sweep(
            name,
            f"Arc angle of a cantilever arc, h/R = {ARC_RATIO:.4g}",
            [
                {"path": "flexures.f.width_deg", "values": widths.tolist()},
                {"path": "flexures.f.axis_deg", "values": (-90.0 + widths / 2.0).tolist()},
                {"path": "target.point.0", "values": [t[0][0] for t in tips]},
                {"path": "target.point.1", "values": [t[0][1] for t in tips]},
                {"path": "load_cases.F.angle_deg", "values": [t[1] for t in tips]},
            ],
            "zip",
        )
    if name == "notch_ratio":
        return _notch_sweep()
    raise KeyError(name)
