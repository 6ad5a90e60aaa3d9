"""LoadPath: the one result type of every model on one load case.

For each requested load level it holds the target point's displacement
(dx, dy) in mm and the target body's rotation in rad (counterclockwise
positive), optionally every body's pose and the deformed flexure shapes, and
the solver's statistics. It round-trips through JSON without loss (floats
are written with ``repr`` precision by the json module).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

RUN_ADDITIONS = frozenset({"first_yield", "safety_factor", "yield_note"})
"""What ``flexval run --json`` adds to a load path's fields where the scene's material has a
yield strength (:func:`flexval.validation.studies.yieldpoint.scene_yield`): derived, not stored."""


@dataclass
class LoadPath:
    """Result of one model on one load case.

    Attributes
    ----------
    model : str
        Model id, e.g. ``beam:100``.
    load_case : str
    load : list of float
        Load value at each level (N for a force case, N mm for a moment case).
    dx, dy : list of float
        Target point displacement at each level, mm.
    rotation : list of float
        Target body rotation at each level, rad, counterclockwise positive.
    seconds : float
        Wall-clock time of the whole load path, s.
    converged : bool
        False if the path stopped early (then the lists end at the last
        converged level and ``stats['failure']`` says why).
    stats : dict
        Solver statistics: ``newton_iterations``, ``step_cuts``, ``substeps``,
        ``unknowns``, per-level ``iterations``, and ``failure`` if any.
    settings : dict
        Model settings that determine the result.
    scene : str
    load_unit : str
        ``N`` or ``N mm``.
    poses : dict of body -> list of [x, y, theta], optional
        Every body's pose at each level (mm, rad).
    shapes : dict of flexure -> list of [[x, y], ...], optional
        Deformed centre lines (or boundary) at each level, mm.
    section_forces : dict of flexure -> {"at", "axial", "moment"}, optional
        Recorded with the shapes: the model's own normal force (N, tension
        positive) and bending moment (N mm, counterclockwise on the part
        towards the flexure's second body) at the stations ``at`` (arc-length
        fractions from the first end) at every level, ``axial[k][i]`` and
        ``moment[k][i]``; the fibre-stress fields of a time series
        (:mod:`flexval.validation.series`) are made from them.
    reactions : list of [Fx, Fy, M], optional
        Total force (N) and moment about the origin (N mm) the ground exerts.
    drive_reactions : list of [Fx, Fy, M], optional
        Of a load case that prescribes a motion (displacement control): at
        every level, the force (N) and the moment (N mm, about the driven
        point) the drive applies to the driven body, what holds the
        prescribed motion. ``load`` is then the prescribed motion (mm, or rad
        for a rotation alone).
    valid : list of bool, optional
        The validity monitor at each level: True when every connector's state
        is inside its model's range of meaning (chord stretch, rotation per
        element, element inversion: see each connector's ``validity``).
    validity : list of (str or None), optional
        Why a level is not valid (the connectors' reasons, ``"; "``-joined),
        None where it is. The run is never stopped by it.
    time : list of float, optional
        Time (s) of each recorded state of a dynamic run
        (:mod:`flexval.reducedmodels.analyses.dynamics`); ``load`` is then the load at that time.
    peak_stress : dict of flexure -> list of float, optional
        Peak outer-fibre normal stress |N|/A + |M| h/(2 I) in each flexure
        at each level, MPa, from the model's own section forces
        (:meth:`flexval.reducedmodels.core.connector.Connector.section_forces`).
    peak_stress_at : dict of flexure -> list of float, optional
        Where that peak lies: arc-length fraction from the flexure's first
        end (the start of its centre line), 0..1.
    stress_profile : dict of flexure -> {"at": [...], "stress": [...]}, optional
        Outer-fibre stress (MPa) along each flexure at the last level
        (arc-length fractions from the first end).
    fibre_stress : dict of flexure -> {"stress", "at", "layer"}, optional
        The continuum's own peak fibre normal stress at full load (MPa), where
        (fraction from the first end) and the boundary layer excluded at each
        end face (mm): see :mod:`flexval.validation.continuum.fibre`. A notch
        hinge's entry adds that peak at every level, ``path_stress`` (MPa) and
        ``path_at`` (fraction), the stress its first yield is judged by. A
        reduced model records the same four for each calibrated notch hinge
        (its connector's ``surface_stress``: K(s) times its beam formula,
        :mod:`flexval.reducedmodels.notchcorrection`), without layers.
    limit_points : list of dict, optional
        Of an arc-length trace: where the load turns, each ``{"index",
        "load", "traced_load", "dx", "dy", "rotation"}`` (see
        :func:`flexval.validation.studies.limits.limit_points`; N or N mm, mm, rad).
    bifurcations : list of dict, optional
        Of a traced path: the bifurcation points it passed or stopped at,
        each ``{"load", "fraction"}`` (N or N mm, and the load factor), where
        the tangent's inertia changes while the load does not turn (see
        :mod:`flexval.reducedmodels.core.bifurcation`).
    """

    model: str
    load_case: str
    load: list[float]
    dx: list[float]
    dy: list[float]
    rotation: list[float]
    seconds: float
    converged: bool = True
    stats: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    scene: str = ""
    load_unit: str = "N"
    poses: dict | None = None
    shapes: dict | None = None
    section_forces: dict | None = None
    reactions: list | None = None
    drive_reactions: list | None = None
    valid: list | None = None
    validity: list | None = None
    time: list | None = None
    peak_stress: dict | None = None
    peak_stress_at: dict | None = None
    stress_profile: dict | None = None
    limit_points: list | None = None
    fibre_stress: dict | None = None
    bifurcations: list | None = None

    @property
    def displacement(self) -> np.ndarray:
        """Magnitude of the target point displacement at each level, mm."""
        return np.hypot(np.asarray(self.dx), np.asarray(self.dy))

    def arrays(self) -> dict[str, np.ndarray]:
        """The per-level results as numpy arrays: ``load`` (N or N mm), ``dx``, ``dy`` and
        ``displacement`` (mm), ``rotation`` (rad) and ``valid`` (bool; all True where the
        path has no verdicts)."""
        valid = self.valid if self.valid is not None else [True] * len(self.load)
        return {
            "load": np.asarray(self.load, float),
            "dx": np.asarray(self.dx, float),
            "dy": np.asarray(self.dy, float),
            "displacement": self.displacement,
            "rotation": np.asarray(self.rotation, float),
            "valid": np.asarray(valid, bool),
        }

    def to_dataframe(self):
        """:meth:`arrays` as a pandas DataFrame, one row per level, with the model and the
        load case as columns (pandas: the optional extra ``frames``).

        Raises
        ------
        ImportError
            Saying how to install pandas, where it is missing.
        """
        try:
            import pandas
        except ImportError:
            raise ImportError(
                "LoadPath.to_dataframe needs pandas: pip install 'flexval[frames]' "
                "(or pandas); LoadPath.arrays() gives the same columns as numpy arrays"
            ) from None
        frame = pandas.DataFrame(self.arrays())
        frame.insert(0, "load_case", self.load_case)
        frame.insert(0, "model", self.model)
        return frame

    def to_dict(self) -> dict:
        """Plain JSON-ready dict (None fields omitted)."""
        return {k: v for k, v in asdict(self).items() if v is not None}

    @classmethod
    def from_dict(cls, data: dict) -> LoadPath:
        """Inverse of :meth:`to_dict`; also reads a result of ``flexval run --json``, whose
        first-yield entries (:data:`RUN_ADDITIONS`, derived from the path and the scene's
        material) are left out.

        Raises
        ------
        ValueError
            A key that is neither a field nor such an entry (naming it).
        """
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - names - RUN_ADDITIONS)
        if unknown:
            raise ValueError(f"not a load path: unknown keys {unknown}")
        return cls(**{k: v for k, v in data.items() if k in names})

    @classmethod
    def read_run_json(cls, path: str | Path) -> list[LoadPath]:
        """Every load path of a ``flexval run --json`` file (its ``results``), in its order."""
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        return [cls.from_dict(result) for result in data["results"]]

    def to_json(self) -> str:
        """JSON text (lossless for floats)."""
        return json.dumps(self.to_dict())

    @classmethod
    def from_json(cls, text: str) -> LoadPath:
        """Inverse of :meth:`to_json`."""
        return cls.from_dict(json.loads(text))


def read_results(path: str | Path) -> list[LoadPath]:
    """Every load path of a ``flexval run --json`` file, in its order
    (:meth:`LoadPath.read_run_json`)."""
    return LoadPath.read_run_json(path)
