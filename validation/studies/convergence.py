"""Resolution convergence studies: observed order, Richardson extrapolation, GCI.

For a model family refined by a constant ratio r (continuum mesh levels halve
the element size: r = 2; ``beam:N`` and ``dcmm:N`` with N doubling: r = 2; the
family's :class:`flexval.reducedmodels.catalogue.Resolution` gives the ratio),
the end-of-ramp target displacement magnitude (mm) and rotation (rad) of
the three finest resolutions f1 (coarse), f2, f3 (fine) give

* the observed order p = ln(|f2 - f1| / |f3 - f2|) / ln r,
* the Richardson-extrapolated value f_ext = f3 + (f3 - f2) / (r^p - 1),
* Roache's grid-convergence index GCI = 1.25 |(f3 - f2) / f3| / (r^p - 1)
  (percent), an error band on the finest value.

The same analysis is made of the largest peak outer-fibre stress over the
flexures at full load (MPa, ``peak_stress``) for models that report it, and
of the continuum's own largest fibre stress outside the end faces' boundary
layers (MPa, ``fibre_stress``: :attr:`flexval.reducedmodels.LoadPath.fibre_stress`,
recovered from the solid's stresses by :mod:`flexval.validation.continuum.fibre`).

A quantity whose changes between resolutions are below ``ROUND_OFF_CHANGE``
of its value is converged to the solver's tolerance: an order computed from
those changes would be round-off (the uniform peak stress under pure end
moments gave "orders" of 0.12 and 1.02 from two codes that differ in their
last bits), so none is given and the text says why.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from flexval.geometry import LoadCase, Scene
from flexval.reducedmodels import LoadPath, SolverError
from flexval.reducedmodels.catalogue import ModelSpec

from ..failures import Failure, failure_of
from ..report.tables import Column, sig, text_table
from ..run import run_model

ROUND_OFF_CHANGE = 1e-6
"""Relative change between resolutions below which a quantity is converged to round-off.

Measured in the paper report: the exact, uniform peak stress under pure end
moments (open chain m+) changes by 1.6e-8 and 8e-9 of its value from continuum
level 0 to 1 to 2 (the converged states' own tolerance;
``strength.UNIFORM_SPREAD`` draws the same line along a flexure), while the
smallest discretisation change in the report's studies is 4.8e-5 (the same
study's displacement, levels 1 to 2): the threshold sits some 50 times above
the one and below the other."""


STRESSES = ("peak_stress", "fibre_stress")
"""The stresses (MPa) a study's rows hold, None for a model that does not report one."""


@dataclass
class ConvergenceStudy:
    """Results of one refinement study of one model family on one load case.

    ``ratio`` is the constant refinement ratio, NaN when the resolutions are
    not refined by one constant ratio (a comma list such as ``5,7,20``) or
    fewer than two are given; then no order or Richardson value is computed,
    and JSON outputs write it as ``null`` (strict JSON has no NaN).
    """

    family: str
    load_case: str
    ratio: float
    rows: list[dict] = field(default_factory=list)
    summary: dict = field(default_factory=dict)
    failures: list[Failure] = field(default_factory=list)


def richardson(f1: float, f2: float, f3: float, ratio: float) -> dict:
    """Observed order, extrapolated value and GCI (percent) from three resolutions.

    Returns NaN-free results: when the quantity is converged to round-off
    (both changes below ``ROUND_OFF_CHANGE`` of the finest value) or the
    differences do not shrink monotonically (oscillating), ``order`` is None,
    the extrapolated value is the finest one and ``note`` says which
    (None when an order is given).
    """
    e21, e32 = f2 - f1, f3 - f2
    if max(abs(e21), abs(e32)) <= ROUND_OFF_CHANGE * abs(f3):
        return {
            "order": None,
            "extrapolated": f3,
            "gci_percent": None,
            "note": f"converged to round-off (changes within {ROUND_OFF_CHANGE:g} of the value)",
        }
    if e32 == 0.0 or e21 == 0.0 or e21 * e32 < 0 or abs(e32) >= abs(e21):
        return {
            "order": None,
            "extrapolated": f3,
            "gci_percent": None,
            "note": "the changes do not shrink monotonically",
        }
    p = math.log(abs(e21) / abs(e32)) / math.log(ratio)
    ext = f3 + e32 / (ratio**p - 1.0)
    gci = 100.0 * 1.25 * abs(e32 / f3) / (ratio**p - 1.0) if f3 != 0 else None
    return {"order": p, "extrapolated": ext, "gci_percent": gci, "note": None}


