"""Mass and weight of a multibody System: point masses on frames, assembled globally.

Every mass in flexval is a *mass point*: a mass m (t) at a material point of a
frame with coordinates (x, y, theta) (a rigid body's pose, a beam node, a
DCMM cut body), at initial offset ``rel`` (mm) from the frame's origin, with
its own rotary inertia J (t mm^2) about that point; or a point of a frame with
translations only (a continuum node, no theta). A point may also sit on a
*link* hinged to its frame (a PRBM pseudo-link): the link turns by its own
angle phi about the hinge at ``rel``, and the point lies at ``link_rel`` from
the hinge. The point is at

    x = p + R(theta) rel + R(phi) link_rel = p + r1 + r2

(r2 = 0 without a link), so its kinetic energy 1/2 m |x'|^2 + 1/2 J psi'^2
(psi = phi on a link, else theta) is exact at any rotation. With the
Jacobian G = dx/d(x, y, theta, phi) = [I, k x r1, k x r2] the mass matrix is
m G^T G plus J on psi; for a point without a link, over (x, y, theta),

    [[m, 0, -m r_y], [0, m, m r_x], [-m r_y, m r_x, J + m |rel|^2]],  r = R(theta) rel,

and the convective force is m G^T (-theta'^2 r1 - phi'^2 r2) (the
centripetal terms of d/dt G; on the translations -m theta'^2 r1 - m phi'^2 r2).
Its weight is the dead force m g at x.

Where the masses come from:

* rigid bodies: ``[[bodies]]`` mass data (flexval.geometry.inertia), at the centre of mass;
* flexures: the optional connector hook
  :meth:`flexval.reducedmodels.core.connector.Connector.mass_points` returning
  :class:`MassPoints` over the connector's local coordinates
  ``[pose_a, pose_b, internal]`` (default None: massless), or a consistent
  local matrix from :meth:`~flexval.reducedmodels.core.connector.Connector.mass_matrix`.
  Massless flexures are fine for static runs; the modal analysis condenses
  massless internal coordinates and refuses massless body coordinates.

Units: mm, t, s, N; g in mm/s^2.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from flexval.geometry import Mechanism, SceneError
from flexval.geometry.profiles import quadrature_panels

from .connector import Connector, Reasons, overrides

HRZ_ROTARY = 1.0 / 78.0
"""Rotary inertia per end of a lumped segment, as a fraction of m l^2.

