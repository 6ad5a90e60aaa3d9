"""The 3R PRBM's parameters: the table fitted to the continuum, read by arc angle.

:class:`PrbmParameters` holds a flexure's characteristic lengths and
spring constants; :func:`table_parameters` reads them from the fitted table
(``data/prbm_table.json``, ``benchmarks/calibrate_prbm.py``) at the arc's
angle, and :func:`tapered_frame` places a varying section's chain on its
ellipse of elasticity. Units: mm, N mm/rad, rad.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np

from flexval.geometry import Flexure
from flexval.geometry.compliance import curve_compliance
from flexval.geometry.shapes import Shape, arc_semi_axes

from ..core.geometrycache import GEOMETRY_CACHE
from .spline import NotAKnotSpline

TABLE_RESOURCE = "data/prbm_table.json"


@dataclass(frozen=True)
class PrbmParameters:
    """Dimensionless geometry and stiffness of the symmetric 3R chain.

    Attributes
    ----------
    x1, y1 : float
        Outer joint on the start side at (x1, y1) in the ellipse frame
        {C, e1, e2}, in units of the arc length L (the end-side joint is its
        mirror image (-x1, y1)).
    y2 : float
        Middle joint at (0, y2), units of L.
    kappa1, kappa2 : float
        Torsion stiffnesses of the outer and middle joints in units of EI / L.
    """

    x1: float
    y1: float
    y2: float
    kappa1: float
    kappa2: float

    def __post_init__(self) -> None:
        if not all(map(math.isfinite, (self.x1, self.y1, self.y2, self.kappa1, self.kappa2))):
            raise ValueError(f"prbm: parameters must be finite, got {self}")
        if self.kappa1 <= 0.0 or self.kappa2 <= 0.0:
            raise ValueError(
                f"prbm: joint stiffnesses must be > 0, got kappa1={self.kappa1}, "
                f"kappa2={self.kappa2}"
            )
        if self.x1 <= 0.0:
            raise ValueError(f"prbm: outer joints must be apart (x1 > 0), got x1={self.x1}")

    @classmethod
    def from_rho(cls, width: float, rho: float) -> PrbmParameters:
        """The chain with the arc's exact linear compliance and outer-joint compliance share rho.

        Parameters
        ----------
        width : float
            Arc angle 2 gamma, rad.
        rho : float
            2 c1 / (c_total) in (0, 1): fraction of the rotational compliance
            L/EI lumped in the two outer joints.
        """
        a, b = arc_semi_axes(width)  # floats (math.sqrt rounds as np.sqrt does)
        return cls.from_semi_axes(a, b, rho)

    @classmethod
    def from_semi_axes(cls, a: float, b: float, rho: float) -> PrbmParameters:
        """The chain with the linear compliance of an ellipse of semi-axes a, b (units of L).

        The four exactness conditions of the module text for any ellipse of
        elasticity (a across e2, b along it), with outer-joint share rho in (0, 1).
        """
        if not 0.0 < rho < 1.0:
            raise ValueError(f"prbm: rho must lie in (0, 1), got {rho}")
        return cls(
            x1=a / math.sqrt(rho),
            y1=-b * math.sqrt((1.0 - rho) / rho),
            y2=b * math.sqrt(rho / (1.0 - rho)),
            kappa1=2.0 / rho,
            kappa2=1.0 / (1.0 - rho),
        )


@lru_cache(maxsize=1)
def load_table() -> dict:
    """The shipped fit (``reducedmodels/data/prbm_table.json``) as a dict."""
    text = (
        resources.files("flexval.reducedmodels")
        .joinpath(TABLE_RESOURCE)
        .read_text(encoding="utf-8")
    )
    return json.loads(text)


@lru_cache(maxsize=1)
def _rho_spline() -> tuple[NotAKnotSpline, float]:
    rows = load_table()["table"]
    widths = np.radians([row["width_deg"] for row in rows])
    return NotAKnotSpline(widths, [row["rho"] for row in rows]), float(widths[-1])


@lru_cache(maxsize=GEOMETRY_CACHE)
def table_parameters(width: float) -> PrbmParameters:
    """Fitted chain for an arc angle ``width`` (rad), by cubic-spline interpolation of rho
    (kept per angle: the copies of a study share their arcs' angles).

    Raises
    ------
    ValueError
        If ``width`` lies outside the tabulated range.
    """
    return PrbmParameters.from_rho(width, table_rho(width))


def table_rho(width: float) -> float:
    """The fitted outer-joint share rho at an arc angle ``width`` (rad), cubic spline of the table.

    Raises
    ------
    ValueError
        If ``width`` lies outside the tabulated range.
    """
    spline, top = _rho_spline()
    if not 0.0 <= width <= top + 1e-12:
        raise ValueError(
            f"prbm: arc angle {np.degrees(width):.6g} deg is outside the fitted "
            f"range 0 .. {np.degrees(top):.6g} deg of {TABLE_RESOURCE}"
        )
    return float(spline(width))


def fitted_rotation() -> float:
    """Largest flexure end rotation (rad) in the load set the shipped table was fitted on."""
    return math.radians(load_table()["metadata"]["settings"]["max_rotation_deg"])


def shape_frame(shape: Shape) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """Centre of elasticity C (mm), axes e1, e2, length L (mm) and arc angle (rad) of a shape.

    e2 is the symmetry axis (towards the arc's apex) and e1 = R(-90 deg) e2
    points to the start end (:meth:`geometry.Arc.symmetry_frame`); a segment
    takes e1 from its end to its start and e2 = R(90 deg) e1.
    """
    center, e1, e2 = shape.symmetry_frame()
    return center, e1, e2, shape.length, shape.width


def local_joints(params: PrbmParameters) -> np.ndarray:
    """The joints [R_start, R_2, R_end] in the ellipse frame, units of L, (3, 2)."""
    return np.array([[params.x1, params.y1], [0.0, params.y2], [-params.x1, params.y1]])


def joint_positions(shape: Shape, params: PrbmParameters) -> np.ndarray:
    """Initial joints [R_start, R_2, R_end] of the chain for ``shape``, shape (3, 2), mm."""
    center, e1, e2, length, _ = shape_frame(shape)
    return center + length * local_joints(params) @ np.array([e1, e2])  # rows e1, e2


@dataclass(frozen=True)
class TaperedFrame:
    """The ellipse of elasticity of a tapered arc or segment, as the chain needs it.

    Attributes
    ----------
    center : ndarray (2,)
        Centre of elasticity C, mm.
    axes : ndarray (2, 2)
        Rows e1 (towards the start end) and e2 = R(90 deg) e1.
    a, b : float
        Semi-axes along e1 and e2 in units of the length L.
    w : float
        Rotational compliance ∫ ds / EI, 1/(N mm).
    """

    center: np.ndarray
    axes: np.ndarray
    a: float
    b: float
    w: float


def tapered_frame(flexure: Flexure, material) -> TaperedFrame:
    """The chain frame of a tapered arc or segment from its ellipse by quadrature.

    e1 is the ellipse's principal axis nearer to the uniform arc's e1 (across
    the symmetry axis, :meth:`flexval.geometry.shapes.Arc.symmetry_frame`),
    turned towards the start end; a straight segment keeps b = 0.
    """
    shape = flexure.shape
    found = curve_compliance(shape, flexure.section, material).ellipse
    _, uniform_e1, _ = shape.symmetry_frame()
    axes = found.axes.T  # rows: principal directions, spreads a^2, b^2
    spreads = [found.a**2, found.b**2]
    k = int(np.argmax(np.abs(axes @ uniform_e1)))
    e1 = axes[k] if axes[k] @ uniform_e1 > 0.0 else -axes[k]
    L = shape.length
    a = math.sqrt(spreads[k]) / L
    b = 0.0 if shape.kind == "segment" else math.sqrt(spreads[1 - k]) / L
    return TaperedFrame(found.center, np.array([e1, [-e1[1], e1[0]]]), a, b, found.weight)
