"""Mass and weight of a multibody System: point masses on frames, assembled globally.

Every mass in flexval is a *mass point*: a mass m (t) at a material point of a
frame with coordinates (x, y, theta) (a rigid body's pose, a beam node, a
DCMM cut body), at initial offset ``rel`` (mm) from the frame's origin, with
its own rotary inertia J (t mm^2) about that point; or a point of a frame with
translations only (a continuum node, no theta). The point is at
x = p + R(theta) rel, so its kinetic energy 1/2 m |v_p + theta' k x R rel|^2 +
1/2 J theta'^2 is exact at any rotation, and the mass matrix over the frame's
(x, y, theta) is

    [[m, 0, -m r_y], [0, m, m r_x], [-m r_y, m r_x, J + m |rel|^2]],  r = R(theta) rel,

with the convective force m theta'^2 r on the translations (the
centripetal term of d/dt (R rel)). Its weight is the dead force m g at x.

Where the masses come from:

* rigid bodies: ``[[bodies]]`` mass data (geometry.inertia), at the centre of mass;
* flexures: the optional connector hook
  :meth:`reducedmodels.connector.Connector.mass_points` returning
  :class:`MassPoints` over the connector's local coordinates
  ``[pose_a, pose_b, internal]`` (default None: massless), or a consistent
  local matrix from :meth:`~reducedmodels.connector.Connector.mass_matrix`.
  Massless flexures are fine for static runs; the modal analysis condenses
  massless internal coordinates and refuses massless body coordinates.

Units: mm, t, s, N; g in mm/s^2.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np
import scipy.sparse as sp

from geometry import Mechanism, SceneError

from .connector import Connector, overrides

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
        Initial offset of the point from the frame's origin, mm.
    mass : array (k,)
        t.
    rotary : array (k,)
        Own rotary inertia about the point, t mm^2.
    """

    dofs: np.ndarray
    rel: np.ndarray
    mass: np.ndarray
    rotary: np.ndarray


def chain_mass_points(node_dofs: Sequence[Sequence[int]], node_rel: np.ndarray,
                      lengths: np.ndarray, line_density: float) -> MassPoints:
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
    line_density : float
        rho A, t/mm.
    """
    seg_mass = line_density * np.asarray(lengths, float)
    seg_rotary = HRZ_ROTARY * seg_mass * np.asarray(lengths, float) ** 2
    mass = np.zeros(len(seg_mass) + 1)
    rotary = np.zeros_like(mass)
    mass[:-1] += 0.5 * seg_mass
    mass[1:] += 0.5 * seg_mass
    rotary[:-1] += seg_rotary
    rotary[1:] += seg_rotary
    return MassPoints(np.asarray(node_dofs, int).reshape(-1, 3), np.asarray(node_rel, float),
                      mass, rotary)


def _rotated(theta: np.ndarray, rel: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.column_stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]])


def _angles(coords: np.ndarray, theta_dofs: np.ndarray) -> np.ndarray:
    return np.where(theta_dofs >= 0, coords[np.maximum(theta_dofs, 0)], 0.0)


def weight_terms(coords: np.ndarray, points: MassPoints, gravity: np.ndarray
                 ) -> tuple[float, np.ndarray, np.ndarray]:
    """Potential of the weights (N mm), its gradient and the diagonal of its Hessian.

    The potential of dead forces m g at x = p + R(theta) rel is
    -sum m g . x (up to a constant; for frames without theta p may be a
    displacement). Its only second derivatives are d^2/dtheta^2 =
    m g . R(theta) rel, on the diagonal.

    Parameters
    ----------
    coords : array (n,)
        The coordinates ``points.dofs`` index into.
    """
    n = coords.size
    d = points.dofs
    rr = _rotated(_angles(coords, d[:, 2]), points.rel)
    fx, fy = points.mass * gravity[0], points.mass * gravity[1]
    energy = -float(np.sum(fx * (coords[d[:, 0]] + rr[:, 0]) + fy * (coords[d[:, 1]] + rr[:, 1])))
    grad = np.bincount(d[:, 0], weights=-fx, minlength=n) + np.bincount(d[:, 1], weights=-fy,
                                                                        minlength=n)
    has_theta = d[:, 2] >= 0
    t = d[has_theta, 2]
    grad += np.bincount(t, weights=-(fy * rr[:, 0] - fx * rr[:, 1])[has_theta], minlength=n)
    diagonal = np.bincount(t, weights=(fx * rr[:, 0] + fy * rr[:, 1])[has_theta], minlength=n)
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
        rows, cols = (pattern if pattern is not None
                      else (np.repeat(np.arange(n), n), np.tile(np.arange(n), n)))
        self._theta = np.unique(points.dofs[points.dofs[:, 2] >= 0, 2])
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

    def evaluate(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
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

    def path_validity(self, states) -> list[list[str]]:
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


def connector_mass_points(connector: Connector, density: float | None) -> MassPoints | None:
    """The connector's mass points at ``density`` (t/mm^3); None without density or mass."""
    return None if density is None else connector.mass_points(density)


