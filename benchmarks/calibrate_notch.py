"""Offline calibration of the notch-hinge table ``reducedmodels/data/notch_table.json``.

The reduced models see a notch hinge through its section's integrals: bending ∫ ds/EI(s),
shear ∫ ds/(k G A(s)), axial ∫ ds/EA(s) (Euler-Bernoulli and Timoshenko beam theory). A
notch's short, deep sections do not bend as beam theory says: the fibres far from the axis
where the contour widens carry less than the linear strain, and the hinge is more compliant
than ∫ ds/EI by 1 % (slender, shallow notches) to 50 % (short, deep ones). This script
measures that excess against the continuum reference and tabulates it; the runtime
(:mod:`flexval.reducedmodels.notchcorrection`) interpolates the table. It is not part of
the package; the runtime only reads the table. Run from the repository root

    python benchmarks/calibrate_notch.py              # rewrites the shipped table (~9 min)
    python benchmarks/calibrate_notch.py --held-out   # the interpolation error table

What is measured
----------------
A single hinge of axis length L joins the ground to a lever; at the lever's end (the
hinge's end, x = L) a moment M and, apart, a force F across the axis, each small enough
(rotation 1e-4 rad) for the response to be linear. ``continuum:2`` (plane stress, the
reference at a mesh level within 2e-5 of the next finer on these hinges) gives the end
rotation under M and the end deflection under F. With the beam-theory compliance
C (``geometry.compliance.curve_compliance``: Euler-Bernoulli bending and axial terms,
at the end point) and the shear integral S = ∫ ds/(k G A) (k = 5/6):

    bending factor  r_b = theta_continuum / (M C_theta)             (the excess of ∫ ds/EI),
    shear factor    r_s = (dy_continuum / F - r_b C_yy) / S          (what is left, in S).

and the stress concentration at the waist

    K = sigma_fibre / (6 M / (b t^2))     (the continuum's recovered surface fibre peak under
                                           the moment over the beam formula at the waist).

and, along the hinge, the same ratio K(s) over 6 M / (b h(s)^2) and the shear's shift delta(s)
of the moment under the force (:func:`surface_profiles`). The reduced models then take
E / r_b for bending and G / r_s for shear on the hinge (and include the shear term), which
reproduces both measurements, and report the largest of K(s) times their beam formula, the
moment taken at s - delta(s), as the hinge's surface fibre stress; the moment and the force also
turn the hinge by r_b as well as each other (checked in the held-out table). r_b does not
depend on Poisson's ratio (1.0699, 1.0696, 1.0691 at nu = 0.25, 0.33, 0.42 on a circular
hinge of t/L 0.1, H/t 10); r_s (1 + nu) nearly does not (1.2945, 1.3046, 1.3142), so the
table holds r_s at nu = 0.33 and the runtime scales it by 1.33 / (1 + nu).

Grid: t/L and H/t geometric (:data:`T_OVER_L`, :data:`H_OVER_T`), every contour; circular
and corner-filleted hinges only where they exist (H - t <= L), with the deepest one of
each t/L (H = t + L) added; power contours at the exponents :data:`EXPONENTS` (the runtime
interpolates between them by a cubic spline in log n: the factors are convex in n).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from flexval.reducedmodels.notchcorrection import STATIONS, station_fractions

ROOT = Path(__file__).resolve().parent.parent
TABLE = ROOT / "reducedmodels" / "data" / "notch_table.json"

T_OVER_L = (0.015, 0.025, 0.04, 0.065, 0.1, 0.16, 0.25, 0.35, 0.5)
H_OVER_T = (1.5, 2.2, 3.2, 4.7, 7.0, 10.0, 15.0, 22.0, 30.0, 45.0)
EXPONENTS = (1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0)
CONTOURS = ("circular", "elliptical", "corner-filleted", "power")
LEVEL = 2
POISSON = 0.33
YOUNG = 70000.0  # MPa; the factors are ratios, independent of E
LENGTH = 2.0  # mm; the factors depend on shape ratios only
DEPTH = 5.0  # mm
ROTATION = 1e-4
"""rad: small enough for the continuum's response to be linear to 1e-4 of itself."""


