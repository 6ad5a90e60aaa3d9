"""Report figures (Matplotlib, Agg): load paths, deformed shapes, link rotations,
runtime versus error, mesh convergence, and the field model's stress picture at full load
(solved again where it is drawn). Axes carry units: mm, deg, N or N mm, s, MPa."""

from __future__ import annotations

import math
from pathlib import Path

from ..outputs import use_file_backend

use_file_backend()
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from flexval.geometry import Scene  # noqa: E402
from flexval.geometry.kinematics import place_points  # noqa: E402
from flexval.reducedmodels import LoadPath  # noqa: E402

from ..outputs import write_figure  # noqa: E402
from .drawing import draw_mechanism  # noqa: E402

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
    "beam:100[eb]": dict(color="tab:blue", lw=1.0, ls="--", marker="x", ms=5),
    "prbm[eb]": dict(color="tab:green", lw=1.0, ls=":", marker="x", ms=5),
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

    Each curve is ``{"label", "model", "load" (|load|, N or N mm), "dx", "dy",
    "displacement" (|d|) (mm), "rotation" (deg), "bifurcations" (their |load|),
    "limit_points" (their levels), "style"}``. A trace (the branch an arc-length search
    traced through the model's limit point, see
    :attr:`flexval.validation.failures.Failure.trace`) is drawn dashed in its model's colour
    and labelled ``"<model> (arc length)"``.
    """
    curves = []
    for model, lp in paths.items():
        curves.append(dict(label=model, model=model, style=style(model), **_curve(lp)))
    for model, lp in (traces or {}).items():
        st = dict(color=style(model).get("color"), lw=1.2, ls="--", marker=None)
        curves.append(dict(label=f"{model} (arc length)", model=model, style=st, **_curve(lp)))
    return curves


def _curve(lp: LoadPath) -> dict:
    """A path's arrays for a figure: |load|, dx, dy, |d| (mm), rotation (deg), and its
    bifurcation loads and limit points (|load|, index of the level)."""
    limits = [p["index"] for p in lp.limit_points or []] or list(
        lp.stats.get("limit_points", []) if lp.stats else []
    )
    return dict(
        load=np.abs(lp.load),
        dx=np.asarray(lp.dx),
        dy=np.asarray(lp.dy),
        displacement=np.asarray(lp.displacement),
        rotation=np.degrees(lp.rotation),
        bifurcations=[abs(b["load"]) for b in lp.bifurcations or []],
        limit_points=[k for k in limits if 0 <= k < len(lp.load)],
    )


def draw_component(ax, curves: list[dict], key: str, unit: str | None, label: str) -> None:
    """Draw one component (``dx``, ``dy``, ``displacement``: mm; ``rotation``: deg) of the
    curves (:func:`load_path_curves`) versus |load| on ``ax``; a bifurcation is marked with
    a cross, a limit point with a diamond."""
    for c in curves:
        ax.plot(c["load"], c[key], label=c["label"], **c["style"])
        color = c["style"].get("color")
        for k in c["limit_points"]:
            ax.plot(c["load"][k], c[key][k], "D", ms=7, mfc="none", color=color)
        for load in c["bifurcations"]:
            value = np.interp(load, c["load"], c[key]) if len(c["load"]) > 1 else c[key][0]
            ax.plot(load, value, "X", ms=9, color=color)
    ax.set_xlabel(f"|load| ({unit})" if unit else "|load|")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
    ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4), useOffset=False)


def legend_entries(ax, curves: list[dict]) -> tuple[list, list]:
    """The legend of a load-path axis: its curves, and the bifurcation and limit-point
    markers where a curve has one."""
    handles, labels = ax.get_legend_handles_labels()
    if any(c["bifurcations"] for c in curves):
        handles.append(plt.Line2D([], [], ls="", marker="X", ms=8, color="0.3"))
        labels.append("bifurcation")
    if any(c["limit_points"] for c in curves):
        handles.append(plt.Line2D([], [], ls="", marker="D", mfc="none", ms=6, color="0.3"))
        labels.append("limit point")
    return handles, labels


def load_paths(
    scene: Scene,
    case_name: str,
    paths: dict[str, LoadPath],
    path: Path,
    traces: dict[str, LoadPath] | None = None,
) -> str:
    """The target point's dx and dy and the target body's rotation versus load, all models
    (and the arc-length traces through limit points, see :func:`load_path_curves`), each
    component on its own axis so that a parasitic one is seen at its own scale; a
    bifurcation is marked with a cross, a limit point with a diamond."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    unit = next((lp.load_unit for lp in paths.values()), None)
    body = scene.mechanism.target_body
    panels = (
        ("dx", "target point dx (mm)"),
        ("dy", "target point dy (mm)"),
        ("rotation", f"rotation of body {body} (deg)"),
    )
    curves = load_path_curves(paths, traces)
    for ax, (key, label) in zip(axes, panels):
        draw_component(ax, curves, key, unit, label)
    axes[0].legend(*legend_entries(axes[0], curves), fontsize=8)
    fig.suptitle(f"{scene.name}, load case {case_name}")
    fig.tight_layout()
    return _save(fig, path)


