"""Peak stresses and limit loads in the validation report: the data, then its Markdown and figures.

* Peak stress: every model's peak outer-fibre stress at full load
  (:attr:`reducedmodels.LoadPath.peak_stress`, MPa) with the flexure and the
  place where it occurs, and its error against the reference model; a figure
  of the stress along each flexure at full load (the paper's Fig. 13 idea).
  Beam formulas turn section forces into fibre stress as if the flexure were
  straight; on a thick curved flexure the inner fibre carries more
  (Winkler-Bach curved-beam theory, :func:`curved_beam_factor`).
* Limit loads: a model that stops at a limit point under load control is
  traced by arc length when its failure is recorded
  (:func:`flexval.validation.failures.failure_of`); the limit loads are tabulated
  with their error against the reference's own limit load where it has one, and
  beside them every model's first bifurcation point (load and fraction of the full
  load) where its path has one.

Units: MPa, N or N mm, mm.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path

from ..outputs import use_file_backend

use_file_backend()
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from flexval.geometry import Scene  # noqa: E402
from flexval.reducedmodels import LoadPath  # noqa: E402

from ..failures import LIMIT_POINT, Failure  # noqa: E402
from ..outputs import output_path, write_figure  # noqa: E402
from ..studies.convergence import ConvergenceStudy, order_text  # noqa: E402
from .figurejobs import draw_now  # noqa: E402
from .figures import style  # noqa: E402
from .yieldtable import yield_section  # noqa: E402


def curved_beam_factor(radius: float, thickness: float) -> float:
    """Inner-fibre bending stress of a curved rectangular bar over the straight-beam value.

    Winkler-Bach theory: with r_i, r_o = r -+ h/2 the neutral radius is
    r_n = h / ln(r_o / r_i), its offset e = r - r_n, and a moment M gives the
    inner-fibre stress M (r_n - r_i) / (A e r_i) instead of 6 M / (b h^2);
    the ratio is h (r_n - r_i) / (6 e r_i) (dimensionless, > 1; -> 1 + h/(3r)
    for r >> h). ``radius`` is the centre-line radius (mm, inf for a straight flexure).
    """
    if math.isinf(radius):
        return 1.0
    r_i, r_o = radius - thickness / 2.0, radius + thickness / 2.0
    r_n = thickness / math.log(r_o / r_i)
    e = radius - r_n
    return thickness * (r_n - r_i) / (6.0 * e * r_i)


# --- data ----------------------------------------------------------------------------------
UNIFORM_SPREAD = 1e-6
"""Relative spread (peak - least) / peak of the outer-fibre stress over every flexure's
profile below which the stress counts as uniform and the peak has no place.

