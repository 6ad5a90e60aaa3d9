"""All meshed flexures of a system evaluated and assembled together (the core's connector group).

:class:`ContinuumGroup` numbers the nodes of its connectors one after the
other (:meth:`~.solid.ElementKernel.stack`) and its
:meth:`~ContinuumGroup.assembler` adds the gradient and tangent straight
into the core's global arrays
(:meth:`flexval.reducedmodels.core.connector.ConnectorGroup.assembler`): every element
entry goes to the storage slot of its nodal dofs' first expansion (a free
coordinate, or an end face's body translation) in one ``bincount`` per
flexure with slots worked out once; only the few entries of end-face nodes
add their rotation terms separately. This is the chain rule of
:class:`.connector.ContinuumConnector` (``g = T^T f``, ``H = T^T K T`` plus
the faces' second derivatives) without building the per-connector Hessian
values and concatenating them. The predictor and the Newton update of all
flexures are one set of array operations (:mod:`.polar`).
Units: mm, N, N mm, rad.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from flexval.reducedmodels.core.connector import ConnectorGroup, LocalState

from .polar import (
    PolarShape,
    advanced,
    extrapolate,
    first_order_change,
    interior,
    stack_sections,
    to_polar,
)
from .solid import BLOCK_ENTRY, BLOCK_MIRROR, ElementKernel


class ContinuumGroup(ConnectorGroup):
    """Meshed flexures of one law and plane assumption, evaluated as one solid.

    Parameters
    ----------
    connectors : sequence of ContinuumConnector
    """

    def __init__(self, connectors: Sequence):
        super().__init__(connectors)
        self.kernel = ElementKernel.stack([c.solid.kernel for c in self.connectors])
        offsets = np.cumsum([0] + [c.mesh.nodes.shape[0] for c in self.connectors])
        self._nodes = np.vstack([c.mesh.nodes for c in self.connectors])
        self._free = np.concatenate([c.free_nodes + o for c, o in zip(self.connectors, offsets)])
        faces = [
            (c.end_faces[s] + o, c.end_offsets[s])
            for c, o in zip(self.connectors, offsets)
            for s in (0, 1)
        ]
        self._face_nodes = np.concatenate([f for f, _ in faces])
        self._face_rel = np.vstack([r for _, r in faces])
        self._face_of = np.repeat(np.arange(len(faces)), [f.size for f, _ in faces])
        self._sections = stack_sections([c.sections for c in self.connectors], offsets[:-1])
        sections = self._sections
        mid = sections.nodes.shape[1] // 2
        at_face = np.full(self._nodes.shape[0], -1)
        at_face[self._face_nodes] = np.arange(self._face_nodes.size)
        self._face_centres = (
            at_face[sections.nodes[sections.first, mid]],
            at_face[sections.nodes[sections.last, mid]],
        )
        # the interior sections' nodes, flattened, are the free nodes in another order
        inner = sections.nodes[sections.interior].ravel()
        position = np.full(self._nodes.shape[0], -1)
        position[inner] = np.arange(inner.size)
        self._free_in_interior = position[self._free]
        if inner.size != self._free.size or np.any(self._free_in_interior < 0):
            raise RuntimeError("the interior sections are not the free nodes")

    def _positions(self, states: Sequence[LocalState]) -> tuple[np.ndarray, np.ndarray]:
        """All mesh nodes' positions (n_nodes, 2) and the faces' poses (n_faces, 3) of the
        connectors' local ``states`` (mm, rad)."""
        poses = np.array([pose for state in states for pose in state[:2]], float)
        return self._positions_at(poses, np.concatenate([state[2] for state in states])), poses

    def _positions_at(self, poses: np.ndarray, internal: np.ndarray) -> np.ndarray:
        """All mesh nodes' positions (n_nodes, 2) for the faces' poses (n_faces, 3) and the
        free nodes' displacements ``internal`` (flat, in the order of the free nodes), mm."""
        x = self._nodes.copy()
        x[self._free] += internal.reshape(-1, 2)
        x[self._face_nodes] = poses[self._face_of, :2] + self._face_arms(poses)
        return x

    def _node_moves(
        self, x: np.ndarray, poses: np.ndarray, d_internal: np.ndarray, d_poses: np.ndarray
    ) -> np.ndarray:
        """First-order moves (n_nodes, 2) of the nodes at x (faces at ``poses``), mm.

        ``d_internal`` moves the free nodes (flat, their order); ``d_poses``
        (n_faces, 3) moves the faces' bodies, whose nodes follow linearised.
        """
        dx = np.empty_like(x)
        dx[self._free] = d_internal.reshape(-1, 2)
        arm = x[self._face_nodes] - poses[self._face_of, :2]
        turn = d_poses[self._face_of]
        dx[self._face_nodes] = turn[:, :2] + turn[:, 2:] * np.column_stack([-arm[:, 1], arm[:, 0]])
        return dx

    def _coordinate_maps(self, gather: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where the faces' poses (n_faces, 3) and the free nodes' displacements (flat) are
        in the coordinates ``[q, ground pose]``, from the core's ``gather``."""
        pose_at, free_at, block = [], [], 0
        for c in self.connectors:
            local = gather[block : block + 6 + c.n_internal]
            pose_at += [local[0:3], local[3:6]]
            free_at.append(local[6:])
            block += 6 + c.n_internal
        return np.array(pose_at), np.concatenate(free_at)

    def _face_centres_at(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions (mm) of every flexure's start and end face centres for the faces' poses."""
        start, end = self._face_centres
        x = poses[self._face_of[start], :2] + self._face_arms(poses, start)
        return x, poses[self._face_of[end], :2] + self._face_arms(poses, end)

    def _internal_of(self, shape: PolarShape, poses: np.ndarray) -> np.ndarray:
        """The internal coordinates (mm) of ``shape`` rebuilt between the faces at ``poses``."""
        xs = interior(shape, self._sections, *self._face_centres_at(poses))
        return (xs.reshape(-1, 2)[self._free_in_interior] - self._nodes[self._free]).ravel()

    def predict_internal(
        self,
        past: Sequence[Sequence[LocalState]],
        weights: Sequence[float],
        poses: Sequence[tuple[np.ndarray, np.ndarray]],
    ) -> np.ndarray:
        """Interior nodes extrapolated section by section (mm; the load stepping's predictor).

        Chord lengths and directions between the section centres, section
        rotations and the nodes' offsets in their section's frame are
        extrapolated with ``weights`` over the converged states ``past``
        (:mod:`.polar`), and the sections are rebuilt between the end faces
        at the bodies' predicted ``poses``.
        """
        shape = extrapolate(
            [to_polar(self._positions(states)[0], self._sections) for states in past], weights
        )
        return self._internal_of(shape, np.array([p for pose in poses for p in pose], float))

    def update_internal(self, old: Sequence[LocalState], new: Sequence[LocalState]) -> np.ndarray:
        """Interior nodes after a Newton correction, turned section by section (mm).

        ``new`` holds the linearly corrected states. The correction becomes
        first-order changes of the chords, section rotations and offsets
        (:func:`.polar.advanced`; the end faces move with the linearised
        motion of their bodies), applied as finite turns between the end
        faces at the new poses. This agrees with the linear update to first
        order, so Newton stays quadratic, but a section that turns by dphi no
        longer comes out stretched by dphi^2 / 2, which the membrane
        stiffness would turn into forces far above the load.
        """
        x_old, before = self._positions(old)
        after = np.array([pose for state in new for pose in state[:2]], float)
        d_internal = np.concatenate([state[2] for state in new]) - np.concatenate(
            [state[2] for state in old]
        )
        dx = self._node_moves(x_old, before, d_internal, after - before)
        return self._internal_of(advanced(x_old, dx, self._sections), after)

    def predictor(
        self, gather: np.ndarray
    ) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[..., np.ndarray]]:
        """:meth:`predict_internal` on global coordinates, with the path's slope.

        See :meth:`flexval.reducedmodels.core.connector.ConnectorGroup.predictor`.
        ``remember`` keeps a converged state's polar shape, node positions
        and face poses (one flat array: the shapes are not recomputed at
        every prediction); ``predict`` extrapolates the shapes and, given
        the slope dq/dfactor at the last state, adds its polar form
        (:func:`.polar.first_order_change` of the node moves it makes) with
        the slope's Hermite weight: the sections' chords, rotations and
        offsets are then predicted one degree higher, as the bodies' poses
        are. On ``continuum:1``'s six paper paths this took the Newton
        iterations from 38 50 46 157 / 42 40 to 32 28 39 117 / 36 36 (open
        chain m+ m- f+ f- / closed f+ f-), end values within 1e-9.
        """
        pose_at, free_at = self._coordinate_maps(gather)
        stack = self._sections
        n_sections, width = stack.nodes.shape
        sizes = [
            stack.starts.size,
            stack.starts.size,
            n_sections,
            2 * n_sections * width,
            self._nodes.size,
            pose_at.size,
        ]
        cuts = np.cumsum(sizes)[:-1]

        def unpacked(memory: np.ndarray) -> tuple[PolarShape, np.ndarray, np.ndarray]:
            ell, alpha, phi, offset, x, poses = np.split(memory, cuts)
            return (
                PolarShape(ell, alpha, phi, offset.reshape(n_sections, width, 2)),
                x.reshape(-1, 2),
                poses.reshape(-1, 3),
            )

        def remember(coordinates: np.ndarray) -> np.ndarray:
            poses = coordinates[pose_at]
            x = self._positions_at(poses, coordinates[free_at])
            return np.concatenate(
                [*(np.ravel(a) for a in to_polar(x, stack)), x.ravel(), poses.ravel()]
            )

        def predict(
            memories: np.ndarray,
            weights: np.ndarray,
            guess: np.ndarray,
            slope: np.ndarray | None = None,
            slope_weight: float = 0.0,
        ) -> np.ndarray:
            past = [unpacked(memory) for memory in memories]
            shape = extrapolate([p[0] for p in past], weights)
            if slope is not None:
                _, x, poses = past[-1]
                change = first_order_change(
                    x, self._node_moves(x, poses, slope[free_at], slope[pose_at]), stack
                )
                shape = PolarShape(*(a + slope_weight * d for a, d in zip(shape, change)))
            return self._internal_of(shape, guess[pose_at])

        return remember, predict

    def _face_arms(self, poses: np.ndarray, nodes: np.ndarray | slice = slice(None)) -> np.ndarray:
        """R(theta) rel of the end-face ``nodes`` (indices into the face nodes; all by default),
        mm, for the faces' body poses (n_faces, 3)."""
        face_of = self._face_of[nodes]
        c, s = np.cos(poses[face_of, 2]), np.sin(poses[face_of, 2])
        rx, ry = self._face_rel[nodes, 0], self._face_rel[nodes, 1]
        return np.column_stack([c * rx - s * ry, s * rx + c * ry])

    @staticmethod
    def _block_slots(
        first: np.ndarray,
        src: np.ndarray,
        p: np.ndarray,
        q: np.ndarray,
        slot: np.ndarray,
        unit: int,
    ) -> tuple[np.ndarray, ...]:
        """The storage slots of one flexure's tangent blocks (``ElementKernel.evaluate``).

        ``first`` (n_el, 324) holds the slot of every element-matrix entry's
        first expansion (-1: none); ``src`` (flat entry indices, element by
        element), ``p``, ``q`` (coefficient indices) and ``slot`` its further
        expansions. A value of the (0, 1) block stands for two entries, (a x,
        b y) and its mirror (b y, a x): it goes to whichever of their slots is
        kept (the other is in the band's lower triangle, or the ground's), and
        to both (as a further expansion with coefficient ``unit``) when both are.
        Returns the slots (n_el * 243,) of the values and the further
        expansions (value indices, p, q, slots).
        """
        n_el = first.shape[0]
        slots = first[:, BLOCK_ENTRY]
        mirrored = np.flatnonzero(BLOCK_MIRROR >= 0)
        own, other = slots[:, mirrored], first[:, BLOCK_MIRROR[mirrored]]
        both = (own >= 0) & (other >= 0)
        slots[:, mirrored] = np.where(own >= 0, own, other)
        value_of = np.empty(first.shape[1], np.int64)  # entry -> value within an element
        value_of[BLOCK_ENTRY] = np.arange(BLOCK_ENTRY.size)
        value_of[BLOCK_MIRROR[mirrored]] = mirrored
        per_el = BLOCK_ENTRY.size
        twice = (np.arange(n_el)[:, None] * per_el + mirrored)[both]
        src = np.concatenate(
            [src // first.shape[1] * per_el + value_of[src % first.shape[1]], twice]
        )
        unit_at = np.full(twice.size, unit)
        return (
            slots.ravel(),
            src,
            np.concatenate([p, unit_at]),
            np.concatenate([q, unit_at]),
            np.concatenate([slot, other[both]]),
        )

    def assembler(
        self, gather: np.ndarray, grad_dofs: np.ndarray, hess_slots: np.ndarray
    ) -> Callable[[np.ndarray, np.ndarray, np.ndarray], float]:
        """The function adding every flexure's gradient and tangent into the global arrays.

        See :meth:`flexval.reducedmodels.core.connector.ConnectorGroup.assembler` for the
        arguments; ``hess_slots`` follows the order of each connector's
        :meth:`~.connector.ContinuumConnector.hessian_pattern`.
        """
        n_faces = 2 * len(self.connectors)
        first_dof, theta_dof, slot_first = [], [], []
        extra_src, extra_p, extra_q, extra_slot, second_slot = [], [], [], [], []
        block = hess_block = face_dofs = 0
        unit = 2 * self._face_nodes.size  # coefficient index of "1" (not a face rotation)
        pose_at, free_at = self._coordinate_maps(gather)
        for c in self.connectors:
            g_dof = grad_dofs[block : block + 6 + c.n_internal]
            theta_dof += [g_dof[2], g_dof[5]]
            # global dof of each nodal dof's first expansion (-1: the ground's)
            nodal = np.empty(2 * c.mesh.nodes.shape[0], np.int64)
            nodal[(2 * c.free_nodes[:, None] + np.arange(2)).ravel()] = g_dof[6:]
            for s in (0, 1):
                nodal[(2 * c.end_faces[s][:, None] + np.arange(2)).ravel()] = np.tile(
                    g_dof[3 * s : 3 * s + 2], c.end_faces[s].size
                )
            first_dof.append(nodal)
            # Hessian values of the pattern: [plain, mixed, second (2)]
            slots = hess_slots[hess_block : hess_block + c.pattern_rows.size]
            t_mixed, p_mixed, q_mixed = c.mixed
            n_plain = c.plain_src.size
            first = np.full(c.solid.rows.size, -1, np.int64)
            first[c.plain_src] = slots[:n_plain]
            is_first = c.mixed_first
            first[t_mixed[is_first]] = slots[n_plain : n_plain + t_mixed.size][is_first]
            slot_first.append(first)
            coef_at = np.full(c.exp_z.size, unit)
            for s in (0, 1):
                coef_at[c.theta_pos[s]] = face_dofs + np.arange(c.theta_pos[s].size)
                face_dofs += c.theta_pos[s].size
            rest = ~is_first
            keep = slots[n_plain : n_plain + t_mixed.size] >= 0
            extra_src.append(t_mixed[rest & keep])
            extra_p.append(coef_at[p_mixed[rest & keep]])
            extra_q.append(coef_at[q_mixed[rest & keep]])
            extra_slot.append(slots[n_plain : n_plain + t_mixed.size][rest & keep])
            second_slot.append(slots[-2:])
            block += 6 + c.n_internal
            hess_block += c.pattern_rows.size
        first_dof = np.concatenate(first_dof)
        theta_dof = np.array(theta_dof)
        second_slot = np.concatenate(second_slot)
        # one chunk of elements per flexure: its temporaries stay in cache (stacking
        # all flexures into one call measured slower on the open chain) and its
        # entries fall in a narrow range of the storage; dropped entries (the
        # ground's, the lower triangle's) go to one spare slot past that range
        chunks = []
        start = np.cumsum([0] + [c.solid.elements.shape[0] for c in self.connectors])
        for k, first in enumerate(slot_first):
            n_el = start[k + 1] - start[k]
            slots, src, p, q, extra = self._block_slots(
                first.reshape(n_el, -1), extra_src[k], extra_p[k], extra_q[k], extra_slot[k], unit
            )
            kept = slots >= 0
            lo, hi = int(slots[kept].min()), int(slots[kept].max()) + 1
            chunks.append(
                (
                    self.kernel.subset(np.arange(start[k], start[k + 1])),
                    lo,
                    hi,
                    np.where(kept, slots - lo, hi - lo),
                    src,
                    p,
                    q,
                    extra,
                )
            )
        grad_kept = np.flatnonzero(first_dof >= 0)
        grad_kept_dof = first_dof[grad_kept]
        theta_kept = np.flatnonzero(theta_dof >= 0)
        second_kept = np.flatnonzero(second_slot >= 0)
        nodes, free, face_nodes, face_of = self._nodes, self._free, self._face_nodes, self._face_of

        def assemble(coordinates: np.ndarray, grad: np.ndarray, storage: np.ndarray) -> float:
            poses = coordinates[pose_at]
            arms = self._face_arms(poses)
            x = nodes.copy()
            x[free] += coordinates[free_at].reshape(-1, 2)
            x[face_nodes] = poses[face_of, :2] + arms
            jac = np.column_stack([-arms[:, 1], arms[:, 0]])  # d x / d theta
            coef = np.append(jac.ravel(), 1.0)
            energy, forces = 0.0, 0.0
            for kernel, lo, hi, slots, src, p, q, extra in chunks:
                e, f, blocks = kernel.evaluate(x)
                energy, forces = energy + e, forces + f
                values = blocks.ravel()
                storage[lo:hi] += np.bincount(slots, weights=values, minlength=hi - lo + 1)[:-1]
                np.add.at(storage, extra, values[src] * coef[p] * coef[q])
            grad += np.bincount(grad_kept_dof, weights=forces[grad_kept], minlength=grad.size)
            f_face = forces.reshape(-1, 2)[face_nodes]
            moment = np.bincount(
                face_of, weights=np.einsum("ij,ij->i", f_face, jac), minlength=n_faces
            )
            np.add.at(grad, theta_dof[theta_kept], moment[theta_kept])  # bodies may repeat
            second = np.bincount(
                face_of, weights=-np.einsum("ij,ij->i", f_face, arms), minlength=n_faces
            )
            np.add.at(storage, second_slot[second_kept], second[second_kept])
            return energy

        return assemble
