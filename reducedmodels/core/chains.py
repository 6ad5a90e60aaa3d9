"""Chains of nodes joined by chords: the predictor and Newton update of a discretised flexure.

A beam connector's nodes and a DCMM connector's cut bodies lie on a polyline
from one body to the other whose chords hardly stretch. Extrapolating their
coordinates one by one (the core's predictor) or adding a Newton correction
to them (its linear update) stretches every chord that turns by
(turn)^2 / 2, and the axial stiffness turns that error into forces far
larger than the load: tens of Newton iterations a step on slender flexures,
more the finer the chain. :class:`NodeChains` predicts and updates them in
chord lengths and turns instead, each chain closed between its end bodies
by the flexure's own least-energy bending
(:mod:`flexval.reducedmodels.kernels.chainkernel`), for the connectors of one group
at once; the groups hand its functions to the core
(:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.predictor`,
:meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.updater`).

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from .connector import LocalState


@functools.cache
def chain_kernels() -> ModuleType:
    """:mod:`flexval.reducedmodels.kernels.chainkernel`; each kernel is compiled, or loaded from
    the on-disk cache, where it is first called, off the path's clock
    (:mod:`flexval.reducedmodels.kernels.clock`)."""
    from ..kernels import chainkernel

    return chainkernel


def local_coordinates(states: Sequence[LocalState]) -> np.ndarray:
    """The connectors' local coordinates [pose_a, pose_b, internal] laid end to end (float)."""
    return np.concatenate([part for state in states for part in state]).astype(float, copy=False)


@dataclass(frozen=True)
class NodeChains:
    """The chains of a group of connectors, in their local coordinates laid end to end.

    Attributes
    ----------
    node_dof : int64 array (nodes,)
        Where each node's (x, y, theta) is read among the coordinates, or, for a node
        attached to a body (a chain's end), its body's pose.
    node_rel : array (nodes, 2)
        An attached node's offset from its body's reference point at rest (mm; 0 else).
    attached : bool array (nodes,)
        Which nodes are carried by a body.
    chain_nodes : int64 array (chains + 1,)
        Chain k holds the nodes ``chain_nodes[k]`` to ``chain_nodes[k + 1] - 1``.
    bending_flexibility, axial_flexibility : arrays (chords,)
        Each chord's integral of ds / EI (1/(N mm)) and ds / EA (mm/N), chain after chain:
        how the closure shares a gap between the chords.
    """

    node_dof: np.ndarray
    node_rel: np.ndarray
    attached: np.ndarray
    chain_nodes: np.ndarray
    bending_flexibility: np.ndarray
    axial_flexibility: np.ndarray

    def _tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.chain_nodes, self.bending_flexibility, self.axial_flexibility

    def predictor(
        self, gather: np.ndarray
    ) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[..., np.ndarray]]:
        """``(remember, predict)`` on the System's coordinates ``[q, ground pose]``, as
        :meth:`~flexval.reducedmodels.core.connector.ConnectorGroup.predictor` says: the chords'
        lengths, turns and the nodes' rotations extrapolated (with the path's slope where
        given: :func:`~flexval.reducedmodels.kernels.chainkernel.predicted_chains`)."""
        kernels = chain_kernels()
        nodes = (
            np.ascontiguousarray(gather[self.node_dof], np.int64),
            self.node_rel,
            self.attached,
        )
        fixed = (*nodes, *self._tables())
        no_slope = np.zeros(0)  # not read with a zero weight

        def remember(coordinates: np.ndarray) -> np.ndarray:
            return kernels.chain_memory(coordinates, *nodes, self.chain_nodes)

        def predict(
            memories: np.ndarray,
            weights: np.ndarray,
            guess: np.ndarray,
            slope: np.ndarray | None = None,
            slope_weight: float = 0.0,
        ) -> np.ndarray:
            return kernels.predicted_chains(
                memories, weights, guess, *fixed, no_slope if slope is None else slope, slope_weight
            )

        return remember, predict

    def updater(self, gather: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        """``f(old, new)`` on the System's coordinates: the free nodes after a Newton
        correction from ``old`` to ``new`` (linear), chords turned, not sheared
        (:func:`~flexval.reducedmodels.kernels.chainkernel.updated_chains`)."""
        updated_chains = chain_kernels().updated_chains
        fixed = (
            np.ascontiguousarray(gather[self.node_dof], np.int64),
            self.node_rel,
            self.attached,
            *self._tables(),
        )

        def update(old: np.ndarray, new: np.ndarray) -> np.ndarray:
            return updated_chains(old, new, *fixed)

        return update

    def predict_internal(
        self,
        past: Sequence[Sequence[LocalState]],
        weights: Sequence[float],
        poses: Sequence[tuple[np.ndarray, np.ndarray]],
    ) -> np.ndarray:
        """The free nodes (concatenated) predicted from the connectors' local states along
        the history (oldest first), their weights and the bodies' predicted poses."""
        kernels = chain_kernels()
        nodes = (self.node_dof, self.node_rel, self.attached)
        memories = np.array(
            [
                kernels.chain_memory(local_coordinates(states), *nodes, self.chain_nodes)
                for states in past
            ]
        )
        predicted = local_coordinates([(*pose, state[2]) for pose, state in zip(poses, past[-1])])
        return kernels.predicted_chains(
            memories,
            np.asarray(weights, float),
            predicted,
            *nodes,
            *self._tables(),
            np.zeros(0),
            0.0,
        )

    def update_internal(self, old: Sequence[LocalState], new: Sequence[LocalState]) -> np.ndarray:
        """The free nodes (concatenated) after a Newton correction from the local states
        ``old`` to ``new`` (linear)."""
        return chain_kernels().updated_chains(
            local_coordinates(old),
            local_coordinates(new),
            self.node_dof,
            self.node_rel,
            self.attached,
            *self._tables(),
        )
