"""First yield and safety factors of a load path, from the peak stress it records.

Every model records, at each load level, the peak outer-fibre stress of each
flexure and where it lies (:attr:`flexval.reducedmodels.LoadPath.peak_stress`,
``peak_stress_at``: |N|/A + |M| h/(2I) of its own section forces, MPa). The
path's peak stress at a level is the largest over the flexures, the number the
run table and the report show. Against a material's yield strength sigma_y:

The continuum reference records the same beam-formula stress of its own
section resultants, and at a notch hinge also its true peak: the Cauchy
fibre stress recovered at the surface, outside the boundary layer at each
clamped end face (:mod:`flexval.validation.continuum.fibre`); a notch hinge's
stress at a level is that true peak (stress concentration included). A reduced
model records the same for a calibrated notch hinge: the largest of its beam
formula times the hinge's stress concentration K(s) over its stations, K(s)
calibrated against the continuum's surface fibre stress along the hinge
(:mod:`flexval.reducedmodels.notchcorrection`; not under the option ``eb``).

* **first yield**: the first level k whose peak stress reaches sigma_y; the
  yield load is interpolated linearly between levels k - 1 and k where the
  peak stress crosses sigma_y (the target's displacement and rotation with the
  same weight); the flexure and the place (arc length from its first end, mm)
  are those of the peak at level k. When level 0 already reaches sigma_y
  there is nothing to interpolate from and the yield point is that level.
  None when the path reaches full load below sigma_y.
* **safety factor at full load**: sigma_y / peak stress at full load (and
  sigma_f / peak stress against a fatigue strength sigma_f), None when the
  path stopped short of full load.

A path without stress recovery (no ``peak_stress``) gives None with the
reason, never a number. :func:`first_crossing` and :func:`first_yield` are
pure functions of arrays; :func:`path_yield` reads them off a
:class:`~flexval.reducedmodels.LoadPath`.

Units: loads in N or N mm (the case's), stresses in MPa, places in mm,
displacements in mm, rotations in rad.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from flexval.geometry import Material
from flexval.reducedmodels import LoadPath
from flexval.reducedmodels.core.peaks import flexure_peaks

NO_STRESS = "the model records no stress along its flexures"
"""The reason of a None yield point of a model without stress recovery."""


def first_crossing(stress: Sequence[float], strength: float) -> tuple[int, float] | None:
    """Where a stress series first reaches ``strength``: (k, w) or None.

    ``k`` is the first index with ``stress[k] >= strength`` and ``w`` in
    (0, 1] the linear weight between entries k - 1 and k at which the
    series equals ``strength``: (1 - w) stress[k - 1] + w stress[k] =
    strength (w = 1 for k = 0). None when no entry reaches it.
    """
    s = np.asarray(stress, float)
    hit = np.flatnonzero(s >= strength)
    if hit.size == 0:
        return None
    k = int(hit[0])
    if k == 0:
        return 0, 1.0
    low, high = s[k - 1], s[k]
    return k, float((strength - low) / (high - low))


def first_yield(
    loads: Sequence[float],
    stress: Sequence[float],
    flexures: Sequence[str],
    places: Sequence[float],
    strength: float,
    full_load: float,
    motion: Mapping[str, Sequence[float]] | None = None,
) -> dict | None:
    """The first yield point of a path: ``{"load", "fraction", "flexure", "at", ...}`` or None.

    Parameters
    ----------
    loads : sequence of float
        Load at each recorded level, N or N mm.
    stress : sequence of float
        Peak stress over the flexures at each level, MPa.
    flexures : sequence of str
        The flexure holding that peak at each level.
    places : sequence of float
        Where along that flexure: arc length from its first end, mm.
    strength : float
        Yield strength, MPa.
    full_load : float
        The load case's full load (N or N mm, non-zero): ``fraction`` is load / full_load.
    motion : mapping of name -> sequence of float, optional
        Further quantities per level (target ``dx``, ``dy`` in mm, ``rotation``
        in rad), interpolated with the load's weight and returned by name.

    Returns
    -------
    dict or None
        ``load`` (N or N mm), ``fraction``, ``flexure``, ``at`` (mm) and the
        interpolated ``motion``; None when no level reaches ``strength``.
    """
    found = first_crossing(stress, strength)
    if found is None:
        return None
    k, w = found

    def between(values: Sequence[float]) -> float:
        return float(values[k]) if k == 0 else float((1 - w) * values[k - 1] + w * values[k])

    load = between(loads)
    out = {
        "load": load,
        "fraction": load / full_load,
        "flexure": str(flexures[k]),
        "at": float(places[k]),
    }
    out.update({name: between(v) for name, v in (motion or {}).items()})
    return out


def peak_series(lp: LoadPath, lengths: Mapping[str, float]) -> tuple[np.ndarray, list, np.ndarray]:
    """The path's peak stress per level (MPa), the flexure holding it and where (mm).

    The largest of each flexure's recorded peak (the first flexure in the
    path's order on a tie). A flexure whose surface fibre peak the path
    records at every level (a notch hinge: ``fibre_stress[name]
    ["path_stress"]``) counts with that peak instead of its section
    resultants' beam formula (:func:`flexure_peaks`). ``lengths`` gives each
    flexure's length (mm), which turns the recorded fraction of length into
    arc length.
    """
    peaks = flexure_peaks(lp)
    names = list(peaks)
    table = np.array([peaks[n][0] for n in names], float)
    where = [peaks[n][1] for n in names]
    which = np.argmax(table, axis=0)
    levels = np.arange(table.shape[1])
    places = np.array([where[j][i] * lengths[names[j]] for i, j in zip(levels, which)])
    return table[which, levels], [names[j] for j in which], places


def path_yield(
    lp: LoadPath,
    material: Material,
    lengths: Mapping[str, float],
    full_load: float,
) -> dict:
    """First yield and safety factors of one path against ``material``'s strengths.

    Parameters
    ----------
    lp : LoadPath
    material : Material
        With ``yield_strength`` (MPa) and optionally ``fatigue_strength``.
    lengths : mapping of flexure -> float
        Each flexure's length, mm.
    full_load : float
        The load case's full load (N or N mm).

    Returns
    -------
    dict
        ``first_yield``: :func:`first_yield` of the path (None below the
        yield strength or without stress); ``safety_factor``: ``{"yield",
        "fatigue"}`` at full load (each None when it cannot be known, the
        fatigue one also without a fatigue strength); ``yield_note``: why a
        value is None when the reason is not that the path stays below the
        yield strength (None otherwise).
    """
    strength = material.yield_strength
    if strength is None:
        raise ValueError("the material has no yield strength")
    factors = {"yield": None, "fatigue": None}
    if not lp.peak_stress or not lp.load:
        return {"first_yield": None, "safety_factor": factors, "yield_note": NO_STRESS}
    stress, flexures, places = peak_series(lp, lengths)
    motion = {"dx": lp.dx, "dy": lp.dy, "rotation": lp.rotation}
    found = first_yield(lp.load, stress, flexures, places, strength, full_load, motion)
    note = None
    if not lp.converged:
        note = f"the path stopped at {lp.load[-1]:.6g} {lp.load_unit}, short of full load"
        if found is None:
            note += ", below the yield strength"
    elif stress[-1] > 0.0:
        factors["yield"] = strength / float(stress[-1])
        if material.fatigue_strength is not None:
            factors["fatigue"] = material.fatigue_strength / float(stress[-1])
    else:
        note = "no stress at full load"
    return {"first_yield": found, "safety_factor": factors, "yield_note": note}


def scene_yield(scene, lp: LoadPath) -> dict | None:
    """:func:`path_yield` of a path of ``scene`` (None when its material has no yield
    strength), the full load and the flexures' lengths taken from the scene."""
    material = scene.mechanism.material
    if material.yield_strength is None:
        return None
    lengths = {f.name: f.shape.length for f in scene.mechanism.flexures}
    case = scene.load_case(lp.load_case)
    return path_yield(lp, material, lengths, case.magnitude)


def yield_columns(scene, lp: LoadPath, outputs: Sequence[str]) -> dict:
    """A sweep row's first-yield columns (:data:`flexval.validation.sweep.store` schema)
    when ``outputs`` asks for ``first_yield`` and ``scene``'s material has a yield strength;
    {} otherwise (the columns stay null).

    ``first_yield_load`` (N or N mm), ``first_yield_fraction`` (of the full load),
    ``first_yield_flexure``, ``first_yield_at`` (mm from its first end), ``safety_factor``
    and ``fatigue_safety_factor`` at full load: :func:`path_yield`'s values, null where it
    has none.
    """
    found = scene_yield(scene, lp) if "first_yield" in outputs else None
    if found is None:
        return {}
    fy = found["first_yield"] or {}
    return {
        "first_yield_load": fy.get("load"),
        "first_yield_fraction": fy.get("fraction"),
        "first_yield_flexure": fy.get("flexure"),
        "first_yield_at": fy.get("at"),
        "safety_factor": found["safety_factor"]["yield"],
        "fatigue_safety_factor": found["safety_factor"]["fatigue"],
    }