VISIBLE_MOTION = 0.1
"""The share of the mechanism's size the largest motion of a deformed-shape figure is drawn
at, where the true motion is smaller: the displacements are magnified by a round factor
(1, 2 or 5 times a power of ten) and the figure says by how much."""


def deformation_scale(motion: float, size: float) -> float:
    """The factor (1, 2 or 5 times a power of ten, at least 1) that draws a largest motion of
    ``motion`` mm at about :data:`VISIBLE_MOTION` of the mechanism's ``size`` (mm)."""
    if motion <= 0.0 or motion >= VISIBLE_MOTION * size:
        return 1.0
    wanted = VISIBLE_MOTION * size / motion
    power = 10.0 ** math.floor(math.log10(wanted))
    return max(1.0, max(f * power for f in (1.0, 2.0, 5.0) if f * power <= wanted))


def deformed(scene: Scene, case_name: str, lp: LoadPath, path: Path) -> str:
    """Deformed configurations at every other level and the tracing-point path, the
    displacements magnified (:func:`deformation_scale`, stated in the title) where the
    motion is too small to see."""
    fig, ax = plt.subplots(figsize=(7, 7))
    draw_deformed(ax, scene, case_name, lp)
    return _save(fig, path)


def draw_deformed(
    ax, scene: Scene, case_name: str, lp: LoadPath, scale: float | None = None
) -> float:
    """Draw the undeformed mechanism, the deformed flexures and links at about five levels
    (coloured from 0 to full load) and the tracing point's path on ``ax``; returns the
    displacement magnification used (``scale``, or :func:`deformation_scale` where None),
    which the title states. ``lp`` needs its poses and shapes recorded (mm, rad).

    Raises
    ------
    ValueError
        If ``lp`` holds no poses or shapes.
    """
    if lp.poses is None or lp.shapes is None:
        raise ValueError(
            f"{lp.model} on {lp.load_case}: a deformed picture needs the poses and shapes of "
            "every level (run with record_poses=True, record_shapes=True)"
        )
    draw_mechanism(scene, ax, load_case=case_name)
    mech = scene.mechanism
    n = len(lp.load)
    cmap = plt.get_cmap("viridis")
    rest_shapes = {name: np.asarray(pts[0]) for name, pts in lp.shapes.items()}
    placed = {}  # each moving body's drawn points (mm) at each level, true scale
    for body, poses in lp.poses.items():
        b = mech.bodies[body]
        if b.is_ground:
            continue
        pts = b.points if body != mech.target_body else np.vstack([b.points, mech.target_point])
        placed[body] = [place_points(np.asarray(pose), pts - b.reference) for pose in poses]
    motion = max(
        [
            float(np.abs(np.asarray(p) - rest_shapes[name]).max())
            for name, s in lp.shapes.items()
            for p in s
        ]
        + [float(np.abs(q - qs[0]).max()) for qs in placed.values() for q in qs],
        default=0.0,
    )
    scale = deformation_scale(motion, mech.size()) if scale is None else float(scale)
    for k in range(0, n, max(1, n // 5)) if n > 1 else [0]:
        col = cmap(k / max(n - 1, 1))
        for name, pts in lp.shapes.items():
            p = rest_shapes[name] + scale * (np.asarray(pts[k]) - rest_shapes[name])
            ax.plot(p[:, 0], p[:, 1], color=col, lw=1.2, alpha=0.9)
        for qs in placed.values():
            q = qs[0] + scale * (qs[k] - qs[0])
            ax.plot(q[:, 0], q[:, 1], color=col, lw=3, alpha=0.6)
    trace = mech.target_point + scale * np.column_stack([lp.dx, lp.dy])
    ax.plot(trace[:, 0], trace[:, 1], "k.-", lw=1, ms=4, label="tracing point path")
    ax.legend(fontsize=8, loc="best")
    magnified = "true scale" if scale == 1.0 else f"displacements x {scale:g}"
    ax.set_title(
        f"{scene.name} {case_name}: deformed ({lp.model})\n{magnified}, "
        "levels coloured 0 -> full load"
    )
    return scale


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

    from ..run import run_model

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
