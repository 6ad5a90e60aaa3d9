"""Geometrically exact 2D beam FEM (``beam:N``): corotational two-node elements.

Each flexure's centre line is cut into N straight two-node elements whose
nodes lie exactly on the centre line, at arc lengths s_k = k L / N (a
section that varies along the flexure grades them instead, shorter where
it is thin: :mod:`flexval.reducedmodels.beam.varying`). A node
carries (x, y, theta): its position (mm) and its rotation increment (rad)
from the initial configuration. The two end nodes are rigidly attached to
the bodies the flexure joins; the N - 1 interior nodes are the connector's
internal coordinates.

Every element follows the corotational formulation of Crisfield (1991, Non-linear finite
element analysis of solids and structures, vol. 1) in the form of Battini (2002, PhD
thesis, KTH): the chord carries the element's rigid motion, and what is left, u = l - l0
and the end rotations from the chord a = (a1, a2) wrapped to (-pi, pi], is small and linear:

    E = 1/2 [EA/l0 u^2 + a^T k_b a],   k_b = EI/l0 [[4, 2], [2, 4]],

or with ``shear=True`` the Timoshenko beam's condensed k_b; a varying section takes the
inverse of each element's exact flexibility (:mod:`flexval.reducedmodels.beam.varying`).
Gradient and tangent are exact; the elements of all flexures are evaluated in one compiled
call (:mod:`flexval.reducedmodels.kernels.beamkernel`), which adds them straight into the
global gradient and tangent. End rotations and positions converge at O(1/N^2). The
formulation and its accuracy are in the documentation's models page, ``beam:N``.

Units: mm, N, MPa, N mm, rad.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from types import ModuleType

import numpy as np

from flexval.geometry import Flexure, Mechanism
from flexval.geometry.kinematics import rotate_xy

from ..core.chains import NodeChains, local_coordinates
from ..core.connector import Connector, ConnectorGroup, LocalState, Reasons
from ..core.inertia import MassPoints, chain_mass_points
from ..core.sections import SectionForces, statics_section_forces, unit_vectors
from ..core.validity import MAX_CHORD_TURN, MAX_STRAIN, rotation_reasons, stretch_reasons
from .varying import element_stiffness, graded_stations

SHEAR_CORRECTION = 5.0 / 6.0
"""Timoshenko shear coefficient kappa of a rectangular section."""

NODE_COORDINATES = 3
"""A node's coordinates (x, y, theta)."""

CHAIN_HALF_BANDWIDTH = 2 * NODE_COORDINATES - 1
"""Half-bandwidth of the tangent of a chain of two-node elements numbered node after node
(an element couples its two nodes' coordinates): the band flexures' tangents take."""