def notch_scene(contour: str, t_over_l: float, h_over_t: float, exponent: float | None = None):
    """A single hinge (axis from (0, 0) to (L, 0)) from the ground to a lever, with a
    moment case and a force case across the axis at its end; loads of 1 (scaled later)."""
    from flexval.geometry.scene import parse_scene

    t = t_over_l * LENGTH
    height = h_over_t * t
    hinge = {
        "name": "hinge",
        "bodies": ["ground", "lever"],
        "shape": "notch",
        "start": [0.0, 0.0],
        "end": [LENGTH, 0.0],
        "contour": contour,
        "thickness": t,
        "height": height,
    }
    if contour == "corner-filleted":
        hinge["fillet_radius"] = 0.5 * (height - t)
    if contour == "power":
        hinge["exponent"] = exponent
    data = {
        "name": "notch",
        "material": {"youngs_modulus": YOUNG, "poisson_ratio": POISSON},
        "section": {"depth": DEPTH, "thickness": t},
        "ground": {"name": "ground", "points": [[0.0, 0.0]]},
        "target": {"body": "lever", "point": [LENGTH, 0.0]},
        "flexures": [hinge],
        "load_cases": [
            {"name": "moment", "kind": "moment", "body": "lever", "value": 1.0},
            {
                "name": "force",
                "kind": "force",
                "body": "lever",
                "point": [LENGTH, 0.0],
                "angle_deg": 90.0,
                "value": 1.0,
            },
        ],
    }
    return parse_scene(data, f"<{contour} t/L {t_over_l} H/t {h_over_t} n {exponent}>")


def exists(contour: str, t_over_l: float, h_over_t: float) -> bool:
    """A circular or corner-filleted hinge needs H - t <= L; the others exist for any H > t."""
    if contour in ("circular", "corner-filleted"):
        return (h_over_t - 1.0) * t_over_l <= 1.0 + 1e-12
    return True


def beam_theory(scene) -> tuple[float, float, float]:
    """(C_theta 1/(N mm), C_yy mm/N, S mm/N) of the scene's hinge at its end."""
    from flexval.geometry.compliance import curve_compliance

    flexure = scene.mechanism.flexures[0]
    found = curve_compliance(flexure.shape, flexure.section, scene.mechanism.material)
    c = found.matrix(np.array([LENGTH, 0.0]), axial=True, shear=False)
    return float(c[2, 2]), float(c[1, 1]), float(found.shear[1, 1])


def scaled(scene, case: str, value: float):
    """The scene with load case ``case`` only, of ``value`` (N or N mm)."""
    import copy

    from flexval.geometry.scene import parse_scene

    data = copy.deepcopy(scene.data)
    data["load_cases"] = [dict(c, value=value) for c in data["load_cases"] if c["name"] == case]
    return parse_scene(data, scene.source)


def measure(contour: str, t_over_l: float, h_over_t: float, exponent=None, model=None) -> dict:
    """The factors of one hinge: ``r_b``, ``r_s`` (at nu = 0.33) and the continuum's
    end rotation and deflection per unit load."""
    import flexval

    model = model or f"continuum:{LEVEL}"
    scene = notch_scene(contour, t_over_l, h_over_t, exponent)
    c_theta, c_yy, shear = beam_theory(scene)
    moment = ROTATION / c_theta
    force = ROTATION / (c_theta * 0.5 * LENGTH)
    m = flexval.run_model(scaled(scene, "moment", moment), model, "moment", levels=2)
    f = flexval.run_model(scaled(scene, "force", force), model, "force", levels=2)
    theta = m.rotation[-1] / moment
    deflection = f.dy[-1] / force
    r_b = theta / c_theta
    t = scene.mechanism.flexures[0].section.profile.t
    waist = 6.0 * moment / (DEPTH * t * t)  # the beam formula at the waist, MPa
    return {
        "contour": contour,
        "t_over_l": t_over_l,
        "h_over_t": h_over_t,
        "exponent": exponent,
        "bending": r_b,
        "shear": (deflection - r_b * c_yy) / shear,
        "theta_per_moment": theta,
        "dy_per_force": deflection,
        "force_turn": (f.rotation[-1] / force) / (c_theta * 0.5 * LENGTH) / r_b,
        "stress": m.fibre_stress["hinge"]["stress"] / waist,
        **surface_profiles(scene, moment, force),
    }


