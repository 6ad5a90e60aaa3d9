"""Geometrically exact 2D beam FEM (``beam:N``): corotational two-node elements.

Each flexure's centre line is cut into N straight two-node elements whose
nodes lie exactly on the centre line, at arc lengths s_k = k L / N. A node
carries (x, y, theta): its position (mm) and its rotation increment (rad)
from the initial configuration. The two end nodes are rigidly attached to
the bodies the flexure joins; the N - 1 interior nodes are the connector's
internal coordinates.

Every element follows the corotational formulation for planar beams of
Crisfield (1991, Non-linear finite element analysis of solids and
structures, vol. 1) in the form of Battini (2002, PhD thesis, KTH): the
rigid motion of the element is carried by its chord, and what is left is
small and linear in a frame that rotates with the chord,

    u  = l - l0                        (axial stretch, mm)
    a1 = wrap(theta_1 - alpha)         (local end rotations, rad)
    a2 = wrap(theta_2 - alpha)

where l0 and l are the initial and current chord lengths and alpha is the
chord's rotation from the initial configuration, taken with atan2 of the
initial and current chords. Because theta_i and alpha are both increments,
the initial local rotations of a curved centre line (tangent angle minus
chord angle) cancel: the unloaded arc is stress free. Wrapping the local
rotations to (-pi, pi] keeps them right when nodes and chords have turned by
more than pi (the chord angle is only known modulo 2 pi).
The local energy is

    E = 1/2 [EA/l0 u^2 + a^T k_b a],   k_b = EI/l0 [[4, 2], [2, 4]],

or, with ``shear=True``, the Timoshenko beam's condensed bending stiffness
k_b = EI / (l0 (1 + phi)) [[4 + phi, 2 - phi], [2 - phi, 4 + phi]] with
phi = 12 EI / (kappa G A l0^2), kappa = 5/6. Gradient and tangent are
exact (material plus geometric parts), all elements are evaluated at once
with numpy, and the Hessian is returned as the values of a fixed sparse
pattern.

Accuracy: the elements bend over their chords, so an arc's bending length
is the chord polygon's, shorter than the arc by ~(width/N)^2 / 24; end
rotations and positions converge at O(1/N^2) (exact rotation under a pure
end moment only for a straight flexure).

Units: mm, N, MPa, N mm, rad.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from geometry import Flexure, Mechanism
from geometry.kinematics import rotate_xy

from .connector import Connector, ConnectorGroup, LocalState
from .validity import MAX_CHORD_TURN, MAX_STRAIN, rotation_reasons, stretch_reasons
from .sections import SectionForces, statics_section_forces, unit_vectors

from .inertia import MassPoints, chain_mass_points

SHEAR_CORRECTION = 5.0 / 6.0
"""Timoshenko shear coefficient kappa of a rectangular section."""


def _tangent_layout() -> tuple[np.ndarray, np.ndarray]:
    """Where each entry of a row-major 6x6 element tangent comes from: (source, sign), (36,) each.

    In element coordinates [x1, y1, theta1, x2, y2, theta2] the tangent is,
    by node and dof kind, [[A, w, -A, w], [w^T, k11, -w^T, k12],
    [-A, -w, A, -w], [w^T, k12, -w^T, k11]] with A symmetric 2x2, so every
    entry is +- one of the independent entries [Axx, Axy, Ayy, wx, wy, k11, k12].
    (A gather, not a matrix product: small BLAS calls thrash under load.)
    """
    source = np.empty((6, 6), dtype=np.intp)
    sign = np.ones((6, 6))
    translations, rotations = ([0, 1], [3, 4]), (2, 5)
    for i, ti in enumerate(translations):
        for j, tj in enumerate(translations):
            source[np.ix_(ti, tj)] = [[0, 1], [1, 2]]
            sign[np.ix_(ti, tj)] = 1.0 if i == j else -1.0
        for r in rotations:
            source[ti, r] = source[r, ti] = [3, 4]
            sign[ti, r] = sign[r, ti] = 1.0 if i == 0 else -1.0
    source[2, 2] = source[5, 5] = 5
    source[2, 5] = source[5, 2] = 6
    return source.ravel(), sign.ravel()


_SOURCE, _SIGN = _tangent_layout()


def wrap_angle(angle: np.ndarray) -> np.ndarray:
    """Angles (rad) brought into (-pi, pi], so that full turns carry no strain."""
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def bending_stiffness_terms(EI: float, l0: np.ndarray, shear_stiffness: float | None
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Diagonal and off-diagonal entries of the local bending stiffness k_b, N mm.

    Parameters
    ----------
    EI : float
        Bending stiffness, N mm^2.
    l0 : array (n,)
        Initial chord lengths, mm.
    shear_stiffness : float or None
        kappa G A in N for a Timoshenko beam, None for Euler-Bernoulli.
    """
    phi = 0.0 if shear_stiffness is None else 12.0 * EI / (shear_stiffness * l0**2)
    scale = EI / (l0 * (1.0 + phi))
    return scale * (4.0 + phi), scale * (2.0 - phi)


