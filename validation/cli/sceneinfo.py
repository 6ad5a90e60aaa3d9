"""Describe a scene: bodies, flexures with their ellipse data, target, load cases.

Used by ``flexval info``. Units in the output: mm, N, N mm, MPa, deg.
"""

from __future__ import annotations

import math

import numpy as np

from flexval.geometry import Force, Moment, Scene
from flexval.reducedmodels.catalogue import parse_model

from ..report.tables import Column, sig, text_table


def scene_info(scene: Scene) -> dict:
    """A JSON-ready description of ``scene`` (lengths mm, angles deg, EI N mm^2, w 1/(N mm))."""
    mech = scene.mechanism
    flexures = []
    for f in mech.flexures:
        varying = None if f.section.is_uniform else varying_section(f, mech.material)
        if varying is None:
            EI, EA = f.bending_stiffness(mech.material), f.axial_stiffness(mech.material)
            ell = f.shape.ellipse(EI)
        else:
            EI, EA, ell = varying["EI_Nmm2"], varying["EA_N"], varying.pop("ellipse")
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
            "EA_N": EA,
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
        if varying is not None:
            entry["section"] = varying
        if mech.inertia.density is not None:  # (inertia's solvers load only where needed)
            from flexval.reducedmodels.core.inertia import line_density, piece_inertia

            mass_per_length = line_density(mech.inertia.density, f.section)  # t/mm
            entry["mass_t"] = piece_inertia(
                f.shape, 0.0, f.shape.length, mass_per_length, np.zeros(2)
            )[0]
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
        "material": {
            "E_MPa": mech.material.youngs_modulus,
            "nu": mech.material.poisson_ratio,
            "density_t_per_mm3": mech.inertia.density,
            "yield_strength_MPa": mech.material.yield_strength,
            "fatigue_strength_MPa": mech.material.fatigue_strength,
        },
        "gravity_mm_per_s2": (
            None if mech.inertia.gravity is None else mech.inertia.gravity.tolist()
        ),
        "ground": mech.ground,
        "bodies": {n: _body_entry(mech, n) for n in mech.bodies},
        "flexures": flexures,
        "target": {"body": mech.target_body, "point": mech.target_point.tolist()},
        "load_cases": cases,
        "models": [parse_model(m, scene.source, "request.models").id for m in scene.models],
    }


def _body_entry(mech, name: str) -> dict:
    """A body's kind, attachment points (mm) and, where the scene gives it, its mass (t),
    rotary inertia about its centre of mass (t mm^2) and that centre (mm)."""
    body, mass = mech.bodies[name], mech.inertia.bodies.get(name)
    entry = {"ground": body.is_ground, "attachment_points": body.points.tolist()}
    if mass is not None:
        entry.update(
            mass_t=mass.mass,
            inertia_t_mm2=mass.inertia,
            center_of_mass_mm=np.asarray(mass.center_of_mass, float).tolist(),
        )
    return entry


def varying_section(flexure, material) -> dict:
    """A varying section's thickness law and its compliance-based stiffnesses.

    EI and EA of a varying section are the uniform-equivalent ones, L / ∫ ds / EI
    and L / ∫ ds / EA (N mm^2, N: a uniform flexure of the same length with
    these has the same rotational and axial compliance), beside the
    stiffnesses themselves, 1 / ∫ ds / EI (N mm per rad) and 1 / ∫ ds / EA
    (N/mm), from :func:`flexval.geometry.compliance.curve_compliance`. The
    ellipse (key ``ellipse``) is that of the varying section.
    """
    from flexval.geometry.compliance import curve_compliance
    from flexval.geometry.profiles import quadrature_panels

    profile = flexure.section.profile
    found = curve_compliance(flexure.shape, flexure.section, material)
    length = flexure.shape.length
    s, weights = quadrature_panels(length, profile.breakpoints)
    axial = float(weights @ (1.0 / flexure.axial_stiffness_at(material, s)))  # ∫ ds / EA
    out = {
        "profile": profile.kind,
        **profile.parameters(),
        "min_thickness_mm": profile.min_thickness,
        "max_thickness_mm": profile.max_thickness,
        "rotational_stiffness_Nmm": 1.0 / found.ellipse.weight,
        "axial_stiffness_N_per_mm": 1.0 / axial,
        "EI_Nmm2": length / found.ellipse.weight,
        "EA_N": length / axial,
        "ellipse": found.ellipse,
    }
    if profile.kind == "taper":
        from flexval.reducedmodels.core.validity import taper_slope

        out["contour_slope_rad"] = taper_slope(flexure.section)
    if profile.kind == "notch":
        from flexval.reducedmodels.notchcorrection import factors_of

        factors = factors_of(flexure, material.poisson_ratio)
        out["calibrated"] = {
            "bending_factor": factors.bending,
            "shear_factor": factors.shear,
            "stress_concentration": factors.stress,
            "inside_range": factors.inside,
            "ratios": factors.where,
        }
    return out