def surface_profiles(scene, moment: float, force: float) -> dict[str, list[float]]:
    """K(s) and the shear shift delta(s) of the hinge of ``scene`` at the table's stations
    (:func:`flexval.reducedmodels.notchcorrection.station_fractions`, first half).

    ``profile``: under the end ``moment`` (N mm), the continuum's surface fibre stress over
    the beam formula 6 M / (b h(s)^2), the two halves of the symmetric hinge averaged.
    ``shift``: under the end ``force`` (N) across the axis, the surface above station s
    carries K(s) times the beam formula of the moment at s - delta(s), not at s (its
    surface normal meets the axis nearer the thick end): delta / L = (K_F / K - 1)(1 - s/L),
    K_F the force's ratio of surface stress over 6 F (L - s) / (b h(s)^2); on the second
    half delta is the mirror's, of opposite sign. Inside an end face's boundary layer
    (:func:`flexval.validation.continuum.fibre.boundary_layers`), where the rigid face
    perturbs the field, both take the value at the layer's edge."""
    from flexval.validation.continuum.fibre import boundary_layers

    flexure = scene.mechanism.flexures[0]
    first, end = boundary_layers(flexure)
    x = station_fractions(flexure.section.profile)
    lo, hi = first / LENGTH, 1.0 - end / LENGTH
    fractions, sigma = surface_stress(scaled(scene, "moment", moment), "moment")
    h = np.asarray(flexure.section.thickness_at(fractions * LENGTH), float)
    concentration = sigma / (6.0 * moment / (DEPTH * h * h))
    halves = [np.interp(np.clip(f, lo, hi), fractions, concentration) for f in (x, 1.0 - x)]
    k_moment = 0.5 * (halves[0] + halves[1])
    _, sigma = surface_stress(scaled(scene, "force", force), "force")
    beam = 6.0 * force * (1.0 - fractions) * LENGTH / (DEPTH * h * h)
    k_force = np.interp(np.clip(x, lo, 0.5), fractions, sigma / np.maximum(beam, 1e-300))
    shift = (k_force / k_moment - 1.0) * (1.0 - np.clip(x, lo, 0.5))
    return {
        "profile": [round(float(v), 5) for v in k_moment],
        "shift": [round(float(v), 6) for v in shift],
    }


def surface_stress(scene, case: str) -> tuple[np.ndarray, np.ndarray]:
    """The continuum's largest surface |fibre stress| (MPa) over each mesh section of the
    hinge of ``scene`` under its load case ``case``, and the sections' fractions."""
    from flexval.reducedmodels import LoadControl, trace
    from flexval.validation.continuum.fibre import surface_profile
    from flexval.validation.continuum.run import build_system

    system = build_system(scene.mechanism, LEVEL, "svk", "stress")
    load_case = scene.load_case(case)
    *_, last = trace(system, system.loads(load_case), LoadControl(load_case.factors(2)))
    return surface_profile(system.connectors[0], *system.local_states(last.state)[0])


def grid() -> list[tuple]:
    """Every (contour, t/L, H/t, exponent) of the table."""
    points = []
    for contour in CONTOURS:
        for n in EXPONENTS if contour == "power" else (None,):
            for tl in T_OVER_L:
                ratios = [h for h in H_OVER_T if exists(contour, tl, h)]
                if contour in ("circular", "corner-filleted"):
                    deepest = 1.0 + 1.0 / tl
                    if deepest <= H_OVER_T[-1] and deepest not in ratios:
                        ratios.append(deepest)
                points += [(contour, tl, h, n) for h in sorted(ratios)]
    return points


