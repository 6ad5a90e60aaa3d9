"""3R pseudo-rigid-body model ``prbm`` of arcs and straight beams (paper Sect. 2.2).

Which flexures it models (:func:`prbm_connector`): uniform arcs and
segments; tapered ones by the same chain built on their own ellipse of
elasticity (:func:`tapered_frame`); a notch hinge by the classic one-pivot
model (:mod:`flexval.reducedmodels.prbm.pivot`); a free-form (spline) centre
line not at all: it is refused with a SceneError that names the flexure and
points to ``beam``, ``dcmm`` and ``continuum``.

Each flexure joining bodies a and b becomes the serial chain

    a --R_a-- link h --R_2-- link l --R_b-- b

of two rigid links and three revolute joints with torsion springs k1, k2,
k1, placed on the flexure's ellipse of elasticity so that the chain's linear
compliance is the flexure's exactly; one share rho per arc angle, fitted
offline to a nonlinear beam (``benchmarks/calibrate_prbm.py``, shipped in
``data/prbm_table.json`` and interpolated in the arc angle), fixes the joints
and springs. The internal coordinates are the two links' rotations (rad), in
which the joint rotations are linear (no angle wrapping), and a closure
multiplier mu (2, mm) that closes the chain exactly at R_b: inverse
kinematics would make the joint angles singular where the chain is stretched
straight, as a straight beam's chain is at rest. The derivation (exactness
conditions, joints, Lagrangian) is in the documentation's models page,
``prbm``, its tapered chain under "Other shapes and varying sections".

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import cache
from types import ModuleType

import numpy as np

from flexval.geometry import Flexure, Mechanism
from flexval.geometry.kinematics import rotate_xy
from flexval.geometry.shapes import Shape

from ..core.connector import Connector, KernelEndPass, Reasons
from ..core.geometrycache import per_centre_line
from ..core.inertia import MassPoints, line_density, rigid_pieces
from ..core.sections import ForceStack, SectionForces, column_stacks, polyline_fractions
from ..core.validity import MAX_STRAIN, SCREEN_MARGIN, rotation_reasons, stretch_reasons
from .parameters import (
    PrbmParameters,
    fitted_rotation,
    joint_positions,
    local_joints,
    table_parameters,
    table_rho,
    tapered_frame,
)


def prbm_connector(flexure: Flexure, mechanism: Mechanism, **options) -> Connector:
    """The ``prbm`` connector of one flexure: the 3R chain, or a notch hinge's pivot.

    Arcs and segments, uniform or tapered, take :class:`PrbmConnector`; a
    notch hinge takes the one-pivot model
    (:class:`flexval.reducedmodels.prbm.pivot.NotchPivotConnector`).

    Raises
    ------
    ValueError
        For a free-form (spline) centre line, which has no pseudo-rigid-body
        model here (its flexibility is not lumped at a few joints without a
        calibration of its own), or options a notch pivot does not take.
    """
    if flexure.shape.kind == "spline":
        raise ValueError(
            f"prbm has no pseudo-rigid-body model of the free-form (spline) flexure "
            f"{flexure.name!r}: use beam, dcmm or continuum for it"
        )
    profile = flexure.section.profile
    if profile is not None and profile.kind == "notch":
        if options:
            raise ValueError(
                f"prbm: the notch hinge's pivot model takes no options, got {sorted(options)}"
            )
        from .pivot import NotchPivotConnector

        return NotchPivotConnector(flexure, mechanism)
    return PrbmConnector(flexure, mechanism, **options)


@cache
def prbm_kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.prbmkernel`; each kernel is compiled, or loaded
    from the on-disk cache, where it is first called, off the path's clock
    (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import prbmkernel

    return prbmkernel


_LOCAL = np.arange(10, dtype=np.int64)[None]
"""A single chain's identity gather and gradient slots (its own local coordinates)."""


