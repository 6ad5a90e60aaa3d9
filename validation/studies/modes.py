"""``flexval modes``: natural frequencies and mode shapes of one model about an equilibrium.

The System is built exactly as for ``flexval run`` (gravity included); the
equilibrium at a fraction of a load case is traced by the same core, and the
modes come from :func:`flexval.reducedmodels.analyses.modes.natural_modes`. Units: Hz, mm, rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexval.geometry import LoadCase, Scene, SceneError
from flexval.geometry.errors import COMMAND_LINE
from flexval.geometry.inertia import PLA_DENSITY
from flexval.reducedmodels.analyses.modes import Modes, natural_modes
from flexval.reducedmodels.catalogue import LINEAR, ModelSpec

from ..outputs import save_figure


@dataclass(frozen=True)
class DensityChoice:
    """The flexure density an analysis with masses uses, and where it comes from.

    Attributes
    ----------
    density : float or None
        Flexure density, t/mm^3 (None: the flexures are massless).
    source : str
        ``"scene"`` (its ``material.density``), ``"--density"`` (the command line's,
        replacing the scene's if it has one), ``"default"`` (:data:`PLA_DENSITY`, the
        report's choice for a scene without one) or ``"none"``.
    """

    density: float | None
    source: str

    def describe(self, unit: str = "t/mm^3") -> str:
        """The choice in words, for a command's output (or a report's, ``unit="t/mm³"``)."""
        if self.source == "scene":
            return f"the scene's flexure density {self.density:g} {unit} (material.density)"
        if self.source == "--density":
            return f"the flexure density {self.density:g} {unit} given by --density"
        if self.source == "default":
            return (
                f"flexures of PLA ({self.density:g} {unit}, the default: the scene "
                "gives no material.density)"
            )
        return "massless flexures (the scene gives no material.density)"

    def record(self) -> dict:
        """JSON: ``{"value": t/mm^3 or null, "source": ...}``."""
        return {"value": self.density, "source": self.source}


def choose_density(
    scene: Scene, option: float | None, default: float | None = None, what: str = "this analysis"
) -> tuple[Scene, DensityChoice]:
    """The scene with the flexure density ``what`` uses, and which one it is.

    ``option`` (``--density``, t/mm^3) replaces the scene's ``material.density``;
    without either, ``default`` is taken (the report passes :data:`PLA_DENSITY`; the
    commands pass None). A scene that is then still massless, its flexures without
    density and a moving body without mass data, is refused: the modes and time
    histories of such a scene are undefined.

    Raises
    ------
    SceneError
        ``--density`` out of range, or a massless scene (naming ``--density`` with
        PLA's value as an example).
    """
    given = scene.mechanism.inertia.density
    if option is not None:
        scene = with_density(scene, option)
        return scene, DensityChoice(scene.mechanism.inertia.density, "--density")
    if given is not None:
        return scene, DensityChoice(given, "scene")
    if default is not None:
        return with_density(scene, default), DensityChoice(default, "default")
    massless = scene.mechanism.inertia.massless_bodies(scene.mechanism.moving_bodies)
    if massless:
        raise SceneError(
            COMMAND_LINE,
            "--density",
            None,
            f"{what} needs masses, but the scene gives no material.density and the moving "
            f"bodies {', '.join(massless)} no mass data: give the flexures' density in "
            f"t/mm^3, e.g. --density {PLA_DENSITY:g} (PLA), or material.density in the scene",
        )
    return scene, DensityChoice(None, "none")


def with_density(scene: Scene, density: float) -> Scene:
    """``scene`` with its flexures' density replaced (t/mm^3; checked like the scene field)."""
    import dataclasses

    from flexval.geometry.inertia import parse_density

    def fail(field: str, value, reason: str) -> None:
        raise SceneError(COMMAND_LINE, "--density", value, reason)

    inertia = dataclasses.replace(
        scene.mechanism.inertia, density=parse_density({"density": density}, fail)
    )
    return dataclasses.replace(  # its data no longer says what it is: none kept
        scene, mechanism=dataclasses.replace(scene.mechanism, inertia=inertia), data=None
    )


def modal_system(scene: Scene, spec: ModelSpec):
    """The System of ``scene`` with every flexure modelled as ``spec`` (the family's
    ``system``; ``ee``'s is ``dcmm:1``'s, whose tangent at rest is the ellipse of elasticity)."""
    from flexval.reducedmodels.models import build_system

    return build_system(scene.mechanism, spec)


def run_modes(
    scene: Scene, spec: ModelSpec, case: LoadCase | None, fraction: float, count: int
) -> tuple[object, Modes]:
    """The System and its ``count`` lowest modes at ``fraction`` of ``case``.

    Raises
    ------
    SceneError
        Bad ``--at`` or ``--count``, or a massless body.
    flexval.reducedmodels.core.settings.SolverError
        If the equilibrium cannot be reached.
    """
    if not 0.0 <= fraction <= 1.0 or not math.isfinite(fraction):
        raise SceneError(
            COMMAND_LINE,
            "--at",
            fraction,
            "must be a load fraction from 0 (unloaded) to 1 (full load)",
        )
    if fraction:
        from flexval.reducedmodels.core.drives import refuse_prescribed_motion

        refuse_prescribed_motion(case, COMMAND_LINE, "--load-case", "modes about a preload")
    if spec.model_family.has(LINEAR) and fraction != 0.0:
        raise SceneError(
            COMMAND_LINE,
            "--at",
            fraction,
            f"{spec.id} is linear: its modes are those at rest (use --at 0)",
        )
    if not 1 <= count <= 1000:
        raise SceneError(COMMAND_LINE, "--count", count, "must be from 1 to 1000")
    system = modal_system(scene, spec)
    return system, natural_modes(system, case, fraction, count)


def modes_record(
    scene: Scene,
    spec: ModelSpec,
    case: LoadCase | None,
    fraction: float,
    system,
    modes: Modes,
    density: DensityChoice | None = None,
) -> dict:
    """The JSON record: frequencies (Hz), omega^2 (1/s^2) and each mode's body motions.

    ``density`` (``{"value": t/mm^3, "source": ...}``, :meth:`DensityChoice.record`)
    is the flexure density used, taken from the scene if not given.

    ``mode_shapes[k][body]`` is (dx, dy, dtheta) of the body's reference
    point (mm, mm, rad) in mode k, normalised to unit modal mass (x^T M x = 1
    in t mm^2); only the direction and the ratios are physical.
    """
    shapes = [
        {b: modes.shapes[k, system.pose_dofs(b)].tolist() for b in system.mechanism.moving_bodies}
        for k in range(modes.eigenvalues.size)
    ]
    dx, dy, rot = system.target(modes.state)
    inertia = scene.mechanism.inertia
    return {
        "scene": scene.name,
        "model": spec.id,
        "load_case": None if case is None else case.name,
        "at": fraction,
        "frequencies_hz": modes.frequencies_hz.tolist(),
        "eigenvalues": modes.eigenvalues.tolist(),
        "equilibrium": {"dx": dx, "dy": dy, "rotation": rot},
        "density": (
            density
            or DensityChoice(inertia.density, "none" if inertia.density is None else "scene")
        ).record(),
        "massless_bodies": inertia.massless_bodies(system.mechanism.moving_bodies),
        "mode_shapes": shapes,
    }


PANELS_PER_ROW = 3
"""Mode panels side by side in a figure; more modes take more rows."""


def plot_modes(
    system, modes: Modes, path: str | Path, title: str, labels: list[str] | None = None
) -> None:
    """One panel per mode, :data:`PANELS_PER_ROW` to a row: the equilibrium shape (grey)
    and the mode shape (colour), flexures thin and rigid bodies thick.

    ``labels`` are the panels' titles (default: each mode's frequency in Hz).

    Each mode is scaled so that its largest body or node translation is 10 %
    of the mechanism's size.
    """
    from ..outputs import use_file_backend

    use_file_backend()
    import matplotlib.pyplot as plt

    from flexval.geometry.kinematics import place_points

    k = modes.eigenvalues.size
    columns = min(k, PANELS_PER_ROW)
    rows = -(-k // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(3.6 * columns, 3.6 * rows), squeeze=False)
    translations = ~system.is_rotation
    mech = system.mechanism
    for j, ax in enumerate(axes.ravel()):
        if j >= k:
            ax.set_axis_off()
            continue
        x = modes.shapes[j]
        scale = 0.1 * system.size / max(float(np.abs(x[translations]).max()), 1e-300)
        for q, color in ((modes.state, "0.7"), (modes.state + scale * x, "tab:red")):
            for c, local in zip(system.connectors, system.local_states(q)):
                pts = c.shape(*local)
                ax.plot(pts[:, 0], pts[:, 1], color=color, lw=1.5)
            for name, body in mech.bodies.items():  # the rigid bodies, thick
                pts = place_points(system.pose(q, name), body.points - body.reference)
                ax.plot(pts[:, 0], pts[:, 1], color=color, lw=4, alpha=0.6, solid_capstyle="round")
        ax.set_aspect("equal")
        label = labels[j] if labels else f"mode {j + 1}: {modes.frequencies_hz[j]:.4g} Hz"
        ax.set_title(label, fontsize=9)
        ax.tick_params(labelsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    plt.close(fig)