def body_mass_points(mechanism: Mechanism, body: str, slot: int) -> MassPoints | None:
    """The rigid body's own mass as a point at its centre of mass, in connector slot 0 or 1."""
    data = mechanism.inertia.bodies.get(body)
    if data is None:
        return None
    rel = data.center_of_mass - mechanism.bodies[body].reference
    return MassPoints(np.array([[3 * slot, 3 * slot + 1, 3 * slot + 2]]), rel[None],
                      np.array([data.mass]), np.array([data.inertia]))


def merge(points: Sequence[MassPoints | None]) -> MassPoints | None:
    """All given mass points in one table (None if there are none)."""
    points = [p for p in points if p is not None and p.mass.size]
    if not points:
        return None
    return MassPoints(*(np.concatenate([getattr(p, f) for p in points])
                        for f in MassPoints._fields))


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
        if own is None and data.density is not None and c.name in {f.name for f in
                                                                     mechanism.flexures}:
            raise SceneError(mechanism.source, "material.density", data.density,
                             f"flexure {c.name!r}: this model has no mass of the flexure")
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
    system : reducedmodels.core.System
        Its connectors' local-to-global maps place the connectors' masses.
    """

    def __init__(self, system):
        mech = system.mechanism
        self.density = mech.inertia.density
        self.system = system
        tables, self._consistent = [], []
        for k, (c, idx) in enumerate(zip(system.connectors, system._local_to_global)):
            own = c.inner if isinstance(c, Weighted) else c
            if self.density is not None and overrides(own, "mass_matrix"):
                self._consistent.append(k)
                continue
            points = connector_mass_points(c, self.density)
            if points is not None:
                gd = np.where(points.dofs >= 0, idx[np.maximum(points.dofs, 0)], -1)
                tables.append(points._replace(dofs=gd))
        for b in mech.moving_bodies:
            points = body_mass_points(mech, b, 0)
            if points is not None:
                tables.append(points._replace(dofs=system.pose_dofs(b)[None]))
        self.n = system.n_dofs
        merged = merge(tables) or MassPoints(np.zeros((0, 3), int), np.zeros((0, 2)),
                                             np.zeros(0), np.zeros(0))
        moving = merged.dofs[:, 0] >= 0            # points on the ground never move
        self.points = MassPoints(*(getattr(merged, f)[moving] for f in MassPoints._fields))

    def matrix(self, q: np.ndarray) -> sp.csr_matrix:
        """Mass matrix M(q) (t, t mm, t mm^2) over all coordinates of the System."""
        d, m, rel = self.points.dofs, self.points.mass, self.points.rel
        rr = _rotated(_angles(q, d[:, 2]), rel)
        has_theta = d[:, 2] >= 0
        t = d[has_theta, 2]
        rows = [d[:, 0], d[:, 1], t, d[has_theta, 0], t, d[has_theta, 1], t]
        cols = [d[:, 0], d[:, 1], t, t, d[has_theta, 0], t, d[has_theta, 1]]
        mt, rrt = m[has_theta], rr[has_theta]
        theta_theta = (self.points.rotary + m * (rel**2).sum(axis=1))[has_theta]
        vals = [m, m, theta_theta, -mt * rrt[:, 1], -mt * rrt[:, 1], mt * rrt[:, 0],
                mt * rrt[:, 0]]
        if self._consistent:
            states = self.system.local_states(q)
            for k in self._consistent:
                local = self.system.connectors[k].mass_matrix(self.density, *states[k]).tocoo()
                idx = self.system._local_to_global[k]
                r, c = idx[local.row], idx[local.col]
                keep = (r >= 0) & (c >= 0)
                rows.append(r[keep]), cols.append(c[keep]), vals.append(local.data[keep])
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(self.n, self.n))

    def convective(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Velocity-dependent inertia forces of the mass points (N): -sum m theta'^2 r.

        A point's acceleration is a_p + theta'' k x r - theta'^2 r, so the
        equations of motion are M(q) a + c(q, v) = f with c on the point's
        translations (its theta row gets (k x r) . r = 0). Consistent
        matrices (``mass_matrix`` connectors) are not covered.
        """
        d, m = self.points.dofs, self.points.mass
        has_theta = d[:, 2] >= 0
        rr = _rotated(_angles(q, d[:, 2]), self.points.rel)
        omega2 = np.where(has_theta, v[np.maximum(d[:, 2], 0)], 0.0) ** 2
        return (np.bincount(d[:, 0], weights=-m * omega2 * rr[:, 0], minlength=self.n)
                + np.bincount(d[:, 1], weights=-m * omega2 * rr[:, 1], minlength=self.n))

    def kinetic_energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """1/2 v^T M(q) v, N mm (t mm^2/s^2)."""
        return 0.5 * float(v @ (self.matrix(q) @ v))

    @property
    def has_consistent(self) -> bool:
        """True if some connector gives a consistent mass matrix (its convective terms are
        not modelled: :meth:`convective` covers mass points only)."""
        return bool(self._consistent)

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
    for c, idx in zip(system.connectors, system._local_to_global):
        for j, g in enumerate(idx[6:]):
            if mask[g]:
                names.append(f"{c.name} internal {j}")
    return names
