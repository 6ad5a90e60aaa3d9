"""Rigid placement of a whole mechanism (for invariance checks and user frames)."""

from __future__ import annotations

import dataclasses

import numpy as np

from .kinematics import rotation
from .shapes import Arc, Segment


def transform_point(p: np.ndarray, angle: float, shift: np.ndarray) -> np.ndarray:
    """Rotate point(s) p (mm) by ``angle`` (rad) about the origin, then add ``shift`` (mm)."""
    return np.asarray(p, float) @ rotation(angle).T + shift


def transform_shape(shape, angle: float, shift: np.ndarray):
    """The same arc or segment rigidly moved; arc length parametrisation is kept."""
    if isinstance(shape, Arc):
        c = transform_point(np.asarray(shape.center), angle, shift)
        return Arc((float(c[0]), float(c[1])), shape.radius, shape.axis + angle, shape.width)
    if isinstance(shape, Segment):
        a = transform_point(np.asarray(shape.start), angle, shift)
        b = transform_point(np.asarray(shape.end), angle, shift)
        return Segment(tuple(map(float, a)), tuple(map(float, b)))
    raise TypeError(f"unknown shape {type(shape).__name__}")


def transform_mechanism(mech, angle: float, shift: np.ndarray):
    """A Mechanism rotated by ``angle`` (rad) about the origin and shifted by ``shift`` (mm)."""
    flexures = tuple(
        dataclasses.replace(f, shape=transform_shape(f.shape, angle, shift)) for f in mech.flexures
    )
    bodies = {
        n: dataclasses.replace(b, points=transform_point(b.points, angle, shift))
        for n, b in mech.bodies.items()
    }
    return dataclasses.replace(
        mech,
        flexures=flexures,
        bodies=bodies,
        target_point=transform_point(mech.target_point, angle, shift),
    )
