"""Rigid placement of a whole mechanism (for invariance checks and user frames)."""

from __future__ import annotations

import dataclasses

import numpy as np

from .kinematics import rotation


def transform_point(p: np.ndarray, angle: float, shift: np.ndarray) -> np.ndarray:
    """Rotate point(s) p (mm) by ``angle`` (rad) about the origin, then add ``shift`` (mm)."""
    return np.asarray(p, float) @ rotation(angle).T + shift


def transform_mechanism(mech, angle: float, shift: np.ndarray):
    """A Mechanism rotated by ``angle`` (rad) about the origin and shifted by ``shift`` (mm)."""
    flexures = tuple(
        dataclasses.replace(f, shape=f.shape.moved(angle, shift)) for f in mech.flexures
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