The Hinton-Rock-Zienkiewicz diagonal scaling of the Euler-Bernoulli
element's consistent mass (diagonal 156, 4 l^2, 156, 4 l^2 times m / 420)
scaled so that the translations carry the segment's mass: m/2 per end, and
m l^2 / 78 of rotary inertia per end."""


class MassPoints(NamedTuple):
    """Point masses over a connector's local coordinates.

    Attributes
    ----------
    dofs : int array (k, 3)
        Local indices of the (x, y, theta) coordinates of each point's frame;
        theta -1 for a frame without rotation (then ``rel`` is zero).
    rel : array (k, 2)
        Initial offset of the point (or of its link's hinge) from the frame's origin, mm.
    mass : array (k,)
        t.
    rotary : array (k,)
        Own rotary inertia about the point, t mm^2 (it turns with the link if
        there is one, else with the frame).
    link : int array (k,), optional
        Local index of the angle phi of the link the point sits on (rad,
        measured from the initial configuration), -1 for none. Default: none.
    link_rel : array (k, 2), optional
        Initial offset of the point from its link's hinge, mm (zero without a link).
    """

    dofs: np.ndarray
    rel: np.ndarray
    mass: np.ndarray
    rotary: np.ndarray
    link: np.ndarray | None = None
    link_rel: np.ndarray | None = None

    def complete(self) -> MassPoints:
        """The same points with ``link`` and ``link_rel`` filled in (-1 and zeros if absent)."""
        k = self.mass.size
        return self._replace(
            link=np.full(k, -1) if self.link is None else np.asarray(self.link, int),
            link_rel=np.zeros((k, 2))
            if self.link_rel is None
            else np.asarray(self.link_rel, float),
        )


def chain_mass_points(
    node_dofs: Sequence[Sequence[int]],
    node_rel: np.ndarray,
    lengths: np.ndarray,
    line_density: float | np.ndarray,
) -> MassPoints:
    """HRZ-lumped masses of a chain of segments between consecutive nodes.

    Segment k (length ``lengths[k]``, mm, between nodes k and k + 1) of mass
    m_k = line_density l_k gives m_k / 2 and m_k l_k^2 / 78 of rotary inertia
    to each of its end nodes (:data:`HRZ_ROTARY`). The total mass and its
    centre are exact for a uniform flexure cut into equal segments; the
    rotary terms keep every node's rotation massive.

    Parameters
    ----------
    node_dofs : (n + 1) triples of int
        Local (x, y, theta) indices of each node's frame.
    node_rel : array (n + 1, 2)
        Each node's offset from its frame's origin, mm.
    lengths : array (n,)
        Segment lengths, mm.
    line_density : float or array (n,)
        rho A, t/mm: one value, or each segment's mean over its length (a
        section that varies along the flexure).
    """
    seg_mass = line_density * np.asarray(lengths, float)
    seg_rotary = HRZ_ROTARY * seg_mass * np.asarray(lengths, float) ** 2
    mass = np.zeros(len(seg_mass) + 1)
    rotary = np.zeros_like(mass)
    mass[:-1] += 0.5 * seg_mass
    mass[1:] += 0.5 * seg_mass
    rotary[:-1] += seg_rotary
    rotary[1:] += seg_rotary
    return MassPoints(
        np.asarray(node_dofs, int).reshape(-1, 3), np.asarray(node_rel, float), mass, rotary
    )


GAUSS_POINTS = 16
"""Gauss-Legendre points per piece of flexure in :func:`piece_inertia`: exact for a
straight piece (polynomial integrands of degree <= 2), and for a circular piece of
angle phi the error is of order (phi / 2)^32 / 32!, below round-off for phi <= 2 pi."""


class LineDensity:
    """Mass per length rho A(s) of a flexure whose section varies, t/mm (s in mm).

    Parameters
    ----------
    density : float
        rho, t/mm^3.
    section : flexval.geometry.Section
        With a thickness profile h(s) from the flexure's first end.
    """

    def __init__(self, density: float, section):
        self.density, self.section = density, section

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """rho A(s), t/mm."""
        return self.density * self.section.area_at(s)

    def rule(self, s0: float, s1: float) -> tuple[np.ndarray, np.ndarray]:
        """Nodes s (mm) and mass weights (t) of the mass of the stretch [s0, s1].

        :func:`flexval.geometry.profiles.quadrature_panels` on the stretch,
        split at the profile's breakpoints inside it: exact to about 1e-13
        for every built-in profile.
        """
        if s1 <= s0:
            return np.array([s0]), np.zeros(1)
        inner = tuple(b - s0 for b in self.section.profile.breakpoints if s0 < b < s1)
        u, w = quadrature_panels(s1 - s0, inner, panels=8)
        return s0 + u, w * self(s0 + u)


def line_density(density: float, section) -> float | LineDensity:
    """Mass per length of a flexure: rho A (t/mm) for a uniform section, else rho A(s)."""
    return density * section.area if section.profile is None else LineDensity(density, section)


def piece_inertia(
    shape, s0: float, s1: float, line_density: float | LineDensity, origin: np.ndarray
) -> tuple[float, np.ndarray, float]:
    """Mass, centre of mass and rotary inertia of a piece of flexure taken as rigid.

    The centre line of ``shape`` between arc lengths ``s0`` and ``s1`` (mm),
    of mass per length ``line_density`` (rho A, t/mm, or a :class:`LineDensity`
    rho A(s) along a varying section), integrated by Gauss-Legendre
    quadrature (:data:`GAUSS_POINTS`; a varying section by
    :meth:`LineDensity.rule`, split where its profile is not smooth). The
    section's own rotary inertia rho I per length (a fraction (h / L)^2 / 12
    of the rest) is left out, as in Euler-Bernoulli theory. A piece of zero
    length has zero mass at the point s0.

    Returns
    -------
    mass : float
        t.
    rel : array (2,)
        Centre of mass minus ``origin``, mm.
    rotary : float
        Rotary inertia about the centre of mass, t mm^2.
    """
    if isinstance(line_density, LineDensity):
        s, dm = line_density.rule(min(s0, s1), max(s0, s1))
    else:
        x, w = np.polynomial.legendre.leggauss(GAUSS_POINTS)
        s = 0.5 * (s0 + s1) + 0.5 * (s1 - s0) * x
        dm = 0.5 * abs(s1 - s0) * w * line_density
    points = shape.point(s)
    mass = float(dm.sum())
    centre = dm @ points / mass if mass > 0.0 else points[0]
    rotary = float(dm @ ((points - centre) ** 2).sum(axis=1))
    return mass, centre - np.asarray(origin, float), rotary


def rigid_pieces(
    shape,
    forward: bool,
    bounds: np.ndarray,
    anchors: np.ndarray,
    line_density: float | LineDensity,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A flexure cut into consecutive pieces, each taken as rigid (:func:`piece_inertia`).

    Parameters
    ----------
    shape : flexval.geometry.shapes.Shape
        The flexure's centre line (arc length s from its start, mm).
    forward : bool
        Whether the chain order (body a to body b) runs from the shape's start.
    bounds : array (m + 1,)
        Arc lengths from body a's end (chain order, mm) where the m pieces meet,
        from 0 to the flexure's length.
    anchors : array (m, 2)
        The point each piece's centre of mass is measured from (its body's
        reference point or its link's hinge), mm.
    line_density : float or LineDensity
        rho A, t/mm (:func:`line_density` of the flexure's section).

    Returns
    -------
    mass (m,) in t, centre of mass minus anchor (m, 2) in mm, rotary inertia
    about the centre of mass (m,) in t mm^2.
    """
    length = shape.length
    out = []
    for (u0, u1), anchor in zip(zip(bounds[:-1], bounds[1:]), anchors):
        s0, s1 = (u0, u1) if forward else (length - u1, length - u0)
        out.append(piece_inertia(shape, s0, s1, line_density, anchor))
    mass, rel, rotary = zip(*out)
    return np.array(mass), np.array(rel), np.array(rotary)


