"""Describe a scene: bodies, flexures with their ellipse data, target, load cases.

Used by ``flexval info``. Units in the output: mm, N, N mm, MPa, deg.
"""

from __future__ import annotations

import math

from flexval.geometry import Force, Moment, Scene
from flexval.reducedmodels.catalogue import parse_model


def scene_info(scene: Scene) -> dict:
    """A JSON-ready description of ``scene`` (lengths mm, angles deg, EI N mm^2, w 1/(N mm))."""
    mech = scene.mechanism
    flexures = []
    for f in mech.flexures:
        EI = f.bending_stiffness(mech.material)
        ell = f.shape.ellipse(EI)
        entry = {
            "name": f.name,
            "bodies": list(f.bodies),
            "shape": f.shape.kind,
            "start": f.shape.end_points[0].tolist(),
            "end": f.shape.end_points[1].tolist(),
            "start_body": f.start_body,
            "end_body": f.end_body,
            "length_mm": f.shape.length,
            "b_mm": f.section.depth,
            "h_mm": f.section.thickness,
            "EI_Nmm2": EI,
            "EA_N": f.axial_stiffness(mech.material),
            "ellipse": {
                "w_per_Nmm": ell.weight,
                "C_mm": ell.center.tolist(),
                "a_mm": ell.a,
                "b_mm": ell.b,
                "e1": ell.axes[:, 0].tolist(),
                "e2": ell.axes[:, 1].tolist(),
            },
        }
        entry.update(f.shape.parameters())
        flexures.append(entry)
    cases = []
    for lc in scene.load_cases:
        comps = []
        for c in lc.components:
            if isinstance(c, Moment):
                comps.append({"kind": "moment", "body": c.body, "value_Nmm": c.value})
            elif isinstance(c, Force):
                comps.append(
                    {
                        "kind": "force",
                        "body": c.body,
                        "point": list(map(float, c.point)),
                        "angle_deg": math.degrees(c.angle),
                        "value_N": c.value,
                    }
                )
        cases.append({"name": lc.name, "levels": lc.levels, "loads": comps})
    return {
        "scene": scene.name,
        "source": scene.source,
        "description": scene.description,
        "material": {"E_MPa": mech.material.youngs_modulus, "nu": mech.material.poisson_ratio},
        "ground": mech.ground,
        "bodies": {
            n: {"ground": b.is_ground, "attachment_points": b.points.tolist()}
            for n, b in mech.bodies.items()
        },
        "flexures": flexures,
        "target": {"body": mech.target_body, "point": mech.target_point.tolist()},
        "load_cases": cases,
        "models": [parse_model(m, scene.source, "request.models").id for m in scene.models],
    }


def _pt(p) -> str:
    return f"({p[0]:.3f}, {p[1]:.3f})"


def format_info(info: dict) -> str:
    """Human-readable text of :func:`scene_info`."""
    lines = [f"scene {info['scene']}  ({info['source']})"]
    if info["description"]:
        lines.append(f"  {info['description']}")
    m = info["material"]
    lines.append(f"material  E = {m['E_MPa']:g} MPa, nu = {m['nu']:g}")
    lines.append("bodies (attachment points, mm)")
    for name, b in info["bodies"].items():
        tag = "ground" if b["ground"] else "link"
        pts = " -- ".join(_pt(p) for p in b["attachment_points"])
        lines.append(f"  {name:>6} {tag:<6} {pts}")
    lines.append("flexures")
    lines.append(
        f"  {'name':<6} {'bodies':<8} {'start':>18} {'end':>18} {'L mm':>8} "
        f"{'EI N mm2':>10} {'w 1/Nmm':>10} {'C mm':>18} {'a mm':>7} {'b mm':>7}"
    )
    for f in info["flexures"]:
        e = f["ellipse"]
        lines.append(
            f"  {f['name']:<6} {f['start_body'] + '->' + f['end_body']:<8} {_pt(f['start']):>18} "
            f"{_pt(f['end']):>18} {f['length_mm']:8.3f} {f['EI_Nmm2']:10.4g} "
            f"{e['w_per_Nmm']:10.4g} {_pt(e['C_mm']):>18} {e['a_mm']:7.3f} {e['b_mm']:7.3f}"
        )
    t = info["target"]
    lines.append(f"target  body {t['body']} at {_pt(t['point'])} mm")
    lines.append("load cases")
    for lc in info["load_cases"]:
        parts = []
        for c in lc["loads"]:
            if c["kind"] == "moment":
                parts.append(f"moment {c['value_Nmm']:g} N mm on body {c['body']}")
            else:
                parts.append(
                    f"force {c['value_N']:g} N at {c['angle_deg']:g} deg on body "
                    f"{c['body']} at {_pt(c['point'])}"
                )
        lines.append(f"  {lc['name']:<6} {'; '.join(parts)}  ({lc['levels']} levels from 0)")
    if info["models"]:
        lines.append(f"requested models: {', '.join(info['models'])}")
    return "\n".join(lines)
