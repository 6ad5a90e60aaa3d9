"""A batch's block-diagonal saddle-point tangent, factorised copy by copy.

The copies of a batch (:class:`flexval.reducedmodels.core.batch.BatchSystem`) are
independent, so its tangent is block-diagonal: one block per copy, held in
one band. A copy whose own tangent is a small dense saddle point (Lagrange
multipliers: ``prbm``'s closure, pins) is factorised alone by LAPACK's
Bunch-Kaufman LDL^T (:class:`flexval.reducedmodels.core.tangent.DenseTangent`),
which gives both its solves and its inertia. :class:`BlockTangent` does the
same for every block of the batch in one compiled loop
(:mod:`flexval.reducedmodels.kernels.ldlkernel`), in each copy's own numbering, so
that

* each copy's correction is the one its own System computes (to round-off:
  the same pivots and updates), instead of a banded LU's of the band;
* the stability check reads each copy's inertia from the factorisation the
  next step's predictor solves with, instead of factorising the block again;
* a singular block stops its own copy (a NaN correction), not the batch.

Units: those of the tangent (N/mm, N, N mm).
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from .tangent import BandedTangent, TangentLayout, ldl_kernels


class BlockMaps(NamedTuple):
    """Where the copies of a block-diagonal band have their blocks (:func:`block_maps`)."""

    places: np.ndarray
    """(m, m): where entry (p, q), p <= q, of copy 0's block in its own numbering lies in
    the flat band storage (-1: outside the band, a zero)."""
    stride: int
    """The values between one copy's block and the next's: (b + 1) m."""
    index: np.ndarray
    """(copies, m): the unknown of the whole system that is copy c's own unknown p."""


def block_maps(own: np.ndarray, half_bandwidth: int, index: np.ndarray) -> BlockMaps:
    """The :class:`BlockMaps` of copies of m unknowns whose own unknown p is the band row
    ``own[p]`` of its block (the band of half-width ``half_bandwidth`` in flat storage:
    K[i, j], i <= j, at (b + 1) j + b + i - j), and ``index`` as :class:`BlockMaps` says."""
    b, m = half_bandwidth, own.size
    i, j = np.minimum.outer(own, own), np.maximum.outer(own, own)
    places = np.where(j - i <= b, (b + 1) * j + b + i - j, -1).astype(np.int64)
    return BlockMaps(places, (b + 1) * m, np.ascontiguousarray(index, np.int64))


class BlockTangent(BandedTangent):
    """A block-diagonal symmetric tangent in band storage, each block factorised alone.

    A batch's tangents are these where its copies are saddle points; the
    stability check of copies with other small dense tangents wraps theirs
    in one to count each copy's inertia.

    Parameters
    ----------
    storage : ndarray ((b + 1) n,)
        The band's values, flat: K[perm[i], perm[j]], i <= j <= i + b, at
        (b + 1) j + b + i - j (:class:`~flexval.reducedmodels.core.tangent.TangentLayout`'s
        banded storage).
    perm, half_bandwidth :
        As for :class:`~flexval.reducedmodels.core.tangent.BandedTangent`: the band
        order puts each copy's unknowns together, copy c's block in the band's
        rows c m .. c m + m - 1.
    blocks : BlockMaps
        Where each copy's block and unknowns are (:func:`block_maps`).
    """

    def __init__(
        self, storage: np.ndarray, perm: np.ndarray, half_bandwidth: int, blocks: BlockMaps
    ):
        n = perm.size
        super().__init__(
            storage.reshape(n, half_bandwidth + 1).T, perm, half_bandwidth, indefinite=True
        )
        self.flat, self.blocks = storage, blocks
        self._blocks: tuple | None = None  # factors, pivots, D's eigenvalues, info, negative

    def _factorise(self) -> None:
        if self._blocks is None:
            copies, m = self.blocks.index.shape
            factors = np.empty((copies, ldl_kernels().packed_size(m)))
            pivots = np.empty((copies, m), np.int64)
            eigenvalues = np.empty((copies, m))
            info = np.empty(copies, np.int64)
            negative = np.empty(copies, np.int64)
            ldl_kernels().block_factor(
                self.flat,
                self.blocks.places,
                self.blocks.stride,
                factors,
                pivots,
                eigenvalues,
                info,
                negative,
            )
            self._blocks = (factors, pivots, eigenvalues, info, negative)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """K x = rhs, each copy's part by its own block's LDL^T; NaN for a copy whose block is
        singular or not finite (a batch of one copy raises, as the copy's own tangent does)."""
        self._factorise()
        factors, pivots, _, info, _ = self._blocks
        if info.size == 1 and info[0] > 0:
            raise np.linalg.LinAlgError(f"singular tangent (zero pivot {int(info[0])})")
        solve = functools.partial(
            ldl_kernels().block_solve, factors, pivots, info, self.blocks.index
        )
        rhs = np.asarray(rhs, float)
        if rhs.ndim == 1:
            x = np.empty(self.n)
            solve(np.ascontiguousarray(rhs), x)
            return x
        x = np.empty((self.n, rhs.shape[1]))
        for k in range(rhs.shape[1]):
            column = np.empty(self.n)
            solve(np.ascontiguousarray(rhs[:, k]), column)
            x[:, k] = column
        return x

    def positive_definite(self) -> bool:
        """True when every block's D is positive (never for a saddle point)."""
        self._factorise()
        eigenvalues, info = self._blocks[2], self._blocks[3]
        return bool((info == 0).all() and (eigenvalues > 0.0).all())

    def copy_negative(self) -> np.ndarray:
        """Each copy's negative eigenvalues, D's pivots judged by the one rule
        (:mod:`flexval.reducedmodels.core.stability`) in the kernel that factorised the block, the
        kernel its own dense tangent counts with (-1: a block that is not finite, not judged)."""
        self._factorise()
        return self._blocks[4]

    def negative_eigenvalues(self) -> int | None:
        """The sum of :meth:`copy_negative` (None if a block is not finite)."""
        counts = self.copy_negative()
        return None if (counts < 0).any() else int(counts.sum())


class BlockLayout(TangentLayout):
    """A batch's band layout whose tangents are :class:`BlockTangent` (see the module).

    Parameters
    ----------
    layout : TangentLayout
        The batch's banded layout (its slots, order and half-bandwidth are kept).
    blocks : BlockMaps
        Where each copy's block and unknowns are (:func:`block_maps`).
    """

    def __init__(self, layout: TangentLayout, blocks: BlockMaps):
        self.__dict__.update(layout.__dict__)
        self.blocks = blocks

    def tangent(self, storage: np.ndarray) -> BlockTangent:
        return BlockTangent(storage, self.perm, self.b, self.blocks)