def order_text(summary: dict) -> str:
    """The observed order of a :func:`richardson` result as printed, or why there is none."""
    if summary["order"] is None:
        return f"n/a ({summary['note']})" if summary.get("note") else "n/a"
    return f"{summary['order']:.2f}"


def study(
    scene: Scene,
    model: ModelSpec,
    resolutions: list[int],
    case: LoadCase,
    levels: int | None = None,
    progress=None,
    run: Callable[[ModelSpec], LoadPath] | None = None,
) -> ConvergenceStudy:
    """Run ``model`` (its options kept) at each resolution (increasing) on ``case`` and
    analyse convergence.

    A resolution that fails is recorded in ``failures`` (no row) and the study
    carries on; the Richardson summary needs the three finest resolutions to
    have converged. ``run(spec)`` runs one resolution (default: :func:`run_model`
    with ``levels``; the report passes its cached runner, so a path it has
    already computed is not computed again).
    """
    refine = model.model_family.resolution
    ratios = {refine.ratio(a, b) for a, b in zip(resolutions, resolutions[1:])}
    ratio = ratios.pop() if len(ratios) == 1 else float("nan")
    st = ConvergenceStudy(model.family, case.name, ratio)
    for res in resolutions:
        spec = model.with_resolution(res)
        try:
            lp = run(spec) if run else run_model(scene, spec, case, levels)
        except SolverError as exc:
            st.failures.append(failure_of(exc, scene, spec, case))
            if progress:
                progress(spec.id)
            continue
        st.rows.append(
            {
                "model": spec.id,
                "resolution": res,
                "unknowns": lp.stats.get("unknowns"),
                "seconds": lp.seconds,
                "dx": lp.dx[-1],
                "dy": lp.dy[-1],
                "displacement": float(lp.displacement[-1]),
                "rotation": lp.rotation[-1],
                "peak_stress": (
                    max(v[-1] for v in lp.peak_stress.values()) if lp.peak_stress else None
                ),
                "fibre_stress": (
                    max(v["stress"] for v in lp.fibre_stress.values()) if lp.fibre_stress else None
                ),
            }
        )
        if progress:
            progress(spec.id)
    finest = [r["resolution"] for r in st.rows[-3:]]
    if len(st.rows) >= 3 and finest == resolutions[-3:] and math.isfinite(ratio):
        f = st.rows[-3:]
        keys = ["displacement", "rotation"]
        keys += [k for k in STRESSES if all(r.get(k) is not None for r in f)]
        st.summary = {key: richardson(f[0][key], f[1][key], f[2][key], ratio) for key in keys}
    return st


def format_study(st: ConvergenceStudy) -> str:
    """Plain-text table of a study (mm, deg, s)."""
    lines = [f"{st.family} convergence on load case {st.load_case} (refinement ratio {st.ratio:g})"]
    columns = [
        Column("model", "<"),
        Column("unknowns"),
        Column("seconds"),
        Column("|d| mm"),
        Column("rot deg"),
        Column("peak MPa"),
    ]
    fibre = any(r.get("fibre_stress") is not None for r in st.rows)
    if fibre:
        columns.append(Column("fibre MPa"))
    rows = [
        [
            r["model"],
            str(r["unknowns"]),
            sig(r["seconds"], 3),
            f"{r['displacement']:.6f}",
            f"{math.degrees(r['rotation']):.6f}",
            sig(r["peak_stress"], 6),
        ]
        + ([sig(r.get("fibre_stress"), 6)] if fibre else [])
        for r in st.rows
    ]
    lines += text_table(columns, rows)
    for key, unit, conv in (
        ("displacement", "mm", 1.0),
        ("rotation", "deg", math.degrees(1.0)),
        ("peak_stress", "MPa", 1.0),
        ("fibre_stress", "MPa", 1.0),
    ):
        s = st.summary.get(key)
        if not s:
            continue
        gci = "n/a" if s["gci_percent"] is None else f"{s['gci_percent']:.3g} %"
        lines.append(
            f"{key}: observed order {order_text(s)}, extrapolated "
            f"{s['extrapolated'] * conv:.6f} {unit}, GCI {gci}"
        )
    lines += [f"{f.model}: {f.summary()}" for f in st.failures]
    return "\n".join(lines)