def chord_rotation(chord0: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Rotation (rad, in (-pi, pi]) of each chord d (n, 2) from its initial unit chord (n, 2).

    Taken with atan2 of the cross and dot products: robust for any magnitude.
    """
    return np.arctan2(chord0[:, 0] * d[:, 1] - chord0[:, 1] * d[:, 0],
                      chord0[:, 0] * d[:, 0] + chord0[:, 1] * d[:, 1])


def corotational_elements(x1: np.ndarray, x2: np.ndarray, theta1: np.ndarray,
                          theta2: np.ndarray, chord0: np.ndarray, l0: np.ndarray,
                          k_axial: np.ndarray, k11: np.ndarray, k12: np.ndarray
                          ) -> tuple[float, np.ndarray, np.ndarray]:
    """Energy, gradients and tangents of n corotational beam elements.

    Element e joins its first node (x1[e], theta1[e]) to its second
    (x2[e], theta2[e]); its coordinates are [x_1, y_1, theta_1, x_2, y_2,
    theta_2]. (For a chain of nodes x, x1 = x[:-1] and x2 = x[1:].)

    Parameters
    ----------
    x1, x2 : array (n, 2)
        Current positions of the elements' first and second nodes, mm.
    theta1, theta2 : array (n,)
        Their rotation increments from the initial configuration, rad.
    chord0 : array (n, 2)
        Initial unit chord vectors.
    l0 : array (n,)
        Initial chord lengths, mm.
    k_axial, k11, k12 : array (n,)
        EA / l0 (N/mm) and the entries of k_b (N mm).

    Returns
    -------
    energy : float
        Total strain energy, N mm.
    grad : array (n, 6)
        Element internal forces (N, N, N mm per node).
    hess : array (n, 36)
        Element consistent tangents, row-major 6x6 each: Crisfield's
        B^T D B + N z z^T / l + (M1 + M2) (r z^T + z r^T) / l^2 with
        r = dl/dq, z = l dalpha/dq, written out entry by entry.

    Notes
    -----
    With e = (c, s) the current chord direction and n = (-s, c) its normal,
    node 1 carries the force f = -N e + V n with the shear V = (M1 + M2)/l,
    node 2 carries -f, and the translational tangent block is
    A = EA/l0 e e^T + (2 (k11 + k12)/l^2 + N/l) n n^T + (M1 + M2)/l^2 (e n^T + n e^T).
    """
    d = x2 - x1
    length = np.hypot(d[:, 0], d[:, 1])
    c, s = d[:, 0] / length, d[:, 1] / length
    alpha = chord_rotation(chord0, d)
    a1 = wrap_angle(theta1 - alpha)
    a2 = wrap_angle(theta2 - alpha)
    u = length - l0
    axial = k_axial * u
    m1 = k11 * a1 + k12 * a2
    m2 = k12 * a1 + k11 * a2
    energy = 0.5 * float(np.sum(axial * u + m1 * a1 + m2 * a2))

    shear = (m1 + m2) / length
    fx, fy = -axial * c - shear * s, -axial * s + shear * c
    grad = np.empty((len(l0), 6))          # (filled through its transpose: np.column_stack
    grad.T[:] = (fx, fy, m1, -fx, -fy, m2)  # costs 5-10 times more on short arrays)

    # A in double-angle form: cos 2b = c^2 - s^2, sin 2b = 2 c s
    k_normal = 2.0 * (k11 + k12) / length**2 + axial / length
    k_cross = shear / length
    k_rot = (k11 + k12) / length
    cos2, sin2 = c * c - s * s, 2.0 * c * s
    mean, half = 0.5 * (k_axial + k_normal), 0.5 * (k_axial - k_normal)
    diagonal = half * cos2 - k_cross * sin2
    entries = np.array([mean + diagonal, half * sin2 + k_cross * cos2, mean - diagonal,
                        -k_rot * s, k_rot * c, k11, k12])                   # (7, n)
    hess = np.empty((len(l0), 36))          # C order: callers reshape rows (6, 6) in place
    np.multiply(entries[_SOURCE].T, _SIGN, out=hess)
    return energy, grad, hess


def attach_to_bodies(grad: np.ndarray, hess: np.ndarray, elements: np.ndarray, slot: int,
                     tangent: np.ndarray) -> None:
    """Transport end-node forces and tangents of some elements to rigid bodies' poses, in place.

    Each such node is its body's material point x = p + R(theta) rel (rel:
    its initial offset from the body's reference point, mm) and turns with
    it: theta_node = theta. With T = d node / d pose (identity except
    dx/dtheta = t = J R(theta) rel) the chain rule gives g <- T^T g and
    K <- T^T K T + (g_xy . d^2x/dtheta^2) e_theta e_theta^T, where
    d^2x/dtheta^2 = -R(theta) rel.

    Parameters
    ----------
    grad : array (n, 6)
        Element gradients; the node's rotation entries are updated.
    hess : array (n, 6, 6)
        Element tangents; the node's rotation rows and columns are updated.
    elements : int array (m,)
        The elements whose node is attached (distinct).
    slot : int
        First entry of that node in the element vector (0 or 3).
    tangent : array (m, 2)
        t = dx/dtheta of each attached node, mm.
    """
    t0, t1 = tangent[:, 0], tangent[:, 1]
    x, y, th = slot, slot + 1, slot + 2
    gx, gy = grad[elements, x], grad[elements, y]
    geometric = -(gx * t1 - gy * t0)                    # g_xy . (-R rel), with R rel = -J t
    grad[elements, th] += t0 * gx + t1 * gy
    hess[elements, th, :] += t0[:, None] * hess[elements, x, :] + t1[:, None] * hess[elements, y, :]
    hess[elements, :, th] += t0[:, None] * hess[elements, :, x] + t1[:, None] * hess[elements, :, y]
    hess[elements, th, th] += geometric


def end_node(pose: np.ndarray, rel: tuple[float, float]) -> tuple[float, float, float, float, float]:
    """(x, y, theta, dx/dtheta) of a flexure's end node on a body at ``pose``, mm and rad.

    The node is the body's material point at initial offset ``rel`` (mm) from
    its reference point: x = p + R(theta) rel, theta_node = theta, and
    dx/dtheta = J R(theta) rel. Plain floats: a few nodes per flexure.
    """
    angle = float(pose[2])
    rx, ry = rotate_xy(angle, rel[0], rel[1])
    return float(pose[0]) + rx, float(pose[1]) + ry, angle, -ry, rx


class BeamGroup(ConnectorGroup):
    """Beam connectors evaluated together: all their elements in one vectorised call.

    The elements of every flexure of the run are laid end to end: one
    corotational kernel call, one transport of the end nodes to their bodies
    and one scatter of the gradients, instead of some forty small array
    calls per flexure. The numbers are those of each flexure alone (the same
    operations, element by element).

    Parameters
    ----------
    connectors : sequence of BeamConnector
    """

    def __init__(self, connectors: Sequence["BeamConnector"]):
        super().__init__(connectors)
        n_nodes = [c._n_nodes for c in self.connectors]
        node_start = np.concatenate([[0], np.cumsum(n_nodes)[:-1]]).astype(np.intp)
        local_start = np.concatenate([[0], np.cumsum([6 + c.n_internal
                                                      for c in self.connectors])[:-1]])
        self._n_nodes = int(sum(n_nodes))
        self._n_local = int(sum(6 + c.n_internal for c in self.connectors))
        self._first = np.concatenate([s + np.arange(n - 1) for s, n in zip(node_start, n_nodes)])
        self._second = self._first + 1
        self._inner = np.concatenate([s + np.arange(1, n - 1)
                                      for s, n in zip(node_start, n_nodes)]).astype(np.intp)
        self._ends = np.column_stack([node_start, node_start + np.array(n_nodes) - 1]).ravel()
        element_start = node_start - np.arange(len(n_nodes))
        self._start_elements = element_start
        self._end_elements = element_start + np.array(n_nodes) - 2
        self._chord0, self._l0, self._k_axial, self._k11, self._k12 = (
            np.concatenate([getattr(c, name) for c in self.connectors])
            for name in ("_chord0", "_l0", "_k_axial", "_k11", "_k12"))
        self._dofs = np.concatenate([c._element_dofs + offset for c, offset
                                     in zip(self.connectors, local_start)]).ravel()
        # (slot of the pose in the local state, offset rel) of each end node, start then end
        self._end_bodies = [(c._end_pose[k], c._end_offsets[k])
                            for c in self.connectors for k in (0, 1)]
        # each connector with its elements' and its nodes' slices
        self._chains = [(c, slice(e, e + n - 1), slice(s, s + n)) for c, e, s, n
                        in zip(self.connectors, element_start, node_start, n_nodes)]

    def _nodes(self, states: Sequence[LocalState]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every flexure's node positions (n, 2) mm, rotations (n,) rad, end nodes' dx/dtheta.

        The last, (connectors, 2, 2) mm: at each flexure's start and end node.
        """
        ends = np.array([end_node(local[slot], rel) for (slot, rel), local
                         in zip(self._end_bodies, (s for s in states for _ in (0, 1)))])
        x = np.empty((self._n_nodes, 2))
        theta = np.empty(self._n_nodes)
        inner = np.concatenate([s[2] for s in states]).reshape(-1, 3)
        x[self._inner], theta[self._inner] = inner[:, :2], inner[:, 2]
        x[self._ends], theta[self._ends] = ends[:, :2], ends[:, 2]
        return x, theta, ends[:, 3:].reshape(-1, 2, 2)

    def predict_internal(self, past: Sequence[Sequence[LocalState]], weights: Sequence[float],
                         poses: Sequence[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
        """Concatenated interior nodes extrapolated in chord lengths and angles.

        As :meth:`BeamConnector.predict_internal` documents, for every
        flexure at once (the chains are closed flexure by flexure).
        """
        nodes = [self._nodes(states)[:2] for states in past]
        chords = [x[self._second] - x[self._first] for x, _ in nodes]
        angle_last = np.arctan2(chords[-1][:, 1], chords[-1][:, 0])
        length = np.zeros(len(self._l0))
        turn = np.zeros(len(self._l0))
        theta = np.zeros(self._n_nodes)
        for w, d, (_, th) in zip(weights, chords, nodes):
            length += w * np.hypot(d[:, 0], d[:, 1])
            turn += w * wrap_angle(np.arctan2(d[:, 1], d[:, 0]) - angle_last)
            theta += w * th
        angle = angle_last + turn
        ends = np.array([end_node(pose[slot], rel)[:2] for (slot, rel), pose
                         in zip(self._end_bodies, (p for p in poses for _ in (0, 1)))])
        return np.concatenate([
            c._closed_chain(length[e], angle[e], ends[2 * k], ends[2 * k + 1], theta[n])
            for k, (c, e, n) in enumerate(self._chains)])

    def update_internal(self, old: Sequence[LocalState], new: Sequence[LocalState]
                        ) -> np.ndarray:
        """Concatenated interior nodes after a Newton correction, chords turned, not sheared.

        As :meth:`BeamConnector.update_internal` documents, for every flexure
        at once (the chains are closed flexure by flexure).
        """
        x_old = self._nodes(old)[0]
        x_new, theta, _ = self._nodes(new)
        d_old = x_old[self._second] - x_old[self._first]
        d_new = x_new[self._second] - x_new[self._first]
        length = np.hypot(d_old[:, 0], d_old[:, 1])
        tangent = d_old / length[:, None]
        change = d_new - d_old
        stretch = np.einsum("ij,ij->i", tangent, change)
        turn = (tangent[:, 0] * change[:, 1] - tangent[:, 1] * change[:, 0]) / length
        angle = np.arctan2(tangent[:, 1], tangent[:, 0]) + turn
        return np.concatenate([
            c._closed_chain(length[e] + stretch[e], angle[e], x_new[n.start], x_new[n.stop - 1],
                            theta[n]) for c, e, n in self._chains])

    def evaluate(self, states: Sequence[LocalState]) -> tuple[float, np.ndarray, np.ndarray]:
        """Total strain energy (N mm), concatenated gradients and Hessian values.

        Per connector, as :meth:`BeamConnector.evaluate` documents: the
        internal forces conjugate to [pose_a, pose_b, internal] (N, N mm)
        and the values of its :meth:`~BeamConnector.hessian_pattern`.
        """
        x, theta, tangents = self._nodes(states)
        energy, grad, hess = corotational_elements(
            x[self._first], x[self._second], theta[self._first], theta[self._second],
            self._chord0, self._l0, self._k_axial, self._k11, self._k12)
        square = hess.reshape(-1, 6, 6)
        attach_to_bodies(grad, square, self._start_elements, 0, tangents[:, 0])
        attach_to_bodies(grad, square, self._end_elements, 3, tangents[:, 1])
        gradient = np.bincount(self._dofs, weights=grad.ravel(), minlength=self._n_local)
        return energy, gradient, hess.ravel()


class BeamConnector(Connector):
    """Corotational beam model of one flexure with N elements (a :class:`~reducedmodels.connector.Connector`).

    Parameters
    ----------
    flexure : Flexure
        The flexure; its centre line gives the node positions.
    mechanism : Mechanism
        Supplies the material and the bodies' reference points.
    n_elements : int
        N >= 1, the number of elements.
    shear : bool
        Use the Timoshenko (shear-flexible) local bending stiffness.

    Notes
    -----
    Local coordinates are [pose_a, pose_b, internal] with (a, b) = bodies;
    internal is the interior nodes' (x, y, theta), ordered from the
    flexure's start to its end.
    """

    def __init__(self, flexure: Flexure, mechanism: Mechanism, n_elements: int,
                 shear: bool = False):
        if n_elements < 1:
            raise ValueError(f"beam: number of elements must be >= 1, got {n_elements}")
        self.name = flexure.name
        self.bodies = tuple(flexure.bodies)
        self.n_internal = 3 * (n_elements - 1)
        self._n_nodes = n_elements + 1
        self._nodes0 = flexure.shape.point(np.linspace(0.0, flexure.shape.length, n_elements + 1))
        self._node_fractions = np.linspace(0.0, 1.0, n_elements + 1)
        self._node_tangent0 = flexure.shape.tangent_angle(self._node_fractions
                                                          * flexure.shape.length)
        chord = np.diff(self._nodes0, axis=0)
        l0 = np.hypot(chord[:, 0], chord[:, 1])
        self._l0 = l0
        self._chord0 = chord / l0[:, None]
        material = mechanism.material
        self._k_axial = flexure.axial_stiffness(material) / l0
        shear_stiffness = (SHEAR_CORRECTION * material.shear_modulus * flexure.section.area
                           if shear else None)
        self._k11, self._k12 = bending_stiffness_terms(flexure.bending_stiffness(material), l0,
                                                       shear_stiffness)
        # which pose (0: pose_a, 1: pose_b) carries the start node and the end node
        self._end_pose = (self.bodies.index(flexure.start_body),
                          self.bodies.index(flexure.end_body))
        self._end_rel = np.array([
            self._nodes0[0] - mechanism.bodies[flexure.start_body].reference,
            self._nodes0[-1] - mechanism.bodies[flexure.end_body].reference])
        self._end_offsets = tuple((float(rel[0]), float(rel[1])) for rel in self._end_rel)
        self._area, self._arc_length = flexure.section.area, flexure.shape.length
        self._element_dofs = self._element_dof_table()
        self._rows = np.repeat(self._element_dofs, 6, axis=1).ravel()
        self._cols = np.tile(self._element_dofs, (1, 6)).ravel()
        self._alone = BeamGroup([self])

    def _element_dof_table(self) -> np.ndarray:
        """Local coordinate number of each element's six dofs, (N, 6).

        The end nodes take their body's pose slots (0..2 for pose_a, 3..5 for
        pose_b) and are transported there by :func:`attach_to_bodies`.
        """
        node_dofs = np.empty((self._n_nodes, 3), dtype=np.int32)
        node_dofs[0] = 3 * self._end_pose[0] + np.arange(3)
        node_dofs[-1] = 3 * self._end_pose[1] + np.arange(3)
        node_dofs[1:-1] = 6 + np.arange(self.n_internal).reshape(-1, 3)
        return np.hstack([node_dofs[:-1], node_dofs[1:]])

    def mass_points(self, density: float) -> MassPoints:
        """The flexure's mass (density in t/mm^3) lumped on the nodes (HRZ rule).

        Lumped rather than consistent: each node's mass is a point mass with
        its own rotary inertia on the node's (x, y, theta), so the kinetic
        energy stays exact and frame-independent at any rotation (a
        consistent Hermite mass would have to turn with each chord). Each
        element gives m/2 and m l^2/78 to each end node
        (:func:`reducedmodels.inertia.chain_mass_points`); the end nodes'
        masses sit on the end bodies at the flexure's end points.
        """
        n = self._n_nodes - 1
        frames = [np.arange(3 * s, 3 * s + 3) for s in self._end_pose]
        node_dofs = [frames[0], *(6 + np.arange(self.n_internal).reshape(-1, 3)), frames[1]]
        rel = np.zeros((n + 1, 2))
        rel[0], rel[-1] = self._end_rel
        return chain_mass_points(node_dofs, rel, np.full(n, self._arc_length / n),
                                 density * self._area)

    def initial_internal(self) -> np.ndarray:
        """Interior nodes at rest: (x, y, 0) each, mm and rad."""
        inner = self._nodes0[1:-1]
        return np.column_stack([inner, np.zeros(len(inner))]).ravel()

    def internal_is_rotation(self) -> np.ndarray:
        """Every third internal coordinate (the nodal rotation) is an angle."""
        return np.tile([False, False, True], self.n_internal // 3)

    def _nodes(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """Current node positions (N + 1, 2) and rotations (N + 1,), mm and rad."""
        poses = (pose_a, pose_b)
        x = np.empty((self._n_nodes, 2))
        theta = np.empty(self._n_nodes)
        inner = np.asarray(internal, float).reshape(-1, 3)
        x[1:-1], theta[1:-1] = inner[:, :2], inner[:, 2]
        for node, slot, rel in zip((0, -1), self._end_pose, self._end_offsets):
            x[node, 0], x[node, 1], theta[node], _, _ = end_node(poses[slot], rel)
        return x, theta

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """Local (rows, cols) of the Hessian values :meth:`evaluate` returns (duplicates sum)."""
        return self._rows, self._cols

    def evaluate(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
                 ) -> tuple[float, np.ndarray, np.ndarray]:
        """Strain energy (N mm), gradient (6 + n_internal) and Hessian values.

        The gradient holds the internal forces conjugate to
        [pose_a, pose_b, internal] (N on translations, N mm on rotations);
        the consistent tangent is returned as the values of the entries of
        :meth:`hessian_pattern` (duplicates summed).
        """
        return self._alone.evaluate([(pose_a, pose_b, internal)])

    @classmethod
    def group(cls, connectors: Sequence["BeamConnector"]) -> BeamGroup:
        """All the connectors' elements evaluated in one vectorised call (:class:`BeamGroup`)."""
        return BeamGroup(connectors)

    def predict_internal(self, states: Sequence[LocalState], weights: Sequence[float],
                         pose_a: np.ndarray, pose_b: np.ndarray) -> np.ndarray:
        """Interior nodes extrapolated in chord lengths and angles (for the load stepping).

        Each element's chord length and direction and each node's rotation
        are extrapolated with ``weights`` over the converged ``states``; the
        chain is then rebuilt from the start body's end node (at its pose
        in ``pose_a``/``pose_b``) and the mismatch with the end body's node
        is spread along it in proportion to arc length. Extrapolating node
        positions instead would shorten every chord that turns, and the
        axial stiffness turns that O(h^2) error into forces far larger than
        the load (tens of Newton iterations on slender flexures).
        """
        return self._alone.predict_internal([[state] for state in states], weights,
                                            [(pose_a, pose_b)])

    def update_internal(self, old: LocalState, new: LocalState) -> np.ndarray:
        """Interior nodes after a Newton correction, with chords turned instead of sheared.

        ``new`` is the linearly corrected state. Each chord's change is split
        into its stretch (along the old chord) and its turn (across it,
        divided by the length), and the chord is rebuilt with that length
        and direction exactly; the chain is then closed between the end
        bodies' nodes as in :meth:`predict_internal`. This agrees with the
        linear update to first order, so Newton keeps its quadratic
        convergence, but a turning chord no longer comes out stretched by
        (turn)^2 / 2, which EA would turn into spurious forces.
        """
        return self._alone.update_internal([old], [new])

    def _closed_chain(self, length: np.ndarray, angle: np.ndarray, start: np.ndarray,
                      end: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Interior nodes of the chain of chords (length, angle) from ``start``, closed at ``end``.

        The mismatch between the last node and ``end`` is spread along the
        chain in proportion to arc length (a uniform stretch, the cheapest
        in axial energy). Returns the internal coordinates (x, y, theta).
        """
        x = np.empty((len(length) + 1, 2))
        x[0] = 0.0
        np.cumsum(length * np.cos(angle), out=x[1:, 0])
        np.cumsum(length * np.sin(angle), out=x[1:, 1])
        x += start
        share = np.concatenate([[0.0], np.cumsum(length)]) / length.sum()
        x += share[:, None] * (end - x[-1])
        internal = np.empty((len(length) - 1, 3))
        internal[:, :2], internal[:, 2] = x[1:-1], theta[1:-1]
        return internal.ravel()

    def validity(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
                 ) -> list[str]:
        """Reasons: element stretch over MAX_STRAIN, end turns from the chord over MAX_CHORD_TURN.

        See :mod:`reducedmodels.validity`: the first is material strain, the
        second an element too coarse for the curvature it carries.
        """
        x, theta = self._nodes(pose_a, pose_b, internal)
        d = x[1:] - x[:-1]
        length = np.hypot(d[:, 0], d[:, 1])
        alpha = chord_rotation(self._chord0, d)
        turn = np.maximum(np.abs(wrap_angle(theta[:-1] - alpha)),
                          np.abs(wrap_angle(theta[1:] - alpha)))
        if np.abs(length / self._l0 - 1.0).max() <= MAX_STRAIN and turn.max() <= MAX_CHORD_TURN:
            return []
        return (stretch_reasons("element", length, self._l0)
                + rotation_reasons("element", turn, MAX_CHORD_TURN))

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Deformed node positions (N + 1, 2), mm, from the flexure's start to its end."""
        return self._nodes(pose_a, pose_b, internal)[0]

    def section_forces(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray,
                       gradient: np.ndarray | None = None) -> SectionForces:
        """Normal force (N) and bending moment (N mm) at both end nodes of every element.

        Each element's own end forces (its internal-force vector at each
        node), so a load inside the flexure (its weight) is accounted for.
        The section axis at a node is the initial tangent turned by the
        node's rotation. ``gradient`` (a linear response's K0 dq) gives the
        forces by statics of the end wrench instead, along the nodes.
        """
        x, theta = self._nodes(pose_a, pose_b, internal)
        axes = unit_vectors(self._node_tangent0 + theta)
        if gradient is not None:
            slot = self._end_pose[1]
            return statics_section_forces(x, self._node_fractions,
                                          gradient[3 * slot:3 * slot + 3],
                                          (pose_a, pose_b)[slot], axes=axes)
        grad = corotational_elements(x[:-1], x[1:], theta[:-1], theta[1:], self._chord0,
                                     self._l0, self._k_axial, self._k11, self._k12)[1]
        # on the part towards the end body, from the part before: at an element's start
        # node the force that holds the element there, at its end node minus that force
        axial = np.concatenate([-np.einsum("ij,ij->i", grad[:, 0:2], axes[:-1]),
                                np.einsum("ij,ij->i", grad[:, 3:5], axes[1:])])
        moment = np.concatenate([grad[:, 2], -grad[:, 5]])
        at = np.concatenate([self._node_fractions[:-1], self._node_fractions[1:]])
        order = np.argsort(at, kind="stable")
        return SectionForces(at[order], axial[order], moment[order])
