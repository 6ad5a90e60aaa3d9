"""Report figures (Matplotlib, Agg): load paths, deformed shapes, link rotations,
runtime versus error, mesh convergence, and the field model's stress picture at full load
(solved again where it is drawn). Axes carry units: mm, deg, N or N mm, s, MPa."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from flexval.geometry import Scene  # noqa: E402
from flexval.geometry.kinematics import place_points  # noqa: E402
from flexval.reducedmodels import LoadPath  # noqa: E402

from .drawing import draw_mechanism  # noqa: E402
from .outputs import write_figure  # noqa: E402

#: fixed style per model family so models stay distinguishable across figures
_STYLE = {
    "continuum": dict(color="black", lw=2.4, ls="-", marker=None),
    "beam:100": dict(color="tab:blue", lw=1.8, ls="-", marker="o", ms=4),
    "beam:20": dict(color="tab:cyan", lw=1.4, ls="--", marker="s", ms=4),
    "prbm": dict(color="tab:green", lw=1.4, ls="-.", marker="^", ms=5),
    "dcmm:1": dict(color="tab:red", lw=1.4, ls=":", marker="v", ms=5),
    "dcmm:2": dict(color="tab:orange", lw=1.4, ls=":", marker="D", ms=4),
    "dcmm:3": dict(color="tab:purple", lw=1.4, ls=":", marker="P", ms=5),
    "ee": dict(color="0.5", lw=1.2, ls="--", marker=None),
}


def style(model: str) -> dict:
    """Line style of a model id or family name: its own, else the first of its family's
    (continuum levels share the continuum style), else a neutral one."""
    family = model.split(":")[0].split("[")[0]
    return _STYLE.get(model) or next(
        (s for k, s in _STYLE.items() if k.split(":")[0] == family), dict(color="tab:brown", lw=1.2)
    )


def _save(fig, path: Path) -> str:
    return write_figure(fig, path).name


def _finish_loglog(fig, ax, xlabel: str, ylabel: str, title: str, path: Path) -> str:
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, which="both")
    if ax.get_legend_handles_labels()[0]:  # nothing to plot (e.g. every run failed): no legend
        ax.legend(fontsize=8)
    ax.set_title(title)
    return _save(fig, path)


def load_path_curves(
    paths: dict[str, LoadPath], traces: dict[str, LoadPath] | None = None
) -> list[dict]:
    """The curves of the load-path figure: each model's path, then its arc-length trace.

    Each curve is ``{"label", "model", "load" (|load|, N or N mm), "displacement" (|d|, mm),
    "rotation" (deg), "style"}``. A trace (the branch an arc-length search traced through
    the model's limit point, see :attr:`flexval.validation.failures.Failure.trace`) is drawn dashed
    in its model's colour and labelled ``"<model> (arc length)"``.
    """
    curves = []
    for model, lp in paths.items():
        curves.append(
            dict(
                label=model,
                model=model,
                load=np.abs(lp.load),
                displacement=np.asarray(lp.displacement),
                rotation=np.degrees(lp.rotation),
                style=style(model),
            )
        )
    for model, lp in (traces or {}).items():
        st = dict(color=style(model).get("color"), lw=1.2, ls="--", marker=None)
        curves.append(
            dict(
                label=f"{model} (arc length)",
                model=model,
                load=np.abs(lp.load),
                displacement=np.asarray(lp.displacement),
                rotation=np.degrees(lp.rotation),
                style=st,
            )
        )
    return curves


def load_paths(
    scene: Scene,
    case_name: str,
    paths: dict[str, LoadPath],
    path: Path,
    traces: dict[str, LoadPath] | None = None,
) -> str:
    """Target displacement magnitude and target-body rotation versus load, all models
    (and the arc-length traces through limit points, see :func:`load_path_curves`)."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    unit = next((lp.load_unit for lp in paths.values()), None)
    for c in load_path_curves(paths, traces):
        a1.plot(c["load"], c["displacement"], label=c["label"], **c["style"])
        a2.plot(c["load"], c["rotation"], label=c["label"], **c["style"])
    a1.set_xlabel(f"|load| ({unit})")
    a1.set_ylabel("target point displacement |d| (mm)")
    a2.set_xlabel(f"|load| ({unit})")
    a2.set_ylabel(f"rotation of body {scene.mechanism.target_body} (deg)")
    for a in (a1, a2):
        a.grid(alpha=0.3)
    a1.legend(fontsize=8)
    fig.suptitle(f"{scene.name}, load case {case_name}")
    return _save(fig, path)


def deformed(scene: Scene, case_name: str, lp: LoadPath, path: Path) -> str:
    """Deformed configurations at every other level and the tracing-point path."""
    fig, ax = plt.subplots(figsize=(7, 7))
    draw_mechanism(scene, ax, load_case=case_name)
    mech = scene.mechanism
    n = len(lp.load)
    cmap = plt.get_cmap("viridis")
    for k in range(0, n, max(1, n // 5)) if n > 1 else [0]:
        col = cmap(k / max(n - 1, 1))
        for pts in lp.shapes.values():
            p = np.asarray(pts[k])
            ax.plot(p[:, 0], p[:, 1], color=col, lw=1.2, alpha=0.9)
        for body, poses in lp.poses.items():
            b = mech.bodies[body]
            if b.is_ground:
                continue
            pts = b.points if body != mech.target_body else np.vstack([b.points, mech.target_point])
            q = place_points(np.asarray(poses[k]), pts - b.reference)
            ax.plot(q[:, 0], q[:, 1], color=col, lw=3, alpha=0.6)
    trace = mech.target_point + np.column_stack([lp.dx, lp.dy])
    ax.plot(trace[:, 0], trace[:, 1], "k.-", lw=1, ms=4, label="tracing point path")
    ax.legend(fontsize=8, loc="best")
    ax.set_title(f"{scene.name} {case_name}: deformed ({lp.model}), levels coloured 0 -> full")
    return _save(fig, path)


def relative_rotations(scene: Scene, case_name: str, lp: LoadPath, path: Path) -> str:
    """Relative rotation of the two bodies joined by each flexure versus load (paper Fig. 15)."""
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for f in scene.mechanism.flexures:
        ta = np.array(lp.poses[f.bodies[0]])[:, 2]
        tb = np.array(lp.poses[f.bodies[1]])[:, 2]
        ax.plot(
            np.abs(lp.load),
            np.degrees(tb - ta),
            marker="o",
            ms=3,
            label=f"{f.name}: body {f.bodies[1]} - body {f.bodies[0]}",
        )
    ax.set_xlabel(f"|load| ({lp.load_unit})")
    ax.set_ylabel("relative rotation (deg)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{scene.name} {case_name}: relative rotations of the links ({lp.model})")
    return _save(fig, path)


def field_picture(scene: Scene, model: str, case_name: str, path: Path) -> str:
    """The picture of ``model`` (a family with stress fields, e.g. ``continuum:1``) at full
    load on ``case_name``: the deformed mechanism, its flexures coloured by the fibre stress
    (MPa), a zoom on the most stressed section (the family's own PNG output, e.g.
    :func:`flexval.validation.continuum.output.render_png`).

    A load path keeps no state, so the model is solved again on the case's load levels: the
    same deterministic path as the report's, ending in the state drawn.

    Raises
    ------
    reducedmodels.SolverError
        If the model does not reach full load (the report draws only cases it reached).
    """
    from flexval.reducedmodels.catalogue import parse_model

    from .run import run_model

    run_model(scene, parse_model(model), scene.load_case(case_name), png=path)
    return path.name


def pareto_front(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the (seconds, error) points not dominated by a cheaper, more accurate one."""
    order = sorted(range(len(points)), key=lambda k: (points[k][0], points[k][1]))
    front, best = [], math.inf
    for k in order:
        if points[k][1] < best:
            front.append(k)
            best = points[k][1]
    return front


def runtime_vs_error(rows: list[dict], title: str, path: Path) -> str:
    """Log-log scatter of seconds versus error (percent) with the Pareto front marked."""
    fig, ax = plt.subplots(figsize=(7.5, 5))
    families: dict[str, list[dict]] = {}
    for r in rows:
        families.setdefault(r["model"].split(":")[0].split("[")[0], []).append(r)
    floor = 1e-4
    for fam, rs in families.items():
        st = style(fam)
        x = [r["seconds"] for r in rs]
        y = [max(r["error"], floor) for r in rs]
        ax.plot(x, y, marker=st.get("marker") or "o", color=st["color"], ls="-", lw=0.8, label=fam)
        for r, xi, yi in zip(rs, x, y):
            ax.annotate(
                r["model"].split(":")[-1] if ":" in r["model"] else r["model"],
                (xi, yi),
                fontsize=7,
                xytext=(3, 3),
                textcoords="offset points",
            )
    pts = [(r["seconds"], max(r["error"], floor)) for r in rows]
    front = pareto_front(pts)
    if front:
        fx, fy = zip(*[pts[k] for k in front])
        ax.step(fx, fy, where="post", color="red", lw=2, alpha=0.4, label="Pareto front")
    else:  # no path reached full load beside the reference's: nothing to compare
        ax.text(
            0.5,
            0.5,
            "no error to plot: no model reached the full load\nbeside the reference",
            transform=ax.transAxes,
            ha="center",
            va="center",
            fontsize=9,
        )
        ax.set_xlim(1e-4, 1.0)
        ax.set_ylim(floor, 100.0)
    return _finish_loglog(fig, ax, "wall time per load path (s, median)", "error (%)", title, path)


def convergence(rows: list[dict], extrapolated: dict, title: str, path: Path) -> str:
    """Relative difference from the Richardson value versus unknowns (log-log)."""
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    n = [r["unknowns"] for r in rows]
    for key, label in (
        ("displacement", "|d|"),
        ("rotation", "rotation"),
        ("fibre_stress", "fibre stress"),
    ):
        ext = extrapolated.get(key)
        if ext is None or ext == 0 or any(r.get(key) is None for r in rows):
            continue
        err = [max(abs(r[key] - ext) / abs(ext) * 100, 1e-6) for r in rows]
        ax.plot(n, err, marker="o", label=label)
    return _finish_loglog(
        fig, ax, "unknowns", "difference from extrapolated value (%)", title, path
    )
