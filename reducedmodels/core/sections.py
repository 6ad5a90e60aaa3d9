"""Section forces and outer-fibre stress along a flexure, by statics of its end wrench.

A flexure carries no load between its ends, so the wrench it transmits is
the same at every cross-section; the section's normal force N and bending
moment M follow from the force and moment the flexure's end body exerts on
it and from the section's position and direction in the (displaced)
configuration:

    N(s) = F . t(s),    M(s) = -(M_ref + (p_ref - x(s)) x F),

with F the force (N) and M_ref the moment (N mm, about the end body's
reference point p_ref) the end body exerts on the flexure, x(s) the section's
current position and t(s) its current axis (pointing towards the end body).
The peak normal stress of the rectangular section is the outer-fibre value

    sigma(s) = |N| / A + |M| h / (2 I)       (MPa),

with h, A and I those of the station for a section that varies along the
flexure (a taper or a notch).

Every flexure connector reports its section forces from its own internal
forces (the gradient of its energy on the end body's pose) along its own
displaced centre line (beam nodes, DCMM displaced sub-arcs, PRBM links,
continuum mid-thickness nodes): see
:meth:`flexval.reducedmodels.core.connector.Connector.section_forces`.

Units: mm, N, N mm, MPa.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from flexval.geometry import Section


@dataclass(frozen=True)
class SectionForces:
    """Normal force and bending moment at stations along one flexure.

    Attributes
    ----------
    at : array (m,)
        Arc-length fraction of each station from the flexure's first end
        (the start of its centre line), 0..1, increasing (a polyline vertex
        appears twice, once per adjacent segment, when the axis turns there).
    axial : array (m,) or (k, m)
        Normal force N, N (tension positive); one row per state when the
        forces of k states at the same stations are stacked (a whole load
        path, see :meth:`flexval.reducedmodels.core.connector.Connector.path_section_forces`).
    moment : array (m,) or (k, m)
        Bending moment M, N mm: the moment the part before the section
        exerts on the part towards the end body (counterclockwise positive).
    """

    at: np.ndarray
    axial: np.ndarray
    moment: np.ndarray

    def fibre_stress(self, section: Section) -> np.ndarray:
        """Outer-fibre normal stress |N|/A + |M| h/(2 I) at each station (and state), MPa.

        A varying section (``section.profile``) takes h(s), A(s) and I(s) at
        each station's arc length s = at L (L the profile's length, the
        flexure's).
        """
        h, area, inertia = constants_at(section, self.at)
        return np.abs(self.axial) / area + np.abs(self.moment) * h / (2.0 * inertia)

    def peak(self, section: Section) -> tuple[float, float]:
        """Largest outer-fibre stress (MPa) and its arc-length fraction from the first end."""
        sigma = self.fibre_stress(section)
        k = int(np.argmax(sigma))
        return float(sigma[k]), float(self.at[k])


def constants_at(section: Section, fractions) -> tuple:
    """A section's thickness h (mm), area A (mm^2) and second moment I (mm^4) at arc-length
    ``fractions`` of its flexure: numbers for a uniform section, arrays along a varying one
    (``section.profile``: at s = fraction L, L the profile's length, the flexure's)."""
    if section.profile is None:
        return section.thickness, section.area, section.inertia
    s = np.asarray(fractions, float) * section.profile.length
    return section.thickness_at(s), section.area_at(s), section.inertia_at(s)


class ForceStack(NamedTuple):
    """Section forces of several connectors of a group at the same stations, stacked.

    What a group's end pass gives a batch's copies (whose flexures are
    alike) without a :class:`SectionForces` per connector: their stresses
    and peaks are then computed for the whole stack in a few array
    operations (:func:`flexval.reducedmodels.core.peaks.stack_peaks`).
    """

    members: list[int]
    """The connectors' indices in their group, one per row of the stack."""
    at: np.ndarray
    """(m,): the stations' arc-length fractions from the first end, shared by every member."""
    axial: np.ndarray
    """(g, k, m): normal force N at each of k levels and m stations of each member (N)."""
    moment: np.ndarray
    """(g, k, m): bending moment M (N mm), as :class:`SectionForces` says."""