@functools.cache
def beam_kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.beamkernel`; each kernel is compiled, or loaded
    from the on-disk cache, where it is first called, off the path's clock
    (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import beamkernel

    return beamkernel


def bending_stiffness_terms(
    EI: float, l0: np.ndarray, shear_stiffness: float | None
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


def end_node(
    pose: np.ndarray, rel: tuple[float, float]
) -> tuple[float, float, float, float, float]:
    """(x, y, theta, dx/dtheta) of a flexure's end node on a body at ``pose``, mm and rad.

    The node is the body's material point at initial offset ``rel`` (mm) from
    its reference point: x = p + R(theta) rel, theta_node = theta, and
    dx/dtheta = J R(theta) rel. Plain floats: a few nodes per flexure.
    """
    angle = float(pose[2])
    rx, ry = rotate_xy(angle, rel[0], rel[1])
    return float(pose[0]) + rx, float(pose[1]) + ry, angle, -ry, rx


class BeamGroup(ConnectorGroup):
    """Beam connectors evaluated together: all their elements in one compiled call.

    The elements of every flexure of the run are laid end to end and
    evaluated by :func:`flexval.reducedmodels.kernels.beamkernel.assemble_elements`, which
    also transports the end nodes to their bodies and adds the results where
    they belong: into the concatenated local gradients and Hessian values
    (:meth:`evaluate`), or straight into the System's gradient and tangent
    storage (:meth:`assembler`). The numbers are those of each flexure
    alone (the same operations, element by element).

    Parameters
    ----------
    connectors : sequence of BeamConnector
    """

    compiled = True

    def __init__(self, connectors: Sequence[BeamConnector]):
        super().__init__(connectors)
        n_nodes = [c._n_nodes for c in self.connectors]
        n_elements = [n - 1 for n in n_nodes]
        sizes = [6 + c.n_internal for c in self.connectors]
        node_start, local_start = _starts(n_nodes), _starts(sizes)
        self._n_nodes, self._n_local = sum(n_nodes), sum(sizes)
        self._chain_nodes = np.array([*node_start, self._n_nodes], np.int64)
        # element e of flexure k joins node e + k to the next (a flexure's nodes follow its
        # elements', plus one)
        self._first = np.arange(sum(n_elements), dtype=np.int64) + np.repeat(
            np.arange(len(n_nodes), dtype=np.int64), n_elements
        )
        ends = np.array([[s, s + n - 1] for s, n in zip(node_start, n_nodes)], np.intp).ravel()
        self._chord0, self._l0, self._k_axial, self._k11, self._k12, self._k22 = (
            np.concatenate([getattr(c, name) for c in self.connectors])
            for name in ("_chord0", "_l0", "_k_axial", "_k11", "_k12", "_k22")
        )
        self._flexibility = np.concatenate([c._flexibility for c in self.connectors])
        # the element kernel's per-element numbers in one table (one argument, not five)
        self._terms = np.column_stack(
            [self._chord0, self._l0, self._k_axial, self._k11, self._k12, self._k22]
        )
        # the kernel's node tables in the concatenated local coordinates: where each node's
        # (x, y, theta) or its body's pose is read, its offset on the body, whether attached
        # (BeamConnector._node_dof_table laid end to end: interior node i of a flexure at
        # 6 + 3 (i - 1) of its coordinates, its end nodes at their bodies' poses)
        offset = np.repeat(np.array(local_start, np.int64), n_nodes)
        within = np.arange(self._n_nodes, dtype=np.int64) - np.repeat(
            np.array(node_start, np.int64), n_nodes
        )
        self._node_dof = offset + 3 * within + 3
        self._node_dof[ends] = [
            start + 3 * pose
            for c, start in zip(self.connectors, local_start)
            for pose in c._end_pose
        ]
        self._node_rel = np.zeros((self._n_nodes, 2))
        self._node_rel[ends] = [rel for c in self.connectors for rel in c._end_offsets]
        self._attached = np.zeros(self._n_nodes, bool)
        self._attached[ends] = True
        # the chain closure's element flexibilities, l0 / EI and l0 / EA for a uniform section
        self._chains = NodeChains(
            self._node_dof,
            self._node_rel,
            self._attached,
            self._chain_nodes,
            self._flexibility,
            1.0 / self._k_axial,
        )
        node_dofs = self._node_dof[:, None] + np.arange(NODE_COORDINATES)
        self._dofs = np.hstack([node_dofs[self._first], node_dofs[self._first + 1]])
        # the end pass's tables: each node's initial tangent angle, each connector's first
        # element, and where its section stations (arc-length order) are among every
        # element's start node then every element's end node
        self._tangent0 = np.concatenate([c._node_tangent0 for c in self.connectors])
        self._element_start = np.array(_starts(n_elements), np.intp)
        total = sum(n_elements)
        self._section_index = [
            np.concatenate([e0 + np.arange(n), total + e0 + np.arange(n)])[c._section_order]
            for c, e0, n in zip(self.connectors, self._element_start, n_elements)
        ]

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """The connectors' :meth:`BeamConnector.hessian_pattern` laid end to end
        (as the base class).

        Each element's row-major 6 x 6 block over its two nodes' coordinates,
        from the element table, in one pass over all the flexures.
        """
        return _block_pattern(self._dofs)

    def _kernel(
        self, node_dof: np.ndarray, grad_slot: np.ndarray, tangent_slot: np.ndarray
    ) -> Callable[[np.ndarray, np.ndarray, np.ndarray], float]:
        """``f(coordinates, grad, storage) -> energy``: the element kernel on these index maps."""
        kernels = beam_kernels()
        assemble_elements = kernels.assemble_elements
        ends = self._attached[self._first] | self._attached[self._first + 1]
        fixed = (
            np.ascontiguousarray(node_dof, np.int64),
            self._node_rel,
            self._attached,
            self._first,
            self._terms,
            np.ascontiguousarray(grad_slot, np.int64),
            *kernels.scatter_tables(
                np.ascontiguousarray(tangent_slot, np.int64).reshape(-1, 36), ends
            ),
        )

        def kernel(coordinates: np.ndarray, grad: np.ndarray, storage: np.ndarray) -> float:
            return assemble_elements(coordinates, *fixed, grad, storage)

        return kernel

    def assembler(
        self, gather: np.ndarray, grad_dofs: np.ndarray, hess_slots: np.ndarray
    ) -> Callable[[np.ndarray, np.ndarray, np.ndarray], float]:
        """The compiled kernel adding every element into the System's gradient and tangent.

        See :meth:`ConnectorGroup.assembler`; a node's (or its body's pose's)
        three coordinates are consecutive in ``[q, ground pose]``.
        """
        return self._kernel(gather[self._node_dof], grad_dofs[self._dofs], hess_slots)

    def predictor(
        self, gather: np.ndarray
    ) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[..., np.ndarray]]:
        """:meth:`predict_internal` on global coordinates (:meth:`ConnectorGroup.predictor`):
        the chains' (:meth:`flexval.reducedmodels.core.chains.NodeChains.predictor`)."""
        return self._chains.predictor(gather)

    def updater(self, gather: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        """:meth:`update_internal` on global coordinates (:meth:`ConnectorGroup.updater`)."""
        return self._chains.updater(gather)

    def evaluate(self, states: Sequence[LocalState]) -> tuple[float, np.ndarray, np.ndarray]:
        """Total strain energy (N mm), concatenated gradients and Hessian values.

        Per connector, as :meth:`BeamConnector.evaluate` documents: the
        internal forces conjugate to [pose_a, pose_b, internal] (N, N mm)
        and the values of its :meth:`~BeamConnector.hessian_pattern`.
        """
        gradient, hessian = np.zeros(self._n_local), np.zeros(36 * len(self._l0))
        kernel = self._kernel(self._node_dof, self._dofs, np.arange(hessian.size))
        energy = kernel(local_coordinates(states), gradient, hessian)
        return energy, gradient, hessian

    def path_end_pass(self, coordinates: np.ndarray) -> tuple[list[Reasons], list[SectionForces]]:
        """:meth:`path_validity` and :meth:`path_section_forces` from one compiled pass.

        ``coordinates`` as :meth:`ConnectorGroup.path_end_pass` says, read by
        the kernel as they are; each element's chord frame at each level
        serves both (:func:`flexval.reducedmodels.kernels.beamkernel.path_element_ends`).
        """
        ends = self._element_ends(coordinates)
        return self._verdicts(*ends), self._section_forces(*ends[2:])

    def path_validity(self, levels: Sequence[Sequence[LocalState]]) -> list[Reasons]:
        """Each connector's :meth:`BeamConnector.validity` at each level, in one compiled pass.

        Reasons are worded only for the (connector, level) pairs found invalid.
        """
        return self._verdicts(*self._element_ends(_levels(levels)))

    def path_section_forces(self, levels: Sequence[Sequence[LocalState]]) -> list[SectionForces]:
        """Each connector's :meth:`BeamConnector.section_forces` at k levels, stacked (k, m).

        Every element's end forces at every level in one compiled pass.
        """
        return self._section_forces(*self._element_ends(_levels(levels))[2:])

    def _element_ends(
        self, coordinates: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Every element's chord length, turn and end forces at each level (k, ...) each.

        ``coordinates`` (k, m): the local coordinates laid end to end at each
        level; see :func:`flexval.reducedmodels.kernels.beamkernel.path_element_ends`.
        """
        return beam_kernels().path_element_ends(
            coordinates,
            self._node_dof,
            self._node_rel,
            self._attached,
            self._first,
            self._tangent0,
            self._chord0,
            self._l0,
            self._k_axial,
            self._k11,
            self._k12,
            self._k22,
        )

    def _verdicts(
        self, lengths: np.ndarray, turns: np.ndarray, axial: np.ndarray, moment: np.ndarray
    ) -> list[Reasons]:
        """The validity reasons per connector and level from the elements' chord measures.

        A flexure whose section varies also has its outer-fibre strain
        (|N| / EA + |M| / (E b h^2 / 6) at every element's end nodes, from
        the element end forces ``axial`` and ``moment``) checked against
        MAX_STRAIN: its thinnest section reaches the limit in bending long
        before its elements stretch or turn that far.
        """
        strain = np.maximum.reduceat(np.abs(lengths / self._l0 - 1.0), self._element_start, axis=1)
        turn = np.maximum.reduceat(turns, self._element_start, axis=1)
        valid = ((strain <= MAX_STRAIN) & (turn <= MAX_CHORD_TURN)).T.tolist()
        fibres = [
            None
            if c._fibre_compliance is None
            else np.abs(axial[:, index]) * c._fibre_compliance[0]
            + np.abs(moment[:, index]) * c._fibre_compliance[1]
            for c, index in zip(self.connectors, self._section_index)
        ]
        ends = [*self._element_start[1:], lengths.shape[1]]
        return [
            [
                (
                    []
                    if ok
                    else (
                        stretch_reasons("element", length[e0:e1], c._l0)
                        + rotation_reasons("element", turn_e[e0:e1], MAX_CHORD_TURN)
                    )
                )
                + ([] if fibre is None else fibre_strain_reasons(fibre[level], c._section_s))
                for level, (ok, length, turn_e) in enumerate(zip(flags, lengths, turns))
            ]
            for c, flags, e0, e1, fibre in zip(
                self.connectors, valid, self._element_start, ends, fibres
            )
        ]

    def _section_forces(self, axial: np.ndarray, moment: np.ndarray) -> list[SectionForces]:
        """Each connector's stacked section forces from every element's end forces."""
        return [
            SectionForces(c._section_at.copy(), axial[:, index], moment[:, index])
            for c, index in zip(self.connectors, self._section_index)
        ]

    def predict_internal(
        self,
        past: Sequence[Sequence[LocalState]],
        weights: Sequence[float],
        poses: Sequence[tuple[np.ndarray, np.ndarray]],
    ) -> np.ndarray:
        """Concatenated interior nodes extrapolated in chord lengths and angles.

        As :meth:`BeamConnector.predict_internal` documents, for every
        flexure at once (:meth:`flexval.reducedmodels.core.chains.NodeChains.predict_internal`).
        """
        return self._chains.predict_internal(past, weights, poses)

    def update_internal(self, old: Sequence[LocalState], new: Sequence[LocalState]) -> np.ndarray:
        """Concatenated interior nodes after a Newton correction, chords turned, not sheared.

        As :meth:`BeamConnector.update_internal` documents, for every flexure
        at once (:meth:`flexval.reducedmodels.core.chains.NodeChains.update_internal`).
        """
        return self._chains.update_internal(old, new)


def fibre_strain_reasons(strain: np.ndarray, stations: np.ndarray) -> list[str]:
    """The largest outer-fibre strain beyond MAX_STRAIN and where it is (mm from the start)."""
    k = int(np.argmax(strain))
    if not strain[k] > MAX_STRAIN:
        return []
    return [
        f"outer fibre strained {100.0 * strain[k]:.3g} % at {stations[k]:.4g} mm from the "
        f"flexure's start, beyond the {100.0 * MAX_STRAIN:g} % strain limit"
    ]


def _starts(counts: Sequence[int]) -> list[int]:
    """Where each of consecutive runs of ``counts`` items starts (0, then running sums)."""
    starts, total = [], 0
    for count in counts:
        starts.append(total)
        total += count
    return starts


def evenly_spaced(stop: float, n: int) -> np.ndarray:
    """``numpy.linspace(0.0, stop, n + 1)`` (n >= 1), the same numbers at a fraction of the calls.

    linspace's own arithmetic, k * (stop / n) with the last value set to
    ``stop``; its generality (dtypes, axes, array bounds) cost more than the
    values on a flexure's few hundred nodes. Units: those of ``stop``.
    """
    values = np.arange(n + 1, dtype=float)
    values *= stop / n
    values[-1] = stop
    return values


def _block_pattern(element_dofs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of every element's row-major 6 x 6 block, from its coordinates (elements, 6)."""
    return (np.repeat(element_dofs, 6, axis=1).ravel(), np.tile(element_dofs, (1, 6)).ravel())


def _levels(levels: Sequence[Sequence[LocalState]]) -> np.ndarray:
    """The connectors' local coordinates laid end to end at k levels, (k, m) float.

    One concatenation of every level's parts (each level's own, then a
    stack of them, cost twice as much on a path's eleven levels).
    """
    parts = [part for states in levels for state in states for part in state]
    return np.concatenate(parts).astype(float, copy=False).reshape(len(levels), -1)


class BeamConnector(Connector):
    """Corotational beam model of one flexure with N elements
    (a :class:`~flexval.reducedmodels.core.connector.Connector`).

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

    update_above = 1e-7
    """Newton corrections go through :meth:`update_internal` (one compiled pass over the
    nodes) down to 1e-7 (scaled). Below :data:`~flexval.reducedmodels.core.newton.NONLINEAR_UPDATE`
    a
    linear update still stretches each turning chord by (turn)^2 / 2 and each end element
    by |rel| (dtheta)^2 / 2 of its body's turn, and the axial stiffness makes that force
    many times the load: on the paper paths of beam:100 a correction of 5e-4 left a
    residual of 1.8 loads and an extra iteration (Newton iterations of open f-, closed
    f+, open m+: 125, 33, 26 with linear updates below 1e-3, 98, 29, 23 always updated).
    Below 1e-7, mostly a sub-step's last correction, the update is not worth its pass
    (a chord turns by at most 1e-7 size / l0: 1.4e-10 of stretch on beam:100's
    elements): the same iterations on the 12 paper beam paths as with 0 (1e-6: one
    more, 1e-5: three), on open f+/f- with beam:500 27/83 and beam:2000 33/127
    (with 0: 27/85, 34/127)."""

    def __init__(
        self, flexure: Flexure, mechanism: Mechanism, n_elements: int, shear: bool = False
    ):
        if n_elements < 1:
            raise ValueError(f"beam: number of elements must be >= 1, got {n_elements}")
        self.name = flexure.name
        self.bodies = tuple(flexure.bodies)
        self.n_internal = 3 * (n_elements - 1)
        self._n_nodes = n_elements + 1
        length = flexure.shape.length
        section = flexure.section
        if section.is_uniform:
            self._nodes0 = flexure.shape.point(evenly_spaced(length, n_elements))
            self._node_fractions = evenly_spaced(1.0, n_elements)
            stations = self._node_fractions * length
        else:  # elements graded by the section (beamvarying.graded_stations)
            stations = graded_stations(flexure.shape, section, n_elements)
            self._nodes0 = flexure.shape.point(stations)
            self._node_fractions = stations / length
        # section forces at every element's start then end node, in arc-length order
        at = np.concatenate([self._node_fractions[:-1], self._node_fractions[1:]])
        self._section_order = np.argsort(at, kind="stable")
        self._section_at = at[self._section_order]
        self._node_tangent0 = flexure.shape.tangent_angle(stations)
        chord = self._nodes0[1:] - self._nodes0[:-1]
        l0 = np.hypot(chord[:, 0], chord[:, 1])
        self._l0 = l0
        self._chord0 = chord / l0[:, None]
        material = mechanism.material
        shear = shear or material.shear_flexible
        if section.is_uniform:
            self._k_axial = flexure.axial_stiffness(material) / l0
            bending = flexure.bending_stiffness(material)
            self._flexibility = l0 / bending  # 1/(N mm)
            shear_stiffness = (
                SHEAR_CORRECTION * material.shear_modulus * section.area if shear else None
            )
            self._k11, self._k12 = bending_stiffness_terms(bending, l0, shear_stiffness)
            self._k22 = self._k11
            self._piece_lengths = np.full(n_elements, length / n_elements)
            self._line_area = section.area
            self._fibre_compliance = None
        else:  # each element's stiffness integrated over its arc (beamvarying.element_stiffness)
            stiffness = element_stiffness(
                section, material, stations, l0, SHEAR_CORRECTION if shear else None
            )
            self._k_axial, self._flexibility = stiffness.k_axial, stiffness.bending_flexibility
            self._k11, self._k12, self._k22 = stiffness.k11, stiffness.k12, stiffness.k22
            self._piece_lengths = np.diff(stations)
            self._line_area = stiffness.mean_area
            # outer-fibre strain per |N| and per |M| at the section stations, 1/N and 1/(N mm)
            self._section_s = self._section_at * length
            h = section.thickness_at(self._section_s)
            E = material.youngs_modulus
            self._fibre_compliance = (
                1.0 / (E * section.area_at(self._section_s)),
                6.0 / (E * section.depth * h * h),
            )
        # which pose (0: pose_a, 1: pose_b) carries the start node and the end node
        self._end_pose = (
            self.bodies.index(flexure.start_body),
            self.bodies.index(flexure.end_body),
        )
        self._end_rel = np.array(
            [
                self._nodes0[0] - mechanism.bodies[flexure.start_body].reference,
                self._nodes0[-1] - mechanism.bodies[flexure.end_body].reference,
            ]
        )
        self._end_offsets = tuple(map(tuple, self._end_rel.tolist()))

    @functools.cached_property
    def _alone(self) -> BeamGroup:
        """This connector as a group of one (its own evaluation; a System builds its groups)."""
        return BeamGroup([self])

    def _node_dof_table(self) -> np.ndarray:
        """Local coordinate numbers of each node's (x, y, theta), (N + 1, 3).

        The end nodes take their body's pose slots (0..2 for pose_a, 3..5 for
        pose_b): they are transported there by the element kernel
        (:func:`flexval.reducedmodels.kernels.beamkernel.attach`).
        """
        node_dofs = np.empty((self._n_nodes, 3), dtype=np.int64)
        node_dofs[0] = 3 * self._end_pose[0] + np.arange(3)
        node_dofs[-1] = 3 * self._end_pose[1] + np.arange(3)
        node_dofs[1:-1] = 6 + np.arange(self.n_internal).reshape(-1, 3)
        return node_dofs

    def mass_points(self, density: float) -> MassPoints:
        """The flexure's mass (density in t/mm^3) lumped on the nodes (HRZ rule).

        Lumped rather than consistent: each node's mass is a point mass with
        its own rotary inertia on the node's (x, y, theta), so the kinetic
        energy stays exact and frame-independent at any rotation (a
        consistent Hermite mass would have to turn with each chord). Each
        element gives m/2 and m l^2/78 to each end node
        (:func:`flexval.reducedmodels.core.inertia.chain_mass_points`), m the
        density times the integral of A(s) over its arc, l the arc's length;
        the end nodes' masses sit on the end bodies at the flexure's end points.
        """
        n = self._n_nodes - 1
        frames = [np.arange(3 * s, 3 * s + 3) for s in self._end_pose]
        node_dofs = [frames[0], *(6 + np.arange(self.n_internal).reshape(-1, 3)), frames[1]]
        rel = np.zeros((n + 1, 2))
        rel[0], rel[-1] = self._end_rel
        return chain_mass_points(node_dofs, rel, self._piece_lengths, density * self._line_area)

    def initial_internal(self) -> np.ndarray:
        """Interior nodes at rest: (x, y, 0) each, mm and rad."""
        inner = self._nodes0[1:-1]
        return np.column_stack([inner, np.zeros(len(inner))]).ravel()

    def internal_is_rotation(self) -> np.ndarray:
        """Every third internal coordinate (the nodal rotation) is an angle."""
        return np.tile([False, False, True], self.n_internal // 3)

    def _nodes(
        self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
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
        """Local (rows, cols) of the Hessian values :meth:`evaluate` returns (duplicates sum).

        Each element's row-major 6 x 6 block over its two nodes' coordinates.
        """
        return self._pattern

    @functools.cached_property
    def _pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`hessian_pattern`, built on first use (a System asks its :class:`BeamGroup`)."""
        node_dofs = self._node_dof_table()
        return _block_pattern(np.hstack([node_dofs[:-1], node_dofs[1:]]))

    def evaluate(
        self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Strain energy (N mm), gradient (6 + n_internal) and Hessian values.

        The gradient holds the internal forces conjugate to
        [pose_a, pose_b, internal] (N on translations, N mm on rotations);
        the consistent tangent is returned as the values of the entries of
        :meth:`hessian_pattern` (duplicates summed).
        """
        return self._alone.evaluate([(pose_a, pose_b, internal)])

    @classmethod
    def group(cls, connectors: Sequence[BeamConnector]) -> BeamGroup:
        """All the connectors' elements evaluated in one vectorised call (:class:`BeamGroup`)."""
        return BeamGroup(connectors)

    def predict_internal(
        self,
        states: Sequence[LocalState],
        weights: Sequence[float],
        pose_a: np.ndarray,
        pose_b: np.ndarray,
    ) -> np.ndarray:
        """Interior nodes extrapolated in chord lengths and angles (for the load stepping).

        Each element's chord length and direction and each node's rotation
        are extrapolated with ``weights`` over the converged ``states``; the
        chain is then rebuilt from the start body's end node (at its pose
        in ``pose_a``/``pose_b``) and closed at the end body's node by the
        flexure's own least-energy bending
        (:func:`flexval.reducedmodels.kernels.chainkernel.close_chains`). Extrapolating node
        positions instead would shorten every chord that turns, and the
        axial stiffness turns that O(h^2) error into forces far larger than
        the load (tens of Newton iterations on slender flexures); so would
        closing the chain by a uniform stretch.
        """
        return self._alone.predict_internal(
            [[state] for state in states], weights, [(pose_a, pose_b)]
        )

    def update_internal(self, old: LocalState, new: LocalState) -> np.ndarray:
        """Interior nodes after a Newton correction, with chords turned instead of sheared.

        ``new`` is the linearly corrected state. Each chord's change is split
        into its stretch (along the old chord) and its turn (across it,
        divided by the length), and the chord is rebuilt with that length
        and direction exactly (an end node's change as Newton linearises
        its body's turn); the chain is then closed between the end bodies'
        nodes as in :meth:`predict_internal`. This agrees with the linear
        update to first order, so Newton keeps its quadratic convergence,
        but a turning chord does not come out stretched by (turn)^2 / 2, as
        after a linear update, which EA would turn into spurious forces.
        """
        return self._alone.update_internal([old], [new])

    def validity(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> list[str]:
        """Reasons: element stretch over MAX_STRAIN, end turns from the chord over MAX_CHORD_TURN.

        See :mod:`flexval.reducedmodels.core.validity`: the first is material strain, the
        second an element too coarse for the curvature it carries. A varying
        section adds its outer-fibre strain over MAX_STRAIN (at the element
        ends, with h(s) there: :meth:`BeamGroup.path_validity`).
        """
        return self.path_validity([(pose_a, pose_b, internal)])[0]

    def path_validity(self, states: Sequence[LocalState]) -> Reasons:
        """:meth:`validity` at k states, in one compiled pass (:meth:`BeamGroup.path_validity`)."""
        return self._alone.path_validity([[state] for state in states])[0]

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Deformed node positions (N + 1, 2), mm, from the flexure's start to its end."""
        return self._nodes(pose_a, pose_b, internal)[0]

    def section_forces(
        self,
        pose_a: np.ndarray,
        pose_b: np.ndarray,
        internal: np.ndarray,
        gradient: np.ndarray | None = None,
    ) -> SectionForces:
        """Normal force (N) and bending moment (N mm) at both end nodes of every element.

        Each element's own end forces (its internal-force vector at each
        node), so a load inside the flexure (its weight) is accounted for.
        The section axis at a node is the initial tangent turned by the
        node's rotation. ``gradient`` (a linear response's K0 dq) gives the
        forces by statics of the end wrench instead, along the nodes.
        """
        if gradient is not None:
            x, theta = self._nodes(pose_a, pose_b, internal)
            slot = self._end_pose[1]
            return statics_section_forces(
                x,
                self._node_fractions,
                gradient[3 * slot : 3 * slot + 3],
                (pose_a, pose_b)[slot],
                axes=unit_vectors(self._node_tangent0 + theta),
            )
        forces = self.path_section_forces([(pose_a, pose_b, internal)])
        return SectionForces(forces.at, forces.axial[0], forces.moment[0])

    def path_section_forces(self, states: Sequence[LocalState]) -> SectionForces:
        """:meth:`section_forces` at k states (a load path), stacked (k, m), in one
        compiled pass."""
        return self._alone.path_section_forces([[state] for state in states])[0]
