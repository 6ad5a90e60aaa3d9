"""A flexure's peak outer-fibre stress and its place, at every level of a path.

The stress helpers the recorder uses for one path or a batch's copies:
:func:`path_peaks` (section forces stacked over levels), :func:`stack_peaks`
(a group's stack of alike connectors, one compiled pass), :func:`state_peaks`
and :func:`record_stress` (a linear response: one state scaled to its levels),
and :func:`append_stresses`, which adds what they find to a LoadPath. A
flexure's numbers are the same whether it is computed alone or stacked with
others.

Units: mm, N, N mm, MPa.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from functools import cache
from types import ModuleType
from typing import NamedTuple

import numpy as np

from flexval.geometry import Section

from .loadpath import LoadPath
from .sections import ForceStack, SectionForces


def record_stress(
    path: LoadPath, connectors, forces, sections: dict, scales: Sequence[float] = (1.0,)
) -> None:
    """Append each flexure's peak outer-fibre stress (MPa) at one state, scaled, to ``path``.

    The linear response's form: one level is appended per entry of
    ``scales``, with the section forces times it (the load factors of a
    linear response, whose section forces are computed once). Connectors
    without section forces (None: pins) or without a section are skipped;
    the stress profile is kept for the last level only (``path.stress_profile``);
    a connector with a ``surface_stress`` also gives its surface peak
    (``path.fibre_stress``).

    Parameters
    ----------
    path : LoadPath
    connectors, forces :
        The system's connectors and their section forces (N, N mm) at the
        state (:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.section_forces`).
    sections : dict of flexure name -> Section
    scales : sequence of float
        The factors of the levels to append.
    """
    named = []
    for c, found in zip(connectors, forces):
        section = sections.get(c.name)
        if section is not None and found is not None:
            named.append((c.name, found, section, c.surface_stress))
    if len(named) < STACK_FROM:  # a path's few flexures: each alone
        factors = [abs(f) for f in np.asarray(scales, float).tolist()]
        append_stresses(
            path,
            (
                (name, _state_peak(found, section, factors, surface_stress))
                for name, found, section, surface_stress in named
            ),
        )
        return
    peaks = state_peaks(
        [(found, section) for _, found, section, _ in named],
        scales,
        [surface_stress for *_, surface_stress in named],
    )
    append_stresses(path, ((entry[0], found) for entry, found in zip(named, peaks)))


class _Sections(NamedTuple):
    """Uniform sections of several flexures as arrays (c, 1, ...) (mm, mm^2, mm^4): what
    :meth:`SectionForces.fibre_stress` reads of one, so one call serves them all."""

    thickness: np.ndarray
    area: np.ndarray
    inertia: np.ndarray
    profile: None = None


Surface = tuple[list[float], list[float]] | None
"""A flexure's surface fibre peak at each level (MPa) and its place, where its connector
has a ``surface_stress`` (a calibrated notch hinge: K(s) times the beam formula), else None."""

Peaks = tuple[list[float], list[float], list[float], list[float], Surface]
"""A flexure's peak stress at each level (MPa), its place (arc-length fraction from the first
end), the stations' fractions, the stress at each station at the last level (MPa) and its
:data:`Surface` peaks."""

SurfaceStress = Callable[[SectionForces, Section], tuple[np.ndarray, np.ndarray]] | None
"""A connector's ``surface_stress`` (:class:`~flexval.reducedmodels.core.connector.Connector`)."""


STACK_FROM = 8
"""Least number of flexures with uniform sections and forces of one shape whose stresses
:func:`path_peaks` and :func:`state_peaks` compute stacked: below it (a path's own few
flexures) stacking them costs more than it saves."""
STACK_SIZE = 64
"""Most flexures in one stack of :func:`path_peaks` and :func:`state_peaks` (a linear batch's
flexures), so that a stack's forces, stresses and the temporaries between them stay in the
processor's caches (64 flexures of 11 levels and 17 stations, ``dcmm:1``'s: 96 kB per array)
instead of every pass going to memory: on a ``dcmm:1`` batch of 1000 copies (open chain f+,
3000 flexures) :func:`path_peaks` costs less in stacks of 32 to 128 than in one stack or in
stacks of 16. A traced batch's stacks take
:func:`stack_peaks`' one compiled pass, without temporaries."""


def _fibre_stresses(
    entries: Sequence[tuple[SectionForces, Section]],
) -> tuple[list[int], list[tuple[list[int], np.ndarray, np.ndarray]]]:
    """The entries whose outer-fibre stress (MPa) is computed alone, and the stacks of the others.

    Entries with uniform sections and forces of one shape, at least
    :data:`STACK_FROM` of them, are stacked (their forces (c, ..., m),
    their sections as arrays), at most :data:`STACK_SIZE` to a stack, and each
    stack takes one call of :meth:`SectionForces.fibre_stress`, elementwise the
    arithmetic of each
    alone, so that a flexure's stress is the same whether it is computed with
    others (a batch's copies) or alone. Returns the indices of the entries
    left alone (a varying section, a few flexures) and, per stack, (the
    entries' indices, their stresses (c, ..., m), their stations (c, m)).
    """
    alone: list[int] = []
    alike: dict[tuple, list[int]] = {}  # uniform sections, by the forces' shape
    for j, (forces, section) in enumerate(entries):
        if section.profile is None:
            alike.setdefault(forces.axial.shape, []).append(j)
        else:
            alone.append(j)
    stacks = []
    constants: dict[int, tuple[float, float, float]] = {}  # a section's, read once
    for alike_members in alike.values():
        if len(alike_members) < STACK_FROM:
            alone += alike_members
            continue
        for first in range(0, len(alike_members), STACK_SIZE):
            members = alike_members[first : first + STACK_SIZE]
            stacks.append((members, *_stacked_stress([entries[j] for j in members], constants)))
    return alone, stacks


def _stacked_stress(
    chosen: list[tuple[SectionForces, Section]], constants: dict[int, tuple[float, float, float]]
) -> tuple[np.ndarray, np.ndarray]:
    """The outer-fibre stresses (c, ..., m) (MPa) and stations (c, m) of uniform sections'
    forces of one shape, stacked: :meth:`SectionForces.fibre_stress` elementwise, each as
    alone; ``constants`` keeps each section's h, A and I by id."""
    at = np.array([f.at for f, _ in chosen])
    axial = np.array([f.axial for f, _ in chosen])  # np.array of equal shapes: np.stack's copy,
    moment = np.array([f.moment for f, _ in chosen])  # at a third the cost
    values = section_constants([s for _, s in chosen], constants)
    shape = (-1, *[1] * (axial.ndim - 1))  # each section's constants against its forces
    stacked = _Sections(*(values[:, k].reshape(shape) for k in range(3)))
    return SectionForces(at, axial, moment).fibre_stress(stacked), at


def section_constants(
    sections: Sequence[Section], known: dict[int, tuple[float, float, float]] | None = None
) -> np.ndarray:
    """Uniform sections' thickness (mm), area (mm^2) and second moment (mm^4), (c, 3);
    ``known`` keeps each section's by id (sections repeat among a batch's copies)."""
    known = {} if known is None else known
    for s in sections:
        if id(s) not in known:
            known[id(s)] = (s.thickness, s.area, s.inertia)
    return np.array([known[id(s)] for s in sections], float).reshape(-1, 3)


def _unit_peaks(unit: np.ndarray, at: np.ndarray) -> list[Peaks]:
    """:data:`Peaks` of stacked stresses ``unit`` (c, k, m) (MPa) at stations ``at`` (c, m)."""
    places = np.take_along_axis(at, unit.argmax(axis=2), axis=1)
    peaks, stations, profiles = unit.max(axis=2).tolist(), at.tolist(), unit[:, -1].tolist()
    return [(*found, None) for found in zip(peaks, places.tolist(), stations, profiles)]


def path_peaks(
    entries: Sequence[tuple[SectionForces, Section]],
    surface_stresses: Sequence[SurfaceStress] | None = None,
) -> list[Peaks]:
    """Each flexure's peak outer-fibre stress at every level, its place and its last profile.

    Many flexures at once (:func:`_fibre_stresses`: a batch's copies), each as alone.

    Parameters
    ----------
    entries : sequence of (SectionForces, Section)
        Section forces (N, N mm) stacked over k levels, (k, m) each, and the
        flexure's section.
    surface_stresses : sequence of SurfaceStress, optional
        Each entry's connector's ``surface_stress`` (default: none has one); only a
        varying section has one, and such a section is computed alone.

    Returns
    -------
    list of :data:`Peaks`
        Per entry, plain lists.
    """
    out: list = [None] * len(entries)
    alone, stacks = _fibre_stresses(entries)
    for j in alone:
        out[j] = _path_peak(*entries[j], surface_stresses[j] if surface_stresses else None)
    for members, unit, at in stacks:  # unit (c, k, m)
        for j, peaks in zip(members, _unit_peaks(unit, at)):
            out[j] = peaks
    return out


@cache
def stress_kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.stresskernel`; its kernel is compiled, or loaded from
    the on-disk cache, where it is first called, off the path's clock
    (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import stresskernel

    return stresskernel


def stack_peaks(stack: ForceStack, constants: np.ndarray) -> list[Peaks]:
    """:func:`path_peaks` of a stack's members (forces (g, k, m)) with uniform sections, whose
    :func:`section_constants` are ``constants`` (g, 3): the same numbers, from one compiled
    pass (:func:`flexval.reducedmodels.kernels.stresskernel.stack_peaks`) without a
    :class:`SectionForces` per member."""
    count, levels, stations = stack.axial.shape
    peaks, places = np.empty((count, levels)), np.empty((count, levels))
    profile = np.empty((count, stations))
    at = np.ascontiguousarray(stack.at, float)
    stress_kernels().stack_peaks(
        at,
        stack.axial,
        stack.moment,
        np.ascontiguousarray(constants, float),
        peaks,
        places,
        profile,
    )
    stations_of = np.broadcast_to(at, (count, stations)).tolist()
    found = zip(peaks.tolist(), places.tolist(), stations_of, profile.tolist())
    return [(*peak, None) for peak in found]


def _path_peak(
    forces: SectionForces, section: Section, surface_stress: SurfaceStress = None
) -> Peaks:
    """:func:`path_peaks` of one flexure alone (forces (k, m))."""
    unit = forces.fibre_stress(section)
    surface = None
    if surface_stress is not None:
        at, true = surface_stress(forces, section)
        surface = (true.max(axis=1).tolist(), at[true.argmax(axis=1)].tolist())
    return (
        unit.max(axis=1).tolist(),
        forces.at[unit.argmax(axis=1)].tolist(),
        forces.at.tolist(),
        unit[-1].tolist(),
        surface,
    )


def _state_peak(
    forces: SectionForces,
    section: Section,
    factors: list[float],
    surface_stress: SurfaceStress = None,
) -> Peaks:
    """:func:`state_peaks` of one flexure alone (forces (m,); ``factors`` the scales' sizes)."""
    unit = forces.fibre_stress(section)
    peak = int(np.argmax(unit))
    top = float(unit[peak])  # plain floats: one product per level
    surface = None
    if surface_stress is not None:
        at, true = surface_stress(forces, section)
        k = int(np.argmax(true))
        surface = ([f * float(true[k]) for f in factors], [float(at[k])] * len(factors))
    return (
        [f * top for f in factors],
        [float(forces.at[peak])] * len(factors),
        forces.at.tolist(),
        (factors[-1] * unit).tolist(),
        surface,
    )


def state_peaks(
    entries: Sequence[tuple[SectionForces, Section]],
    scales: Sequence[float] = (1.0,),
    surface_stresses: Sequence[SurfaceStress] | None = None,
) -> list[Peaks]:
    """Each flexure's peak outer-fibre stress at one state, scaled to several levels.

    The linear response's form (:func:`record_stress`): the stress at the
    state times each entry of ``scales`` in size (MPa), its place at every
    level, the stations and the profile at the last level. Many flexures at
    once (:func:`_fibre_stresses`), each as alone.

    Parameters
    ----------
    entries : sequence of (SectionForces, Section)
        Section forces (N, N mm) at the state, (m,) each, and the flexure's section.
    scales : sequence of float
        The factors of the levels.
    surface_stresses : sequence of SurfaceStress, optional
        Each entry's connector's ``surface_stress`` (:func:`path_peaks`).
    """
    factors = [abs(f) for f in np.asarray(scales, float).tolist()]
    surface_stresses = surface_stresses or [None] * len(entries)
    if len(entries) < STACK_FROM:  # a path's few flexures: each alone, as stacking them would
        return [
            _state_peak(forces, section, factors, surface_stress)
            for (forces, section), surface_stress in zip(entries, surface_stresses)
        ]
    out: list = [None] * len(entries)
    alone, stacks = _fibre_stresses(entries)
    for j in alone:
        out[j] = _state_peak(*entries[j], factors, surface_stresses[j])
    for members, unit, at in stacks:  # unit (c, m)
        rows = np.arange(len(members))
        peak = unit.argmax(axis=1)
        tops, places = unit[rows, peak].tolist(), at[rows, peak].tolist()
        profiles = (factors[-1] * unit).tolist()
        for j, top, place, station, profile in zip(members, tops, places, at.tolist(), profiles):
            out[j] = ([f * top for f in factors], [place] * len(factors), station, profile, None)
    return out


def append_stresses(path: LoadPath, found: Iterable[tuple[str, Peaks]]) -> None:
    """Append each named flexure's peak stresses (MPa) and their places (:data:`Peaks`, as
    :func:`path_peaks` gives them: lists of its own, which a flexure's first levels become);
    its profile replaces the last one. A :data:`Surface` peak goes to ``path.fibre_stress``
    (``path_stress`` and ``path_at`` at every level, ``stress`` and ``at`` at the last)."""
    if path.peak_stress is None:
        path.peak_stress, path.peak_stress_at, path.stress_profile = {}, {}, {}
    stresses, places_of, profiles = path.peak_stress, path.peak_stress_at, path.stress_profile
    for name, (peaks, places, at, profile, surface) in found:
        so_far = stresses.get(name)
        if so_far is None:  # the flexure's first levels
            stresses[name], places_of[name] = peaks, places
        else:
            so_far.extend(peaks)
            places_of[name].extend(places)
        profiles[name] = {"at": at, "stress": profile}
        if surface is not None:
            _append_surface(path, name, *surface)


def _append_surface(path: LoadPath, name: str, peaks: list[float], places: list[float]) -> None:
    """Append a flexure's surface fibre peaks (MPa) and places to ``path.fibre_stress``."""
    if path.fibre_stress is None:
        path.fibre_stress = {}
    entry = path.fibre_stress.setdefault(name, {"path_stress": [], "path_at": []})
    entry["path_stress"].extend(peaks)
    entry["path_at"].extend(places)
    entry["stress"], entry["at"] = entry["path_stress"][-1], entry["path_at"][-1]


def flexure_peaks(lp: LoadPath) -> dict[str, tuple[list, list, bool]]:
    """Each flexure's peak stress at every level (MPa), where (fraction of its length from
    its first end) and whether it is a surface fibre peak (stress concentration included),
    in the path's order: a flexure whose surface fibre peak the path records at every level
    (``fibre_stress[name]["path_stress"]``: the continuum's notch hinges, and a reduced
    model's calibrated ones) with that peak, every other one with its section resultants'
    beam formula."""
    fibre = lp.fibre_stress or {}
    out = {}
    for name, values in (lp.peak_stress or {}).items():
        true = fibre.get(name, {})
        if "path_stress" in true:
            out[name] = (true["path_stress"], true["path_at"], True)
        else:
            out[name] = (values, lp.peak_stress_at[name], False)
    return out