def column_stacks(
    axial: np.ndarray,
    moment: np.ndarray,
    stations: Sequence[tuple[np.ndarray, np.ndarray] | None],
    offsets: np.ndarray,
    kinds: np.ndarray | None = None,
) -> list[ForceStack]:
    """Connectors' section forces read as columns of a group's arrays, stacked by stations.

    Parameters
    ----------
    axial, moment : ndarray (k, S)
        Normal force (N) and bending moment (N mm) at every station of every
        connector of a group, at k levels (a group kernel's output).
    stations : sequence of (at, base) or None
        Per connector (per kind, with ``kinds``): its stations' fractions
        ``at`` (m,) and where their forces are, the columns ``offsets[j] +
        base`` (``base`` (m,) of int); None for a connector without forces.
        Connectors whose ``at`` and ``base`` are equal (a batch's copies:
        read once per pair of objects) share a stack, in their order.
    offsets : ndarray of int
        Each connector's first column.
    kinds : ndarray of int, optional
        Each connector's entry of ``stations`` (a batch's copies of one
        connector share theirs, so a group of thousands reads a few);
        default: its own.
    """
    if kinds is None:
        kinds = np.arange(len(stations))
    order = np.argsort(kinds, kind="stable")  # the connectors of each kind, in their order
    starts = np.flatnonzero(np.diff(kinds[order], prepend=-1))
    by_object: dict[tuple[int, int], list[np.ndarray]] = {}  # the same arrays: one stack
    for members in np.split(order, starts[1:]):
        entry = stations[kinds[members[0]]]
        if entry is not None:
            by_object.setdefault((id(entry[0]), id(entry[1])), []).append(members)
    alike: dict[tuple[bytes, bytes], list[np.ndarray]] = {}
    for parts in by_object.values():
        at, base = stations[kinds[parts[0][0]]]
        alike.setdefault((at.tobytes(), base.tobytes()), []).extend(parts)
    stacks = []
    for parts in alike.values():
        members = np.sort(np.concatenate(parts))
        at, base = stations[kinds[members[0]]]
        columns = offsets[members][:, None] + base
        stacks.append(
            ForceStack(  # (g, k, m)
                members.tolist(),
                at,
                axial[:, columns].transpose(1, 0, 2),
                moment[:, columns].transpose(1, 0, 2),
            )
        )
    return stacks


def statics_section_forces(
    points: np.ndarray,
    fractions: np.ndarray,
    wrench: np.ndarray,
    end_pose: np.ndarray,
    reverse: bool = False,
    axes: np.ndarray | None = None,
) -> SectionForces:
    """Section forces along a displaced centre line from the wrench at its end body.

    Every array may carry a leading axis of k states (a whole load path)
    with the same stations: the forces come out stacked, (k, m).

    Parameters
    ----------
    points : array (m, 2) or (k, m, 2)
        Current centre line as a polyline ending at the end body, mm.
    fractions : array (m,)
        Arc-length fraction of each point measured along the same direction, 0..1.
    wrench : array (3,) or (k, 3)
        The connector's energy gradient on the end body's pose: the force
        (N, N) the end body exerts on the flexure and its moment (N mm) about
        the body's reference point, at equilibrium of the internal coordinates.
    end_pose : array (3,) or (k, 3)
        The end body's pose (mm, mm, rad).
    reverse : bool
        The polyline runs from the flexure's last end to its first: report
        fractions from the first end (1 - fraction) and stations in that order.
    axes : array (m, 2) or (k, m, 2), optional
        The sections' current unit axes at the points (towards the end
        body), where the model knows them (a curved centre line); default:
        each straight segment's own axis. Vertices that coincide with their
        predecessor (in the first state: points of one rigid body coincide
        in every state) have no axis and are left out.

    Returns
    -------
    SectionForces
        One station per point with ``axes``; otherwise two per segment (its
        two ends, with the segment's axis).
    """
    points = np.asarray(points, float)
    fractions = np.asarray(fractions, float)
    if axes is not None:
        x, t, at = points, np.asarray(axes, float), fractions
    else:
        first = points.reshape(-1, *points.shape[-2:])[0]
        keep = np.concatenate([[True], np.any(np.diff(first, axis=0) != 0.0, axis=1)])
        points, fractions = points[..., keep, :], fractions[keep]
        seg = np.diff(points, axis=-2)
        axis = seg / np.hypot(seg[..., 0], seg[..., 1])[..., None]
        x = np.concatenate([points[..., :-1, :], points[..., 1:, :]], axis=-2)
        t = np.concatenate([axis, axis], axis=-2)
        at = np.concatenate([fractions[:-1], fractions[1:]])
    wrench = np.asarray(wrench, float)
    force = wrench[..., :2]
    r = np.asarray(end_pose, float)[..., None, :2] - x
    # the part beyond the section is held by the end body and by the part before it
    moment = -(wrench[..., 2:3] + r[..., 0] * force[..., 1:2] - r[..., 1] * force[..., 0:1])
    axial = np.matmul(t, force[..., None])[..., 0]
    if reverse:
        at = 1.0 - at
    order = np.argsort(at, kind="stable")
    return SectionForces(at[order], axial[..., order], moment[..., order])


def polyline_fractions(points: np.ndarray) -> np.ndarray:
    """Cumulative length fraction (0..1) of the vertices of a polyline (m, 2)."""
    points = np.asarray(points, float)
    seg = np.hypot(*(points[1:] - points[:-1]).T)
    length = np.concatenate([[0.0], np.cumsum(seg)])
    return length / length[-1]


def unit_vectors(angle: np.ndarray) -> np.ndarray:
    """(cos, sin) of each angle (rad) of an array of shape (...), shape (..., 2)."""
    out = np.empty((*np.shape(angle), 2))  # (np.column_stack costs more on short arrays)
    out[..., 0], out[..., 1] = np.cos(angle), np.sin(angle)
    return out


def polyline_axes(points: np.ndarray) -> np.ndarray:
    """Unit axes of a finely sampled smooth curve at its points, by central differences."""
    d = np.gradient(np.asarray(points, float), axis=0)
    return d / np.hypot(d[:, 0], d[:, 1])[:, None]