def _section_line(f: dict) -> str:
    """One line on a varying section: its law and compliance-based stiffnesses."""
    sec = f["section"]
    if sec["profile"] == "notch":
        law = (
            f"{sec['contour']} notch, t = {sec['thickness']:g} mm at the middle, "
            f"H = {sec['height']:g} mm at the ends"
        )
        if "fillet_radius" in sec:
            law += f", fillet radius {sec['fillet_radius']:g} mm"
        if "exponent" in sec:
            law += f", exponent {sec['exponent']:g}"
    else:
        from flexval.reducedmodels.core.validity import TAPER_SLOPE

        h0, h1 = sec["thickness"]
        slope = sec["contour_slope_rad"]
        law = f"taper from h = {h0:g} mm to {h1:g} mm, contour slope {slope:.3g} rad"
        if slope > TAPER_SLOPE:
            law += (
                f" (STEEPER than the {TAPER_SLOPE:.2g} rad within which the reduced models' "
                "section integrals hold to 0.5 %)"
            )
    line = (
        f"  {f['name']}: {law}; stiffness 1/∫ds/EI = {sig(sec['rotational_stiffness_Nmm'])} "
        f"N mm/rad, 1/∫ds/EA = {sig(sec['axial_stiffness_N_per_mm'])} N/mm (EI, EA above: "
        "L over these integrals)"
    )
    calibrated = sec.get("calibrated")
    if calibrated:
        line += (
            f"\n      reduced models (unless [eb]): bending compliance x "
            f"{calibrated['bending_factor']:.4f}, shear x {calibrated['shear_factor']:.4f}, "
            f"stress concentration K(s), {calibrated['stress_concentration']:.4f} at the waist "
            f"(calibrated against the continuum; {calibrated['ratios']}"
            + (
                ")"
                if calibrated["inside_range"]
                else ": OUTSIDE the calibrated range, the nearest calibrated hinge's factors)"
            )
        )
    return line


def _pt(p) -> str:
    return f"({p[0]:.3f}, {p[1]:.3f})"


def format_info(info: dict) -> str:
    """Human-readable text of :func:`scene_info`."""
    lines = [f"scene {info['scene']}  ({info['source']})"]
    if info["description"]:
        lines.append(f"  {info['description']}")
    m = info["material"]
    extra = [
        f"{label} = {m[key]:g} {unit}"
        for key, label, unit in (
            ("density_t_per_mm3", "density", "t/mm3"),
            ("yield_strength_MPa", "yield strength", "MPa"),
            ("fatigue_strength_MPa", "fatigue strength", "MPa"),
        )
        if m.get(key) is not None
    ]
    lines.append(", ".join([f"material  E = {m['E_MPa']:g} MPa, nu = {m['nu']:g}", *extra]))
    if info.get("gravity_mm_per_s2") is not None:
        lines.append(f"gravity  {_pt(info['gravity_mm_per_s2'])} mm/s2")
    lines.append("bodies")
    massive = any("mass_t" in b for b in info["bodies"].values())
    columns = [Column("name", "<"), Column("kind", "<"), Column("attachment points mm", "<")]
    if massive:
        columns += [Column("mass t"), Column("inertia t mm2"), Column("centre of mass mm")]
    rows = []
    for name, b in info["bodies"].items():
        row = [
            name,
            "ground" if b["ground"] else "link",
            " -- ".join(_pt(p) for p in b["attachment_points"]),
        ]
        if massive:
            row += (
                [sig(b["mass_t"]), sig(b["inertia_t_mm2"]), _pt(b["center_of_mass_mm"])]
                if "mass_t" in b
                else ["–", "–", "–"]
            )
        rows.append(row)
    lines += text_table(columns, rows, "  ")
    lines.append("flexures")
    rows = []
    for f in info["flexures"]:
        e = f["ellipse"]
        rows.append(
            [
                f["name"],
                f"{f['start_body']}->{f['end_body']}",
                _pt(f["start"]),
                _pt(f["end"]),
                f"{f['length_mm']:.3f}",
                sig(f["EI_Nmm2"]),
                sig(e["w_per_Nmm"]),
                _pt(e["C_mm"]),
                f"{e['a_mm']:.3f}",
                f"{e['b_mm']:.3f}",
            ]
        )
    lines += text_table(
        [
            Column("name", "<"),
            Column("bodies", "<"),
            Column("start mm"),
            Column("end mm"),
            Column("L mm"),
            Column("EI N mm2"),
            Column("w 1/(N mm)"),
            Column("C mm"),
            Column("a mm"),
            Column("b mm"),
        ],
        rows,
        "  ",
    )
    lines += [_section_line(f) for f in info["flexures"] if "section" in f]
    if any("mass_t" in f for f in info["flexures"]):
        lines.append(
            "  flexure masses: "
            + ", ".join(f"{f['name']} {sig(f['mass_t'])} t" for f in info["flexures"])
        )
    t = info["target"]
    lines.append(f"target  body {t['body']} at {_pt(t['point'])} mm")
    lines.append("load cases")
    cases = []
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
        cases.append([lc["name"], str(lc["levels"]), "; ".join(parts)])
    lines += text_table([Column("name", "<"), Column("levels"), Column("loads", "<")], cases, "  ")
    if info["models"]:
        lines.append(f"requested models: {', '.join(info['models'])}")
    return "\n".join(lines)
