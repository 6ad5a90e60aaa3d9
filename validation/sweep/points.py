"""The points of a sweep: each one's scene values, and the set of them a sweep holds.

A :class:`Point` is one scene of the sweep (its axes' values written into
the base scene); a :class:`PointSet` holds every point compactly (records
and digests, built incrementally for large sweeps) and :class:`ValidPoints`
those whose scene loads. Units: those of the scene fields the axes address.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexval.geometry import Scene

from .fields import RECORD_BLOCK

if TYPE_CHECKING:
    from .spec import Axis, PointBuilder


def digest(data: dict) -> str:
    """Hash of a point's scene data (24 hex digits)."""
    text = json.dumps(data, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


@dataclass(frozen=True)
class Point:
    """One point of the sweep: its parameter values and its loaded scene.

    ``scene`` is None for an invalid generated point, whose ``reason`` says
    why the scene loader refused it. ``digest`` hashes the point's scene
    data (after every edit), so equal scenes have equal digests.
    """

    index: int
    params: dict[str, float]
    scene: Scene | None
    digest: str
    reason: str | None = None


@dataclass(frozen=True)
class PointRecord:
    """What the driver keeps of a point between building it and the summary: its index, the
    digest of its scene data and, for an invalid point, why the loader refused it."""

    index: int
    digest: str
    reason: str | None = None


class PointSet(Sequence):
    """A sweep's points: built on demand, one at a time, from a :class:`PointBuilder` and the
    small per-point records (:class:`PointRecord`) of a checking pass, or a given tuple of
    built points.

    A *lazy* set (``digests`` None, ``count`` points) has had no checking pass: the digests
    follow from the axis values (:meth:`PointBuilder.digest_of`) and a point is known to be
    invalid only once a worker built it (:meth:`note_invalid`); until then
    :attr:`valid_count` counts it valid, and :attr:`checked` is False.

    Indexing and iteration build the points (scenes included); :meth:`records`,
    :meth:`params` and :attr:`valid_count` do not. Memory: 24 bytes of digest per point of a
    checked set, none for a lazy one, and the reasons of the invalid points.
    """

    def __init__(
        self,
        builder: PointBuilder | None = None,
        digests: np.ndarray | None = None,
        reasons: dict[int, str] | None = None,
        points: tuple[Point, ...] | None = None,
        count: int | None = None,
    ):
        self._builder, self._points = builder, points
        self._digests = digests
        self._count = count
        self._reasons = reasons or {}
        if points is not None:
            self._by_index = {p.index: k for k, p in enumerate(points)}

    @property
    def builder(self) -> PointBuilder | None:
        """The builder of the points (None for a set of built points)."""
        return self._builder

    @property
    def checked(self) -> bool:
        """Whether every point's validity is known (a checking pass, or built points)."""
        return self._points is not None or self._digests is not None

    def digest(self, k: int) -> str:
        """The scene digest of the point at position ``k``, without building it."""
        if self._points is not None:
            return self._points[k].digest
        if self._digests is not None:
            return self._digests[k].decode()
        return self._builder.digest_of(self._builder.values(np.array([k]))[0])

    def reason(self, k: int) -> str | None:
        """Why the point at position ``k`` is invalid (None: valid, or not known yet)."""
        if self._points is not None:
            return self._points[k].reason
        return self._reasons.get(k)

    def invalid_records(self) -> Iterator[PointRecord]:
        """The :class:`PointRecord` of every point known to be invalid, in order (a lazy set
        knows those its workers found; no other point's digest is computed)."""
        if self._points is not None:
            yield from (r for r in self.records() if r.reason is not None)
            return
        for k in sorted(self._reasons):
            yield PointRecord(k, self.digest(k), self._reasons[k])

    def note_invalid(self, reasons: dict[int, str]) -> None:
        """Record the points (by index) that a worker found invalid, with why."""
        self._reasons.update(reasons)

    @classmethod
    def of(cls, points: tuple[Point, ...]) -> PointSet:
        """The set of the built ``points`` (positions and indices may differ)."""
        return cls(points=tuple(points))

    def __len__(self) -> int:
        if self._points is not None:
            return len(self._points)
        return len(self._digests) if self._digests is not None else self._count

    def __getitem__(self, k: int) -> Point:  # type: ignore[override]
        """The point at position ``k``, built."""
        if self._points is not None:
            return self._points[k]
        k = range(len(self))[k]
        point = self._builder.build(k)
        if point.digest != self.digest(k):
            raise RuntimeError(f"point {k} of the sweep built differently from its check")
        return point

    def __iter__(self) -> Iterator[Point]:
        if self._points is not None:
            yield from self._points
            return
        for k, values in enumerate(combined_values(self._builder.axes, self._builder.combine)):
            yield self._builder.build(k, {a.path: v for a, v in zip(self._builder.axes, values)})

    def records(self) -> Iterator[PointRecord]:
        """Every point's :class:`PointRecord`, in order, without building a scene."""
        if self._points is not None:
            for p in self._points:
                yield PointRecord(p.index, p.digest, p.reason)
            return
        if self._digests is not None:
            for k, d in enumerate(self._digests):
                yield PointRecord(k, d.decode(), self._reasons.get(k))
            return
        for start in range(0, len(self), RECORD_BLOCK):
            block = np.arange(start, min(start + RECORD_BLOCK, len(self)))
            for k, values in zip(block, self._builder.values(block)):
                yield PointRecord(
                    int(k), self._builder.digest_of(values), self._reasons.get(int(k))
                )

    def params(self, index: int) -> dict[str, float]:
        """The parameters of the point of ``index``, without building it."""
        if self._points is not None:
            return self._points[self._by_index[index]].params
        return self._builder.params(index)

    @property
    def valid_count(self) -> int:
        """The number of points whose scene loaded."""
        if self._points is not None:
            return sum(p.scene is not None for p in self._points)
        return len(self) - len(self._reasons)


class ValidPoints(Sequence):
    """The points of a :class:`PointSet` whose scene loaded, built as they are iterated."""

    def __init__(self, points: PointSet):
        self._all = points

    def __len__(self) -> int:
        return self._all.valid_count

    def __getitem__(self, k: int) -> Point:  # type: ignore[override]
        return next(itertools.islice(iter(self), range(len(self))[k], None))

    def __iter__(self) -> Iterator[Point]:
        if self._all.valid_count == len(self._all):
            yield from (p for p in self._all if p.scene is not None)  # a lazy set's unknowns
            return
        for r in self._all.records():
            if r.reason is None:
                yield self._all[r.index]


def combined_values(axes: tuple[Axis, ...], combine: str) -> Iterator[tuple[float, ...]]:
    """The parameter tuples of every point, in axis order, one at a time."""
    if combine == "zip" and axes:
        return zip(*(a.values for a in axes))
    return itertools.product(*(a.values for a in axes))