def _hessian_pattern() -> tuple[np.ndarray, np.ndarray]:
    """Local (rows, cols) of the PRBM Hessian entries, in the order
    :meth:`PrbmConnector.evaluate` fills them.

    Springs and gap curvature on the angles (theta_a 2, theta_b 5, phi_h 6,
    phi_l 7): the chain theta_a - phi_h - phi_l - theta_b is tridiagonal.
    Then c G in the mu rows (8, 9) and c G^T in the mu columns: +-c on the
    translations, the four angle columns of G.
    """
    springs = [(2, 2), (2, 6), (6, 2), (6, 6), (6, 7), (7, 6), (7, 7), (7, 5), (5, 7), (5, 5)]
    translation = [(8, 0), (8, 3), (9, 1), (9, 4)]
    angles = [(8, 2), (8, 5), (8, 6), (8, 7), (9, 2), (9, 5), (9, 6), (9, 7)]
    pairs = springs + translation + angles + [(j, i) for i, j in translation + angles]
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])


_HESSIAN_ROWS, _HESSIAN_COLS = _hessian_pattern()


def _station_order(rest: list, fractions: list, forward: bool) -> tuple[np.ndarray, np.ndarray]:
    """Arc-length fractions of the section-force stations from the flexure's first end and
    their places among the polyline's segment ends, in increasing order.

    The stations are both ends of each polyline segment (places k and 4 + k
    of segment k in :func:`flexval.reducedmodels.kernels.prbmkernel.chain_statics`); a
    segment of zero length at rest (two points of one rigid member that
    coincide) has none. Plain floats: five points.
    """
    kept = [k for k in range(len(rest) - 1) if rest[k] != rest[k + 1]]
    where = kept + [4 + k for k in kept]
    at = [fractions[k] for k in kept] + [fractions[k + 1] for k in kept]
    if not forward:
        at = [1.0 - a for a in at]
    order = sorted(range(len(at)), key=at.__getitem__)  # stable, as argsort's
    return (np.array([at[k] for k in order]), np.array([where[k] for k in order], np.int64))


def _geometry(shape: Shape, joints: tuple | PrbmParameters, forward: bool, refs: tuple) -> dict:
    """A chain's geometry at rest (mm): its joints and flexure ends in chain order, the
    offsets and link vectors as float pairs, the polyline, its fractions and stations.
    ``joints``: in the centre line's order (mm), or the parameters that place them on a
    uniform one (:func:`joint_positions`)."""
    if isinstance(joints, PrbmParameters):
        joints = joint_positions(shape, joints)
    joints, ends = np.array(joints), shape.end_points  # [start, end]
    if not forward:
        joints, ends = joints[::-1], ends[::-1]
    reference = np.array(refs)
    # joint offsets from the body references, link vectors and the flexure ends' offsets,
    # as float pairs (mm; plain floats: a few numbers)
    (ra, r2, rb), (ea, eb), (fa, fb) = joints.tolist(), ends.tolist(), reference.tolist()
    rest = np.array([ea, ra, r2, rb, eb])  # polyline, mm
    fractions = polyline_fractions(rest)
    stations = _station_order(rest.tolist(), fractions.tolist(), forward)
    for array in (joints, ends, reference, rest, fractions, *stations):
        array.flags.writeable = False
    return {
        "joints": joints,  # [R_a, R_2, R_b], chain order a -> b
        "_ref": reference,
        "_ends": ends,  # flexure end points on a and b
        "_r_a": (ra[0] - fa[0], ra[1] - fa[1]),
        "_r_b": (rb[0] - fb[0], rb[1] - fb[1]),
        "_v_h": (r2[0] - ra[0], r2[1] - ra[1]),
        "_v_l": (rb[0] - r2[0], rb[1] - r2[1]),
        "_end_rel_a": (ea[0] - fa[0], ea[1] - fa[1]),
        "_end_rel_b": (eb[0] - fb[0], eb[1] - fb[1]),
        "_rest": rest,
        "_fractions": fractions,
        "_stations": stations,
    }


