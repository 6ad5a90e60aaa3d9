"""Pictures of a mechanism: the undeformed outline (paper Figs. 6 and 12 in outline).

Matplotlib with the non-interactive Agg backend; lengths in mm.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from flexval.geometry import Force, Moment, Scene  # noqa: E402

from .outputs import save_figure  # noqa: E402


def draw_mechanism(scene: Scene, ax=None, load_case: str | None = None):
    """Draw flexures, rigid links, body labels, target point and load arrows on ``ax``."""
    mech = scene.mechanism
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    size = mech.size()
    for f in mech.flexures:
        s = np.linspace(0.0, f.shape.length, 200)
        p = f.shape.point(s)
        ax.plot(p[:, 0], p[:, 1], color="tab:blue", lw=2)
        mid = f.shape.point(0.5 * f.shape.length)
        ax.annotate(f.name, mid, color="tab:blue", fontsize=9, ha="center", va="bottom")
    for name, b in mech.bodies.items():
        pts = b.points
        if name == mech.target_body:
            pts = np.vstack([pts, mech.target_point])
        if b.is_ground:
            for p in pts:
                ax.plot(*p, marker="s", ms=10, color="0.3")
                ax.plot(
                    [p[0] - 0.03 * size, p[0] + 0.03 * size],
                    [p[1] - 0.015 * size] * 2,
                    color="0.3",
                    lw=3,
                )
            label_at = pts.mean(axis=0) - [0, 0.05 * size]
        else:
            if len(pts) >= 3:
                ax.fill(pts[:, 0], pts[:, 1], color="0.6", alpha=0.35)
                pts = np.vstack([pts, pts[:1]])
            ax.plot(pts[:, 0], pts[:, 1], color="0.15", lw=5, solid_capstyle="round", alpha=0.8)
            label_at = pts[:-1].mean(axis=0) if len(pts) > 3 else pts.mean(axis=0)
        ax.annotate(
            f"{name}",
            label_at,
            fontsize=11,
            weight="bold",
            color="darkred",
            ha="center",
            va="center",
            bbox=dict(boxstyle="circle,pad=0.2", fc="white", ec="darkred"),
        )
    ax.plot(*mech.target_point, marker="*", ms=14, color="gold", mec="k", zorder=5)
    ax.annotate("target", mech.target_point, xytext=(6, 6), textcoords="offset points", fontsize=9)
    cases = [scene.load_case(load_case)] if load_case else scene.load_cases
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"][1:]
    for k, lc in enumerate(cases):
        col = colors[k % len(colors)]
        for c in lc.components:
            if isinstance(c, Force):
                d = np.sign(c.value) * np.array([np.cos(c.angle), np.sin(c.angle)]) * 0.12 * size
                ax.annotate(
                    "",
                    xy=c.point + d,
                    xytext=c.point,
                    arrowprops=dict(arrowstyle="-|>", color=col, lw=2),
                )
                ax.annotate(lc.name, c.point + d, color=col, fontsize=9)
                ax.plot(*(c.point + 1.15 * d), alpha=0.0)  # keep the arrow inside the axes
            elif isinstance(c, Moment):
                p = mech.bodies[c.body].points.mean(axis=0)
                ax.annotate(
                    f"{lc.name} ({'ccw' if c.value > 0 else 'cw'})",
                    p,
                    xytext=(0, -18 - 12 * k),
                    textcoords="offset points",
                    color=col,
                    fontsize=9,
                    ha="center",
                )
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"{scene.name}: undeformed mechanism")
    ax.grid(alpha=0.3)
    return ax


def plot_mechanism(scene: Scene, path: str | Path) -> None:
    """Write the undeformed mechanism picture to ``path`` (PNG)."""
    fig, ax = plt.subplots(figsize=(7, 7))
    draw_mechanism(scene, ax)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)