def _rotated(theta: np.ndarray, rel: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.column_stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]])


def _angles(coords: np.ndarray, theta_dofs: np.ndarray) -> np.ndarray:
    return np.where(theta_dofs >= 0, coords[np.maximum(theta_dofs, 0)], 0.0)


def _kinematics(
    coords: np.ndarray, points: MassPoints
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each point's coordinates (k, 4: x, y, theta, phi; -1 absent), the columns of its
    Jacobian G (k, 4, 2) and its offsets r1, r2 (k, 2, 2) at ``coords``."""
    full = points.complete()
    dofs = np.column_stack([full.dofs, full.link])
    r = np.stack(
        [
            _rotated(_angles(coords, full.dofs[:, 2]), full.rel),
            _rotated(_angles(coords, full.link), full.link_rel),
        ],
        axis=1,
    )
    columns = np.zeros((dofs.shape[0], 4, 2))
    columns[:, 0, 0] = columns[:, 1, 1] = 1.0
    columns[:, 2:, 0], columns[:, 2:, 1] = -r[:, :, 1], r[:, :, 0]  # k x r
    return dofs, columns, r


def weight_terms(
    coords: np.ndarray, points: MassPoints, gravity: np.ndarray
) -> tuple[float, np.ndarray, np.ndarray]:
    """Potential of the weights (N mm), its gradient and the diagonal of its Hessian.

    The potential of dead forces m g at x = p + r1 + r2 is -sum m g . x (up
    to a constant; for frames without theta p may be a displacement). Its
    gradient is -m G^T g, and its only second derivatives are
    d^2/dtheta^2 = m g . r1 and d^2/dphi^2 = m g . r2, on the diagonal.

    Parameters
    ----------
    coords : array (n,)
        The coordinates ``points.dofs`` (and ``points.link``) index into.
    """
    n = coords.size
    dofs, columns, r = _kinematics(coords, points)
    weight = points.mass[:, None] * np.asarray(gravity, float)[None]  # (k, 2), N
    x = coords[dofs[:, 0]] + r[:, :, 0].sum(axis=1), coords[dofs[:, 1]] + r[:, :, 1].sum(axis=1)
    energy = -float(np.sum(weight[:, 0] * x[0] + weight[:, 1] * x[1]))
    present = dofs >= 0
    forces = -np.einsum("kjc,kc->kj", columns, weight)
    grad = np.bincount(dofs[present], weights=forces[present], minlength=n)
    second = np.einsum("kjc,kc->kj", r, weight)  # (k, 2): m g . r
    turns = present[:, 2:]
    diagonal = np.bincount(dofs[:, 2:][turns], weights=second[turns], minlength=n)
    return energy, grad, diagonal


class Weighted(Connector):
    """A connector with the weights of some mass points added to its potential.

    The weight of a flexure (its ``mass_points``) and of the rigid bodies it
    touches are dead loads applied before any load case: they are part of
    the potential at every load factor. Every hook but :meth:`evaluate` and
    :meth:`hessian_pattern` is the wrapped connector's.
    """

    def __init__(self, inner: Connector, points: MassPoints, gravity: np.ndarray):
        self.inner = inner
        self.name, self.bodies = inner.name, inner.bodies
        self.n_internal, self.n_multipliers = inner.n_internal, inner.n_multipliers
        self._points = points
        self._gravity = np.asarray(gravity, float)
        n = 6 + inner.n_internal
        pattern = inner.hessian_pattern()
        rows, cols = (
            pattern
            if pattern is not None
            else (np.repeat(np.arange(n), n), np.tile(np.arange(n), n))
        )
        full = points.complete()
        turns = np.concatenate([full.dofs[:, 2], full.link])
        self._theta = np.unique(turns[turns >= 0])
        self._rows = np.concatenate([rows, self._theta])
        self._cols = np.concatenate([cols, self._theta])
        #: the largest single weight (N): with no load case it scales the residual test
        self.dead_load_scale = float(points.mass.max(initial=0.0) * np.hypot(*self._gravity))

    def __getattr__(self, name: str):
        # model-specific attributes (a continuum's mesh, a PRBM's parameters ...)
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """The wrapped connector's pattern plus the diagonal of the weighted rotations."""
        return self._rows, self._cols

    def evaluate(
        self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Strain energy plus weight potential (N mm), gradient and Hessian values."""
        e, g, h = self.inner.evaluate(pose_a, pose_b, internal)
        coords = np.concatenate([pose_a, pose_b, internal])
        ew, gw, dw = weight_terms(coords, self._points, self._gravity)
        return e + ew, g + gw, np.concatenate([np.ravel(h), dw[self._theta]])

    def shape(self, pose_a, pose_b, internal) -> np.ndarray:
        """The wrapped connector's shape."""
        return self.inner.shape(pose_a, pose_b, internal)

    def initial_internal(self) -> np.ndarray:
        """The wrapped connector's."""
        return self.inner.initial_internal()

    def internal_is_rotation(self) -> np.ndarray:
        """The wrapped connector's."""
        return self.inner.internal_is_rotation()

    def predict_internal(self, states, weights, pose_a, pose_b) -> np.ndarray:
        """The wrapped connector's."""
        return self.inner.predict_internal(states, weights, pose_a, pose_b)

    def update_internal(self, old, new) -> np.ndarray:
        """The wrapped connector's."""
        return self.inner.update_internal(old, new)

    def validity(self, pose_a, pose_b, internal) -> list[str]:
        """The wrapped connector's."""
        return self.inner.validity(pose_a, pose_b, internal)

    def path_validity(self, states) -> Reasons:
        """The wrapped connector's."""
        return self.inner.path_validity(states)

    def mass_points(self, density: float) -> MassPoints | None:
        """The wrapped connector's."""
        return self.inner.mass_points(density)

    def section_forces(self, pose_a, pose_b, internal, gradient=None):
        """The wrapped connector's (from its elastic forces: the weights are not section forces)."""
        return self.inner.section_forces(pose_a, pose_b, internal, gradient)

    def path_section_forces(self, states):
        """The wrapped connector's (from its elastic forces: the weights are not section forces)."""
        return self.inner.path_section_forces(states)

    def mass_matrix(self, density, pose_a, pose_b, internal):
        """The wrapped connector's."""
        return self.inner.mass_matrix(density, pose_a, pose_b, internal)

    def convective_forces(self, density, pose_a, pose_b, internal, velocity):
        """The wrapped connector's."""
        return self.inner.convective_forces(density, pose_a, pose_b, internal, velocity)


def connector_mass_points(connector: Connector, density: float | None) -> MassPoints | None:
    """The connector's mass points at ``density`` (t/mm^3); None without density or mass."""
    return None if density is None else connector.mass_points(density)


def body_mass_points(mechanism: Mechanism, body: str, slot: int) -> MassPoints | None:
    """The rigid body's own mass as a point at its centre of mass, in connector slot 0 or 1."""
    data = mechanism.inertia.bodies.get(body)
    if data is None:
        return None
    rel = data.center_of_mass - mechanism.bodies[body].reference
    return MassPoints(
        np.array([[3 * slot, 3 * slot + 1, 3 * slot + 2]]),
        rel[None],
        np.array([data.mass]),
        np.array([data.inertia]),
    )


def merge(points: Sequence[MassPoints | None]) -> MassPoints | None:
    """All given mass points in one table (None if there are none)."""
    points = [p.complete() for p in points if p is not None and p.mass.size]
    if not points:
        return None
    return MassPoints(
        *(np.concatenate([getattr(p, f) for p in points]) for f in MassPoints._fields)
    )


def with_weights(mechanism: Mechanism, connectors: list) -> list:
    """The connectors with gravity added (unchanged without ``[gravity]``).

    Each flexure carries its own weight (its ``mass_points``); each massive
    rigid body's weight is carried by the first connector that touches it.

    Raises
    ------
    SceneError
        If the scene gives a density but a flexure model has no mass hook.
    """
    data = mechanism.inertia
    if data.gravity is None:
        return list(connectors)
    pending = {b for b in data.bodies}
    out = []
    for c in connectors:
        own = connector_mass_points(c, data.density)
        if (
            own is None
            and data.density is not None
            and c.name in {f.name for f in mechanism.flexures}
        ):
            raise SceneError(
                mechanism.source,
                "material.density",
                data.density,
                f"flexure {c.name!r}: this model has no mass of the flexure",
            )
        parts = [own]
        for slot, b in enumerate(c.bodies):
            if b in pending:
                parts.append(body_mass_points(mechanism, b, slot))
                pending.discard(b)
        points = merge(parts)
        out.append(c if points is None else Weighted(c, points, data.gravity))
    return out


class MassModel:
    """The global mass of a System: every mass point with its global coordinates.

    Flexure connectors with a ``mass_matrix(density, pose_a, pose_b,
    internal)`` hook (the continuum's consistent mass) contribute that
    local matrix instead of their mass points.

    Parameters
    ----------
    system : flexval.reducedmodels.core.system.System
        Its connectors' local-to-global maps place the connectors' masses.
    """

    def __init__(self, system):
        mech = system.mechanism
        self.density = mech.inertia.density
        self.system = system
        tables, self._consistent = [], []
        for k, (c, idx) in enumerate(zip(system.connectors, system.local_to_global)):
            own = c.inner if isinstance(c, Weighted) else c
            if self.density is not None and overrides(own, "mass_matrix"):
                self._consistent.append(k)
                continue
            points = connector_mass_points(c, self.density)
            if points is not None:
                points = points.complete()
                gd = np.where(points.dofs >= 0, idx[np.maximum(points.dofs, 0)], -1)
                gl = np.where(points.link >= 0, idx[np.maximum(points.link, 0)], -1)
                tables.append(points._replace(dofs=gd, link=gl))
        for b in mech.moving_bodies:
            points = body_mass_points(mech, b, 0)
            if points is not None:
                tables.append(points._replace(dofs=system.pose_dofs(b)[None]))
        self.n = system.n_dofs
        merged = (
            merge(tables)
            or MassPoints(
                np.zeros((0, 3), int), np.zeros((0, 2)), np.zeros(0), np.zeros(0)
            ).complete()
        )
        # points on the ground never move (unless on a link hinged to it)
        moving = (merged.dofs[:, 0] >= 0) | (merged.link >= 0)
        self.points = MassPoints(*(getattr(merged, f)[moving] for f in MassPoints._fields))

    def matrix(self, q: np.ndarray) -> sp.csr_matrix:
        """Mass matrix M(q) (t, t mm, t mm^2) over all coordinates of the System
        (see :meth:`entries`)."""
        rows, cols, values = self.entries(q)
        return sp.csr_matrix((values, (rows, cols)), shape=(self.n, self.n))

    def entries(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows, columns and values (t, t mm, t mm^2) of M(q); duplicates sum.

        Each point adds m G^T G over its (x, y, theta, phi) and its own rotary
        inertia on phi (on a link) or theta (see the module docstring).
        """
        dofs, columns, _ = _kinematics(q, self.points)
        m = self.points.mass
        values = m[:, None, None] * np.einsum("kac,kbc->kab", columns, columns)
        present = (dofs[:, :, None] >= 0) & (dofs[:, None, :] >= 0)
        own = np.where(dofs[:, 3] >= 0, dofs[:, 3], dofs[:, 2])
        spins = own >= 0
        rows = [np.broadcast_to(dofs[:, :, None], values.shape)[present], own[spins]]
        cols = [np.broadcast_to(dofs[:, None, :], values.shape)[present], own[spins]]
        vals = [values[present], self.points.rotary[spins]]
        if self._consistent:
            states = self.system.local_states(q)
            for k in self._consistent:
                local = self.system.connectors[k].mass_matrix(self.density, *states[k]).tocoo()
                idx = self.system.local_to_global[k]
                r, c = idx[local.row], idx[local.col]
                keep = (r >= 0) & (c >= 0)
                rows.append(r[keep]), cols.append(c[keep]), vals.append(local.data[keep])
        return np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)

    def convective(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Velocity-dependent inertia forces (N, N mm): c(q, v) with M(q) a + c(q, v) = f.

        A mass point's acceleration is G q'' + a_c with a_c = -theta'^2 r1 -
        phi'^2 r2 (the derivative of G along the motion), so it adds
        m G^T a_c; without a link only the translations get a term
        ((k x r1) . r1 = 0). A ``mass_matrix`` connector adds its own
        :meth:`~flexval.reducedmodels.core.connector.Connector.convective_forces`.
        """
        dofs, columns, r = _kinematics(q, self.points)
        rates = np.where(dofs[:, 2:] >= 0, v[np.maximum(dofs[:, 2:], 0)], 0.0) ** 2
        a_c = -np.einsum("kj,kjc->kc", rates, r)
        forces = self.points.mass[:, None] * np.einsum("kjc,kc->kj", columns, a_c)
        present = dofs >= 0
        # astype: numpy's bincount gives int64 zeros for an empty input even with
        # weights (no lumped mass points: every mass in a consistent matrix)
        total = np.bincount(dofs[present], weights=forces[present], minlength=self.n).astype(
            float, copy=False
        )
        if self._consistent:
            states = self.system.local_states(q)
            for k in self._consistent:
                idx = self.system.local_to_global[k]
                local_v = np.where(idx >= 0, v[np.maximum(idx, 0)], 0.0)
                c = self.system.connectors[k].convective_forces(self.density, *states[k], local_v)
                keep = idx >= 0
                total += np.bincount(idx[keep], weights=c[keep], minlength=self.n)
        return total

    def kinetic_energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """1/2 v^T M(q) v, N mm (t mm^2/s^2)."""
        return 0.5 * float(v @ (self.matrix(q) @ v))

    def massless(self) -> np.ndarray:
        """Boolean mask of the coordinates without mass (zero diagonal of M at rest)."""
        return self.matrix(self.system.initial_state()).diagonal() <= 0.0


def describe_massless(system, mask: np.ndarray) -> list[str]:
    """Names of massless coordinates: "body '3' (x)", "e12 internal 4"."""
    names = []
    labels = ("x", "y", "theta")
    for b, k in system.body_index.items():
        for j in range(3):
            if mask[3 * k + j]:
                names.append(f"body {b!r} ({labels[j]})")
    for c, idx in zip(system.connectors, system.local_to_global):
        for j, g in enumerate(idx[6:]):
            if mask[g]:
                names.append(f"{c.name} internal {j}")
    return names