_kept_geometry = per_centre_line(_geometry)


def _chain_geometry(
    shape: Shape, joints: np.ndarray | PrbmParameters, forward: bool, refs: tuple
) -> dict:
    """:func:`_geometry`, kept per centre line; ``joints`` (3, 2) in the centre line's order
    (mm), or the parameters of a uniform one."""
    key = joints if isinstance(joints, PrbmParameters) else tuple(map(tuple, joints.tolist()))
    return _kept_geometry(shape, key, forward, refs)


class PrbmConnector(Connector):
    """Symmetric 3R PRBM of one flexure (a
    :class:`~flexval.reducedmodels.core.connector.Connector`).

    Internal coordinates: [phi_h, phi_l, mu_x, mu_y], the rotations (rad) of
    link h (at body a) and link l (at body b) from the initial configuration
    and the closure multiplier (mm); see the module docstring.

    Parameters
    ----------
    flexure : Flexure
    mechanism : Mechanism
        For the material and the bodies' reference points.
    params : PrbmParameters or mapping, optional
        Chain parameters. A mapping is either ``{"rho": value}`` (the
        exact-linear family at this flexure's angle with that rho, e.g. for
        sensitivity studies; JSON-friendly, so it can travel through
        ``run_reduced(..., params=...)``) or the five fields of
        :class:`PrbmParameters`. Default: the fitted table at the flexure's
        arc angle.
    """

    def __init__(
        self,
        flexure: Flexure,
        mechanism: Mechanism,
        params: PrbmParameters | Mapping[str, float] | None = None,
    ):
        self.name = flexure.name
        self.bodies = tuple(flexure.bodies)
        self.n_internal = 4
        self.n_multipliers = 2  # the closure multiplier mu
        shape = flexure.shape
        length, width = shape.length, shape.width
        if flexure.section.is_uniform:
            if params is None:
                params = table_parameters(width)
            elif not isinstance(params, PrbmParameters):
                params = (
                    PrbmParameters.from_rho(width, float(params["rho"]))
                    if set(params) == {"rho"}
                    else PrbmParameters(**params)
                )
            EI = flexure.bending_stiffness(mechanism.material)
            stiffness = [
                params.kappa1 * EI / length,
                params.kappa2 * EI / length,
                params.kappa1 * EI / length,
            ]
            self.closure_scale = EI / length**3
            joints = params  # placed on the centre line by _chain_geometry
        else:  # a taper: the chain of the tapered ellipse, with the rho of the arc's angle
            if params is None:
                rho = table_rho(width)
            elif not isinstance(params, PrbmParameters) and set(params) == {"rho"}:
                rho = float(params["rho"])
            else:
                raise ValueError(
                    "prbm: a tapered flexure's chain follows from its ellipse and rho "
                    f"alone; give params={{'rho': value}}, not {params!r}"
                )
            frame = tapered_frame(flexure, mechanism.material)
            params = PrbmParameters.from_semi_axes(frame.a, frame.b, rho)
            # kappa EI / L with EI / L -> 1 / w, w = ∫ ds / EI (equal for a uniform section)
            stiffness = [params.kappa1 / frame.w, params.kappa2 / frame.w, params.kappa1 / frame.w]
            self.closure_scale = 1.0 / (frame.w * length**2)
            joints = frame.center + length * local_joints(params) @ frame.axes
        self.params = params
        self.stiffness = np.array(stiffness)
        self._forward = flexure.start_body == self.bodies[0]
        refs = tuple(tuple(mechanism.bodies[b].reference.tolist()) for b in self.bodies)
        self.__dict__.update(_chain_geometry(shape, joints, self._forward, refs))
        self.length = length
        #: a straight leaf's joints lie on its line: its rigid links hold the axis at rest
        self._axis = None
        if shape.kind == "segment":
            start, end = shape.end_points
            self._axis = (start, (end - start) / length)
        # the parameters of flexval.reducedmodels.kernels.prbmkernel.chain
        self._parameters = np.array(
            [*self._r_a, *self._r_b, *self._v_h, *self._v_l, *stiffness, self.closure_scale]
        )
        self._fitted_rotation = fitted_rotation()
        self._section = flexure.section
        self._shape = shape

    def rigid_directions(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """A straight leaf's axis (a point on it, mm, and its unit direction): its three joints
        lie on one line, so the rigid links hold the leaf inextensible at rest; an arc's chain
        holds nothing rigid."""
        return [] if self._axis is None else [self._axis]

    def mass_points(self, density: float) -> MassPoints:
        """The flexure's mass (density in t/mm^3) on the chain's four rigid members.

        Lumping rule: the flexure is cut where the undeformed polyline
        end_a, R_a, R_2, R_b, end_b reaches each joint (by length fraction;
        on a straight beam, at the joints themselves), and each piece rides
        rigidly, with its exact mass, centre of mass and rotary inertia
        (:func:`flexval.reducedmodels.core.inertia.rigid_pieces`), on the member that
        spans it: end body a, link h (hinged at R_a, turning with phi_h),
        link l (hinged at R_b, turning with phi_l), end body b. So the
        pseudo-links' angles carry inertia and the chain moves as the rigid
        members it is made of. On a clamped-free beam f1 comes out +0.02 %
        from Euler-Bernoulli (HRZ lumping on the end bodies only: -32 %) and
        the self-weight sag is exact in the linear limit (the symmetric chain
        matches the beam's compliance moments up to the third); see the
        documentation's frequency comparison.
        """
        bounds = self._fractions * self.length
        hinges = np.array([self._ref[0], self.joints[0], self.joints[2], self._ref[1]])
        mass, rel, rotary = rigid_pieces(
            self._shape, self._forward, bounds, hinges, line_density(density, self._section)
        )
        on_link = np.array([0.0, 1.0, 1.0, 0.0])[:, None]
        hinge_rel = np.array([[0.0, 0.0], self._r_a, self._r_b, [0.0, 0.0]])
        return MassPoints(
            dofs=np.array([np.arange(3), np.arange(3), np.arange(3, 6), np.arange(3, 6)]),
            rel=on_link * hinge_rel + (1.0 - on_link) * rel,
            mass=mass,
            rotary=rotary,
            link=np.array([-1, 6, 7, -1]),
            link_rel=on_link * rel,
        )

    def internal_is_rotation(self) -> np.ndarray:
        """[True, True, False, False]: two link rotations, then the multiplier (mm)."""
        return np.array([True, True, False, False])

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """Local (rows, cols) of the Hessian values :meth:`evaluate` returns
        (see _HESSIAN_PATTERN)."""
        return _HESSIAN_ROWS, _HESSIAN_COLS

    @classmethod
    def group(cls, connectors) -> PrbmGroup:
        """The PRBM connectors of a run, evaluated into one array of each kind
        (:class:`PrbmGroup`)."""
        return PrbmGroup(connectors)

    def evaluate(
        self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Lagrangian (N mm), gradient (10) and Hessian values over [pose_a, pose_b, internal].

        Local order: [x_a, y_a, theta_a, x_b, y_b, theta_b, phi_h, phi_l, mu_x, mu_y];
        the values of :func:`flexval.reducedmodels.kernels.prbmkernel.chain` in the order of
        :meth:`hessian_pattern`.
        """
        kernels = prbm_kernels()
        gradient, hessian = np.zeros(10), np.zeros(kernels.HESSIAN_VALUES)
        energy = kernels.assemble_chains(
            np.concatenate([pose_a, pose_b, internal]),
            _LOCAL,
            self._parameters[None],
            _LOCAL,
            np.arange(kernels.HESSIAN_VALUES, dtype=np.int64)[None],
            gradient,
            hessian,
        )
        return energy, gradient, hessian

    def validity(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> list[str]:
        """Flexure ends farther apart than its length allows; end rotation beyond the fitted range.

        The rigid links cannot stretch, but the chain's end-to-end span can
        exceed the flexure's length L, which a real flexure reaches only by
        straining: a chord longer than L (1 + MAX_STRAIN) is refused as in
        DCMM. The chain's parameters are fitted on end rotations up to
        :func:`fitted_rotation`; beyond it the model extrapolates. See
        :mod:`flexval.reducedmodels.core.validity`. (Plain floats: it runs at every level.)
        """
        (xa, ya, ta), (xb, yb, tb) = pose_a.tolist(), pose_b.tolist()
        ea, eb = rotate_xy(ta, *self._end_rel_a), rotate_xy(tb, *self._end_rel_b)
        chord = math.hypot(xb + eb[0] - xa - ea[0], yb + eb[1] - ya - ea[1])
        turn = tb - ta
        if chord / self.length - 1.0 <= MAX_STRAIN and abs(turn) <= self._fitted_rotation:
            return []
        return stretch_reasons(
            "chord", np.array([chord]), np.array([self.length]), one_sided=True
        ) + rotation_reasons("end rotation", np.array([turn]), self._fitted_rotation)

    def path_validity(self, states) -> Reasons:
        """:meth:`validity` at k states, screened in one vectorised pass
        (:meth:`PrbmGroup.path_validity`)."""
        return PrbmGroup([self]).path_validity([[state] for state in states])[0]

    def shape(self, pose_a: np.ndarray, pose_b: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """Polyline end_a, R_a, R_2, R_b, end_b in the current configuration, (5, 2) mm."""
        return PrbmGroup([self]).polylines([[(pose_a, pose_b, internal)]])[0, 0]

    def section_forces(
        self,
        pose_a: np.ndarray,
        pose_b: np.ndarray,
        internal: np.ndarray,
        gradient: np.ndarray | None = None,
    ) -> SectionForces:
        """Normal force (N) and bending moment (N mm) along the displaced links.

        The chain transmits one wrench (the gradient on body b's pose,
        closure multiplier included), carried by statics along the polyline
        end_a, R_a, R_2, R_b, end_b; fractions are those of the undeformed
        polyline.
        """
        group, state = PrbmGroup([self]), (pose_a, pose_b, internal)
        if gradient is not None:
            return group.section_forces([state], [gradient])[0]
        forces = group.path_section_forces([[state]])[0]
        return SectionForces(forces.at, forces.axial[0], forces.moment[0])

    def path_section_forces(self, states) -> SectionForces:
        """:meth:`section_forces` at k states (a load path), stacked (k, m), in one pass."""
        return PrbmGroup([self]).path_section_forces([[state] for state in states])[0]


class PrbmGroup(KernelEndPass):
    """PRBM connectors evaluated together (:meth:`PrbmConnector.group`).

    Every chain of the run is evaluated by one call of the compiled
    :func:`flexval.reducedmodels.kernels.prbmkernel.assemble_chains`, which adds the results
    straight into the System's gradient and tangent storage
    (:meth:`assembler`), in the order of the connector-by-connector
    evaluation. A load path's validity and section forces use the
    polylines of all the connectors at all the levels, computed in one set
    of array operations (:meth:`polylines`).
    """

    compiled = True

    def __init__(self, connectors):
        super().__init__(connectors)
        rows: dict[int, int] = {}  # each distinct connector's row (a batch's copies share theirs)
        first, row_of = [], []
        for c in self.connectors:
            row = rows.get(id(c._parameters))
            if row is None:
                row = rows[id(c._parameters)] = len(first)
                first.append(c)
            row_of.append(row)
        # every connector's row; None: each its own (a path's few connectors)
        take = None if len(first) == len(self.connectors) else np.array(row_of, np.intp)

        def table(values: list) -> np.ndarray:
            return np.array(values) if take is None else np.array(values)[take]

        #: the distinct connectors, and each connector's among them
        self._distinct, self._kinds = first, np.arange(len(first)) if take is None else take
        self._parameters = table([c._parameters for c in first])
        self._end_rel = table([(*c._end_rel_a, *c._end_rel_b) for c in first])
        #: each connector's length (mm) and fitted end rotation (rad), for the validity screen
        self._lengths = table([c.length for c in first])
        self._fitted = table([c._fitted_rotation for c in first])

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of the chains' Hessian values laid end to end (see the base class):
        every chain's ten local coordinates have the one pattern of
        :meth:`PrbmConnector.hessian_pattern`, shifted by ten a chain."""
        starts = 10 * np.arange(len(self.connectors), dtype=np.int64)[:, None]
        return (_HESSIAN_ROWS + starts).ravel(), (_HESSIAN_COLS + starts).ravel()

    def assembler(
        self, gather: np.ndarray, grad_dofs: np.ndarray, hess_slots: np.ndarray
    ) -> Callable[[np.ndarray, np.ndarray, np.ndarray], float]:
        """The compiled kernel adding every chain into the System's gradient and tangent.

        See :meth:`ConnectorGroup.assembler`: each connector has ten local
        coordinates and :data:`flexval.reducedmodels.kernels.prbmkernel.HESSIAN_VALUES` Hessian
        values.
        """
        kernels = prbm_kernels()
        chains = len(self.connectors)
        fixed = (
            np.ascontiguousarray(gather, np.int64).reshape(chains, 10),
            self._parameters,
            np.ascontiguousarray(grad_dofs, np.int64).reshape(chains, 10),
            np.ascontiguousarray(hess_slots, np.int64).reshape(chains, kernels.HESSIAN_VALUES),
        )
        assemble_chains = kernels.assemble_chains

        def add(coordinates: np.ndarray, grad: np.ndarray, storage: np.ndarray) -> float:
            return assemble_chains(coordinates, *fixed, grad, storage)

        return add

    def _local(self, levels) -> np.ndarray:
        """Every connector's local coordinates at each of k levels, (k, c, 10)."""
        return np.concatenate([x for states in levels for state in states for x in state]).reshape(
            len(levels), len(self.connectors), 10
        )

    def polylines(self, levels) -> np.ndarray:
        """Each connector's polyline end_a, R_a, R_2, R_b, end_b at k levels, (k, c, 5, 2) mm.

        ``levels`` holds, for each level, the connectors' local states in
        order; one compiled call (:func:`flexval.reducedmodels.kernels.prbmkernel.chain_polylines`).
        """
        return prbm_kernels().chain_polylines(self._local(levels), self._parameters, self._end_rel)

    def _end_pass(self, coordinates: np.ndarray) -> tuple[list[Reasons], np.ndarray, np.ndarray]:
        """The verdicts, and the kernel's normal forces and moments (k, c, 8), of the levels.

        ``coordinates`` (k, 10 c): the connectors' local coordinates at each
        level (:meth:`ConnectorGroup.path_end_pass`), which are this group's
        (k, c, 10) table; the polylines are computed once for the validity
        screen and the statics, and local states are made only for the pairs
        the screen sends to the scalar check.
        """
        local = coordinates.reshape(len(coordinates), len(self.connectors), 10)
        kernels = prbm_kernels()
        lines = kernels.chain_polylines(local, self._parameters, self._end_rel)
        verdicts = self._verdicts(local, lambda: self.local_levels(coordinates), lines)
        wrenches = kernels.chain_wrenches(local, self._parameters)
        return (verdicts, *kernels.line_statics(local, lines, wrenches))

    def path_validity(self, levels) -> list[Reasons]:
        """Each connector's :meth:`PrbmConnector.validity` at each level, screened in one pass.

        Only (level, connector) pairs whose chord stretch or end rotation
        comes within :data:`~flexval.reducedmodels.core.validity.SCREEN_MARGIN` of its
        limit (or beyond) are judged by the scalar check.
        """
        return self._verdicts(self._local(levels), lambda: levels)

    def _verdicts(
        self, local: np.ndarray, levels_of: Callable[[], list], lines: np.ndarray | None = None
    ) -> list[Reasons]:
        """:meth:`path_validity` from the (k, c, 10) table; ``levels_of()`` gives
        the local states, ``lines`` the polylines if computed already."""
        if lines is None:
            lines = prbm_kernels().chain_polylines(local, self._parameters, self._end_rel)
        chord = lines[:, :, 4] - lines[:, :, 0]
        turn = np.abs(local[..., 5] - local[..., 2])
        near = (
            np.hypot(chord[..., 0], chord[..., 1]) / self._lengths - 1.0
            > MAX_STRAIN - SCREEN_MARGIN
        ) | (turn > self._fitted - SCREEN_MARGIN)
        valid = ((),) * len(local)  # no reason at any level: one shared, immutable
        out: list[Reasons] = [valid] * len(self.connectors)
        screened = np.flatnonzero(near.any(axis=0)).tolist()  # connectors near a limit somewhere
        if screened:
            levels = levels_of()
            for j in screened:
                c = self.connectors[j]
                out[j] = [
                    c.validity(*states[j]) if flag else []
                    for states, flag in zip(levels, near[:, j].tolist())
                ]
        return out

    def path_section_forces(self, levels) -> list[SectionForces]:
        """Each connector's :meth:`PrbmConnector.section_forces` at k levels, stacked (k, m).

        Every connector's wrench and statics at every level in two compiled
        calls (:func:`flexval.reducedmodels.kernels.prbmkernel.chain_wrenches`,
        :func:`flexval.reducedmodels.kernels.prbmkernel.chain_statics`).
        """
        return self._forces(self._local(levels))

    def _forces(self, local: np.ndarray) -> list[SectionForces]:
        """:meth:`path_section_forces` from the (k, c, 10) table."""
        kernels = prbm_kernels()
        wrenches = kernels.chain_wrenches(local, self._parameters)
        return self._split(*kernels.chain_statics(local, self._parameters, self._end_rel, wrenches))

    def section_forces(self, states, gradients) -> list[SectionForces]:
        """Each connector's :meth:`PrbmConnector.section_forces` with a known gradient, in one call.

        The wrench is the gradient on body b's pose (entries 3-5).
        """
        wrenches = np.array([np.asarray(g, float)[3:6] for g in gradients])[None]
        axial, moment = prbm_kernels().chain_statics(
            self._local([states]), self._parameters, self._end_rel, wrenches
        )
        return [SectionForces(f.at, f.axial[0], f.moment[0]) for f in self._split(axial, moment)]

    def _split(self, axial: np.ndarray, moment: np.ndarray) -> list[SectionForces]:
        """Each connector's section forces (k, m) from the kernel's (k, c, 8), at its stations
        (a path's few connectors; a batch's are stacked: :meth:`_stacks`)."""
        return [
            SectionForces(at, axial[:, j, where], moment[:, j, where])
            for j, (at, where) in enumerate(c._stations for c in self.connectors)
        ]

    def _stacks(self, axial: np.ndarray, moment: np.ndarray) -> list[ForceStack]:
        """The connectors' section forces from the kernel's (k, c, 8), stacked by stations
        (:func:`~flexval.reducedmodels.core.sections.column_stacks`).

        A connector's stations are both ends of each polyline segment, in
        arc-length order from the flexure's first end; a segment of zero
        length at rest (two points of one rigid member that coincide) has none.
        """
        width = axial.shape[2]
        return column_stacks(
            axial.reshape(len(axial), -1),
            moment.reshape(len(moment), -1),
            [c._stations for c in self._distinct],
            width * np.arange(len(self.connectors)),
            self._kinds,
        )