def held_out(count: int, seed: int = 7) -> list[tuple]:
    """Random hinges inside the table's range (log-uniform), not on its grid."""
    rng = np.random.default_rng(seed)
    points = []
    while len(points) < count:
        contour = CONTOURS[int(rng.integers(len(CONTOURS)))]
        tl = float(np.exp(rng.uniform(math.log(0.02), math.log(0.25))))
        ht = float(np.exp(rng.uniform(math.log(2.0), math.log(20.0))))
        n = float(np.round(rng.uniform(1.2, 5.0), 2)) if contour == "power" else None
        if exists(contour, tl, ht):
            points.append((contour, round(tl, 4), round(ht, 3), n))
    return points


KEY = ("contour", "t_over_l", "h_over_t", "exponent")
FACTORS = ("bending", "shear", "stress", "profile", "shift")
"""What the table holds per hinge: its shape, r_b, r_s, the stress concentration K at the
waist, K(s) along the hinge and the shear shift delta(s) / L (:func:`surface_profiles`)."""


def write_table(rows: list[dict], path: Path) -> None:
    table = {
        "description": (
            "Notch hinges: compliance factors of the continuum over beam theory "
            "(benchmarks/calibrate_notch.py)"
        ),
        "reference": f"continuum:{LEVEL}",
        "poisson_ratio": POISSON,
        "rotation": ROTATION,
        "grid": {
            "t_over_l": T_OVER_L,
            "h_over_t": H_OVER_T,
            "exponents": EXPONENTS,
            "stations": STATIONS.tolist(),
        },
        "rows": [],
    }
    head = json.dumps(table, indent=1)[: -len("[]\n}")]
    lines = [json.dumps({k: row[k] for k in (*KEY, *FACTORS)}) for row in rows]
    path.write_text(head + "[\n  " + ",\n  ".join(lines) + "\n ]\n}\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=TABLE)
    parser.add_argument("--held-out", type=int, metavar="N", help="interpolation error at N")
    parser.add_argument(
        "--resume",
        action="store_true",
        help="keep the rows of the existing table that are on the grid; measure the rest",
    )
    args = parser.parse_args(argv)
    if args.held_out:
        return report_held_out(args.held_out)
    kept = {}
    if args.resume and args.output.is_file():
        for row in json.loads(args.output.read_text())["rows"]:
            if all(k in row for k in FACTORS):  # rows of an older table are measured again
                kept[tuple(row[k] for k in KEY)] = row
    rows, start = [], time.time()
    points = grid()
    for k, (contour, tl, ht, n) in enumerate(points):
        if (contour, tl, ht, n) in kept:
            rows.append(kept[(contour, tl, ht, n)])
            continue
        rows.append(measure(contour, tl, ht, n))
        r = rows[-1]
        print(
            f"{k + 1:4d}/{len(points)} {contour:16s} t/L {tl:<6g} H/t {ht:<8.4g} n {n!s:4s} "
            f"r_b {r['bending']:.5f} r_s {r['shear']:.5f} K {r['stress']:.4f} "
            f"{time.time() - start:6.0f} s",
            flush=True,
        )
    write_table(rows, args.output)
    print(f"wrote {args.output}")
    return 0


def report_held_out(count: int) -> int:
    """The table's interpolation against fresh continuum runs at ``count`` held-out hinges."""
    from flexval.reducedmodels.notchcorrection import factors_of

    worst_b = worst_s = 0.0
    print("| contour | t/L | H/t | n | r_b | table | error | r_s | table | error |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for contour, tl, ht, n in held_out(count):
        found = measure(contour, tl, ht, n)
        scene = notch_scene(contour, tl, ht, n)
        table = factors_of(scene.mechanism.flexures[0], POISSON)
        eb = table.bending / found["bending"] - 1.0
        es = table.shear / found["shear"] - 1.0
        worst_b, worst_s = max(worst_b, abs(eb)), max(worst_s, abs(es))
        print(
            f"| {contour} | {tl:g} | {ht:g} | {n or ''} | {found['bending']:.5f} | "
            f"{table.bending:.5f} | {eb:+.3%} | {found['shear']:.4f} | {table.shear:.4f} | "
            f"{es:+.2%} |"
        )
    print(f"\nlargest error: bending {worst_b:.3%}, shear {worst_s:.2%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