Measured on the open chain at full load: under the pure end moments m+/m- the
spread is <= 2.2e-8 for every model (continuum:1 the largest, from its Newton
tolerance; beam:20 3e-11, dcmm/prbm/ee <= 3e-12); under f+ it is >= 0.94. In a
uniform field the peak's place is decided by round-off, so naming it would make
the report change with the order of floating-point operations."""


def peak_at_full_load(lp: LoadPath) -> dict | None:
    """``{"stress", "flexure", "at", "uniform"}``: the largest peak stress over the flexures at
    the last level (MPa), which flexure and where (fraction from its first end), and whether
    the stress is uniform over every flexure (:data:`UNIFORM_SPREAD`; the place then means
    nothing); None without a peak stress."""
    if not lp.peak_stress:
        return None
    name = max(lp.peak_stress, key=lambda f: lp.peak_stress[f][-1])
    peak = lp.peak_stress[name][-1]
    uniform = False
    if lp.stress_profile and peak > 0.0:
        least = min(min(p["stress"]) for p in lp.stress_profile.values())
        uniform = (peak - least) / peak < UNIFORM_SPREAD
    return {"stress": peak, "flexure": name, "at": lp.peak_stress_at[name][-1], "uniform": uniform}


def peak_stress_data(
    paths: dict[tuple[str, str], LoadPath], models: list[str], cases: list[str], reference: str
) -> dict[str, dict[str, dict]]:
    """{model: {case: peak_at_full_load + "error_percent"}} of the paths that reached full load.

    The error is (model - reference) / reference in percent (None without a reference).
    """
    out: dict[str, dict[str, dict]] = {}
    for m in models:
        for c in cases:
            lp = paths.get((m, c))
            peak = peak_at_full_load(lp) if lp is not None and lp.converged else None
            if peak is None:
                continue
            ref = paths.get((reference, c))
            ref_peak = peak_at_full_load(ref) if ref is not None and ref.converged else None
            peak["error_percent"] = (
                100.0 * (peak["stress"] - ref_peak["stress"]) / ref_peak["stress"]
                if ref_peak
                else None
            )
            out.setdefault(m, {})[c] = peak
    return out


def limit_load_data(failures: list[Failure], reference: str) -> dict[str, dict[str, dict]]:
    """{model: {case: {"load", "unit", "error_percent"}}} of the failures at a limit point.

    The error is against the reference's limit load on the same case (None
    when the reference has none in range).
    """
    limits = {(f.model, f.load_case): f for f in failures if f.reason == LIMIT_POINT}
    out: dict[str, dict[str, dict]] = {}
    for (m, c), f in limits.items():
        ref = limits.get((reference, c))
        err = 100.0 * (f.load - ref.load) / ref.load if ref else None
        out.setdefault(m, {})[c] = {"load": f.load, "unit": f.unit, "error_percent": err}
    return out


def bifurcation_data(
    paths: dict[tuple[str, str], LoadPath], models: list[str], cases: list[str], reference: str
) -> dict[str, dict[str, dict]]:
    """{model: {case: {"load", "fraction", "unit", "error_percent"}}} of the first bifurcation.

    Taken from each model's load-control path on the case
    (:attr:`reducedmodels.LoadPath.bifurcations`: passed, or where the path
    stopped); load in N or N mm, fraction of the full load; the error is
    against the reference's first bifurcation on the same case (None when it
    has none).
    """
    first = {
        (m, c): (paths[(m, c)].bifurcations[0], paths[(m, c)].load_unit)
        for m in models
        for c in cases
        if (m, c) in paths and paths[(m, c)].bifurcations
    }
    out: dict[str, dict[str, dict]] = {}
    for (m, c), (b, unit) in first.items():
        ref = first.get((reference, c))
        err = 100.0 * (b["load"] - ref[0]["load"]) / ref[0]["load"] if ref else None
        out.setdefault(m, {})[c] = {
            "load": b["load"],
            "fraction": b["fraction"],
            "unit": unit,
            "error_percent": err,
        }
    for m in models:  # full load reached past the reference's bifurcation: buckling missed
        for c in cases:
            ref, lp = first.get((reference, c)), paths.get((m, c))
            if ref and (m, c) not in first and lp is not None and lp.converged:
                out.setdefault(m, {})[c] = {
                    "load": None,
                    "fraction": None,
                    "unit": ref[1],
                    "error_percent": None,
                    "missed": ref[0]["load"],
                }
    return out


# --- render --------------------------------------------------------------------------------
def _cell(v: dict | None, value: str) -> str:
    if v is None:
        return "—"
    err = v.get("error_percent")
    return value if err is None else f"{value} ({err:+.2f} %)"


def _peak_text(peak: dict) -> str:
    """ "8.583 MPa at e34@0.47", or "3 MPa, uniform" when the stress has no single place."""
    if peak.get("uniform"):
        return f"{peak['stress']:.4g} MPa, uniform"
    return f"{peak['stress']:.4g} MPa at {peak['flexure']}@{peak['at']:.2f}"


def peak_stress_table(data: dict[str, dict[str, dict]], cases: list[str]) -> list[str]:
    """Markdown: model x load case, peak stress (MPa), where, error against the reference."""
    lines = ["| model | " + " | ".join(cases) + " |", "|---|" + "---:|" * len(cases)]
    for m, row in data.items():
        cells = [_cell(row[c], _peak_text(row[c])) if c in row else "—" for c in cases]
        lines.append(f"| `{m}` | " + " | ".join(cells) + " |")
    return lines


def limit_load_table(
    data: dict[str, dict[str, dict]],
    cases: list[str],
    bifurcations: dict[str, dict[str, dict]] | None = None,
) -> list[str]:
    """Markdown: model x load case, first limit load and its error against the reference;
    then, per model with one, a row of its first bifurcation points (load, percent of the
    full load, error against the reference's)."""
    lines = ["| model | " + " | ".join(cases) + " |", "|---|" + "---:|" * len(cases)]
    for m, row in data.items():
        cells = [
            _cell(row[c], f"{row[c]['load']:.5g} {row[c]['unit']}") if c in row else "—"
            for c in cases
        ]
        lines.append(f"| `{m}` | " + " | ".join(cells) + " |")
    for m, row in (bifurcations or {}).items():
        cells = [
            "—"
            if c not in row
            else f"none to full load (missed: the reference's at {row[c]['missed']:.5g} "
            f"{row[c]['unit']})"
            if row[c]["load"] is None
            else _cell(
                row[c], f"{row[c]['load']:.5g} {row[c]['unit']} at {100 * row[c]['fraction']:.2f} %"
            )
            for c in cases
        ]
        lines.append(f"| `{m}` bifurcation | " + " | ".join(cells) + " |")
    return lines


def fibre_table(
    scene: Scene,
    paths: dict[tuple[str, str], LoadPath],
    reference: str,
    cases: list[str],
    convergence: Sequence[ConvergenceStudy] = (),
) -> list[str]:
    """Markdown comparing the reference continuum's own fibre stress with its beam-formula value.

    Per load case, the flexure with the largest fibre stress at full load
    (:attr:`reducedmodels.LoadPath.fibre_stress`, outside the end faces'
    boundary layers) against the largest outer-fibre stress of its section
    resultants over the same stretch of that flexure (outside the same
    layers, their edges included), the stress concentration of every notch hinge
    (:func:`flexval.validation.continuum.fibre.notch_concentration`), then the
    fibre stress's mesh convergence from the studies in
    ``convergence`` that have it (observed order, Richardson value, GCI);
    empty when the reference reports no fibre stress.
    """
    length = {f.name: f.shape.length for f in scene.mechanism.flexures}
    rows, notches = [], []
    for c in cases:
        lp = paths.get((reference, c))
        if lp is None or not lp.converged or not lp.fibre_stress:
            continue
        name, fibre = max(lp.fibre_stress.items(), key=lambda kv: kv[1]["stress"])
        at = np.asarray(lp.stress_profile[name]["at"])
        first = fibre["layer"] / length[name]
        last = fibre.get("layer_end", fibre["layer"]) / length[name]
        stress = np.asarray(lp.stress_profile[name]["stress"])
        inside = (at >= first) & (at <= 1.0 - last)
        edges = np.interp([first, 1.0 - last], at, stress)  # the window's edges, like the fibre's
        beam = float(max(np.max(stress[inside], initial=0.0), edges.max()))
        rows.append(
            f"| {c} | {name} | {beam:.4g} | {fibre['stress']:.4g} | "
            f"{100 * (fibre['stress'] - beam) / beam:+.1f} % |"
        )
        notches += [
            f"{c}: {n} {v['concentration']:.4g} ({v['stress']:.4g} MPa at {v['at']:.2f})"
            for n, v in lp.fibre_stress.items()
            if "concentration" in v
        ]
    if not rows:
        return []
    from ..continuum.fibre import LAYER_THICKNESSES

    scf = (
        [
            "Stress concentration of the notch hinges (the continuum's peak fibre stress over "
            "the beam formula at the thinnest section, from its own section resultants; peak "
            "and where): " + "; ".join(notches) + ".",
            "",
        ]
        if notches
        else []
    )
    return (
        [
            f"Outside a boundary layer of {LAYER_THICKNESSES:g} thicknesses at each clamped "
            "end face (where the continuum's stress is singular; on a notch hinge it stops "
            "half-way to the thinnest part), the continuum's own fibre normal stress against "
            "the beam formula applied to its section resultants over the same stretch (the "
            "flexure with the largest fibre stress):",
            "",
            "| case | flexure | beam formula (MPa) | continuum fibre (MPa) | difference |",
            "|---|---|---:|---:|---:|",
        ]
        + rows
        + [""]
        + scf
        + _fibre_convergence_lines(convergence)
    )


def _fibre_convergence_lines(convergence: Sequence[ConvergenceStudy]) -> list[str]:
    """One sentence per study with a fibre-stress summary: its mesh convergence."""
    out = []
    for st in convergence:
        s = st.summary.get("fibre_stress")
        if not s:
            continue
        models = ", ".join(f"`{r['model']}`" for r in st.rows[-3:])
        gci = "n/a" if s["gci_percent"] is None else f"{s['gci_percent']:.3g} %"
        out += [
            f"Mesh convergence of the continuum's fibre stress on {st.load_case} ({models}): "
            f"observed order {order_text(s)}, Richardson value {s['extrapolated']:.6g} MPa, "
            f"GCI {gci}.",
            "",
        ]
    return out


def stress_profiles(scene: Scene, case_name: str, paths: dict[str, LoadPath], path: Path) -> str:
    """Outer-fibre stress (MPa) along each flexure at full load, one panel per flexure."""
    names = [f.name for f in scene.mechanism.flexures]
    cols = min(len(names), 3)
    rows = math.ceil(len(names) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    for ax, name in zip(axes.ravel(), names):
        for model, lp in paths.items():
            profile = (lp.stress_profile or {}).get(name)
            if profile and lp.converged:
                ax.plot(
                    profile["at"],
                    profile["stress"],
                    label=model,
                    **{**style(model), "marker": None},
                )
        ax.set_title(name)
        ax.set_xlabel("arc-length fraction from the first end")
        ax.set_ylabel("outer-fibre stress (MPa)")
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[len(names) :]:
        ax.axis("off")
    if axes[0, 0].get_legend_handles_labels()[0]:
        axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"{scene.name}, load case {case_name}: stress along the flexures at full load")
    return write_figure(fig, path).name


def section(
    scene: Scene,
    paths: dict[tuple[str, str], LoadPath],
    failures: list[Failure],
    models: list[str],
    reference: str,
    out: Path,
    draw: Callable = draw_now,
    convergence: Sequence[ConvergenceStudy] = (),
) -> list[str]:
    """The report's Markdown on peak stresses and limit loads of one scene (figures into
    ``out``, drawn with ``draw(fn, *args)``: see :mod:`flexval.validation.report.figurejobs`;
    the fibre stress's mesh convergence from the studies in ``convergence``)."""
    cases = [c.name for c in scene.load_cases]
    name = scene.name
    lines = [
        f"### Peak stress against `{reference}`",
        "",
        "Largest outer-fibre normal stress |N|/A + |M| h/(2I) over the flexures at full "
        "load, from each model's own section forces (the wrench a flexure transmits, carried "
        "by statics along the model's displaced centre line; for the continuum the section "
        "resultants of its stresses), where it occurs (flexure@fraction of its length from "
        'its first end; "uniform" where every section carries it, as under a pure end '
        "moment) and its error against the reference.",
        "",
    ]
    lines += peak_stress_table(peak_stress_data(paths, models, cases, reference), cases) + [""]
    curved = [
        (
            f.name,
            f.shape.radius,
            f.section.thickness,
            curved_beam_factor(f.shape.radius, f.section.thickness),
        )
        for f in scene.mechanism.flexures
        if hasattr(f.shape, "radius")
    ]
    if curved:
        lines += [
            "These are beam formulas: they treat each section as straight. Under pure "
            "bending the inner fibre of a curved section carries more (Winkler-Bach "
            "curved-beam theory): "
            + ", ".join(f"{100 * (k - 1):.1f} % ({n}, r/h = {r / h:.1f})" for n, r, h, k in curved)
            + ". Where the continuum's own fibre stress can be compared, the table below "
            "says how much it differs.",
            "",
        ]
    lines += fibre_table(scene, paths, reference, cases, convergence)
    lines += yield_section(scene, paths, models, cases, reference)
    for c in cases:
        full = {m: paths[(m, c)] for m in models if (m, c) in paths}
        png = output_path(out, f"{name}_{c}_stress", ".png")
        draw(stress_profiles, scene, c, full, png)
        lines += [f"![{name} {c} stress]({png.name})", ""]
    data = limit_load_data(failures, reference)
    bifurcations = bifurcation_data(paths, models, cases, reference)
    if data or bifurcations:
        title = "Limit loads" + (" and bifurcations" if bifurcations else "")
        lines += [
            f"### {title} against `{reference}`",
            "",
            "Models that stopped at a limit point under load control, traced by arc "
            "length: first limit load on the path and its error against the reference's "
            "(— where the reference has none in range).",
        ]
        if bifurcations:
            lines[-1] += (
                " Rows marked bifurcation: the first bifurcation point on the model's path "
                "(the tangent turns indefinite while the load still rises; another branch "
                "crosses there), its load and percent of the full load, and its error "
                "against the reference's."
            )
        lines += [""] + limit_load_table(data, cases, bifurcations) + [""]
    return lines
