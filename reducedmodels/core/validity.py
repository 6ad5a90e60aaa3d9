"""The validity monitor's limits: where the flexibility models stop meaning anything.

A converged state is not necessarily a state a mechanism can reach: under
loads far beyond their design, the reduced models happily report a 12.6 mm
flexure with its ends 694 mm apart. Each connector's
:meth:`~flexval.reducedmodels.core.connector.Connector.validity` compares its state with
the limits below and names what it finds; the recorder stores the verdict
per load level (``LoadPath.valid``, ``LoadPath.validity``) without
stopping the run. The limits follow from the models' shared assumptions
(linear elastic material, small strain, large rotation), each derived from
:data:`MAX_STRAIN` or a model's own calibration rather than typed in:

* :data:`MAX_STRAIN`: material strain, and a flexure's chord against its arc length;
* :data:`MAX_CHORD_TURN`, :data:`MAX_RELATIVE_ROTATION`: a beam element's end rotations
  from its chord, a DCMM sub-arc's relative rotation;
* :data:`MIN_DET_F`, :data:`MAX_LINEAR_ROTATION`: continuum elements near inversion,
  ``ee``'s body rotations; the PRBM's fitted end rotations
  (:func:`flexval.reducedmodels.prbm.parameters.fitted_rotation`);
* :func:`bending_rotation_limit`, :func:`sway_load`: a varying section's thinnest part,
  a leaf's or a DCMM sub-arc's compression where the model has no geometric stiffness;
* :func:`unresolved_levels`: a level whose motion is round-off (:data:`RESOLVED_MOTION`).

Each limit's value and why are in the documentation's concepts page, "Where each model is
valid". ``tests/test_validity.py`` checks that every model's states at the paper's loads
are inside, and that DCMM_1 at 100 and 1000 times them is not.

Units: dimensionless strains, rad.
"""

from __future__ import annotations

import math

import numpy as np

from .geometrycache import per_centre_line

MAX_STRAIN = 0.02
"""Largest material strain (2 %) the models mean anything at.

Every model takes the material as linear elastic (Hooke's law in the beam's
axial and bending terms, Saint Venant-Kirchhoff or neo-Hookean with the
small-strain moduli in the continuum). Flexure materials leave their
elastic range below this (spring steels and titanium alloys near 0.5-1 %,
engineering polymers 1-3 %), and the hyperelastic laws differ from each
other by O(strain) = 2 % in stress there."""

MAX_CHORD_TURN = math.sqrt(6.0 * MAX_STRAIN)
"""Largest end rotation of a corotational beam element from its chord, rad (0.35).

An element whose end sections turn by +-a from its chord stands for an arc
of angle 2a, whose length exceeds the chord by a^2 / 6 to leading order:
at a = sqrt(6 MAX_STRAIN) the straight element's geometric error is as
large as the strain limit, and the element no longer resolves the
curvature (refine N)."""

MAX_RELATIVE_ROTATION = math.pi / 3.0
"""Largest relative rotation of a DCMM sub-arc's two end bodies, rad (60 deg).

DCMM measures a sub-arc's relative displacement v in the displaced frame of
one of its two bodies; the two frames' measures differ by (R(phi) - I) v,
of size 2 sin(phi / 2) |v|. At phi = pi / 3 that difference is |v| itself:
which frame is chosen changes the element's deformation by 100 %, so a
linear compliance acting on it has no meaning left."""

MAX_LINEAR_ROTATION = math.sqrt(2.0 * MAX_STRAIN)
"""Largest body rotation of a linear response (the EE), rad (0.2, 11.5 deg).

A linear response moves a point at distance r from a body's reference by
r theta along the tangent instead of along the circle, so every segment of
the body comes out stretched by sqrt(1 + theta^2) - 1 = theta^2 / 2: at
theta = sqrt(2 MAX_STRAIN) the linearised kinematics alone produce the
strain limit, and the point's own position is off by about theta / 2 = 10 %
of its motion."""

MIN_DET_F = 1.0 / math.sqrt(3.0)
"""Smallest area ratio det F of a continuum element (0.577): near inversion.

Saint Venant-Kirchhoff's nominal stress in uniaxial compression,
E lambda (lambda^2 - 1) / 2, peaks at lambda = 1/sqrt(3) and falls beyond
(the law loses stability); an element compressed that far is in a range no
flexure material shares. (At det F <= 0 the element is inverted and the
connector refuses the state outright.)"""


SCREEN_MARGIN = 1e-9
"""How close to a limit (in its own units) a vectorised screen sends a state to the exact check.

A connector's :meth:`~flexval.reducedmodels.core.connector.Connector.path_validity`
screens all the states of a path with array arithmetic, which may differ
from its scalar :meth:`~flexval.reducedmodels.core.connector.Connector.validity` in the
last bits (``np.hypot`` against ``math.dist``): states within this margin
of a limit, and beyond it, are judged by the scalar check, so the verdicts
are the scalar check's exactly."""


def bending_rotation_limit(
    weight: float, youngs_modulus: float, depth: float, thickness: float
) -> float:
    """Rotation (rad) at which a part's thinnest outer fibre reaches :data:`MAX_STRAIN` in bending.

    A moment M turns a part of rotational compliance w = ∫ ds / EI by
    phi = M w and strains the outer fibre of a section of thickness h by
    M h / (2 E I) = 6 M / (E b h^2), largest at the thinnest section t. So

        phi_max = MAX_STRAIN E b t^2 w / 6

    (for a uniform part of length L, w = L / EI and phi_max = 2 MAX_STRAIN L / h:
    the curvature 2 MAX_STRAIN / h of the limit strain over its length). A
    notch hinge, whose compliance gathers at its thinnest section, reaches
    it at a few degrees (the literature's notch-hinge rotation range).

    Parameters
    ----------
    weight : float
        w, 1/(N mm).
    youngs_modulus : float
        E, MPa.
    depth, thickness : float
        b and the smallest thickness t of the part, mm.
    """
    return MAX_STRAIN * youngs_modulus * depth * thickness**2 * weight / 6.0


def bending_strain_reasons(what: str, angles: np.ndarray, limits: np.ndarray) -> list[str]:
    """The rotation (rad) farthest beyond its own limit (rad), at most one reason naming it."""
    ratio = np.abs(np.asarray(angles, float)) / np.asarray(limits, float)
    k = int(np.argmax(ratio))
    if not ratio[k] > 1.0:
        return []
    return [
        f"{_label(what, k, ratio.size)} turned {math.degrees(abs(angles[k])):.3g} deg, beyond "
        f"the {math.degrees(limits[k]):.3g} deg at which its thinnest section's outer fibre "
        f"reaches the {100.0 * MAX_STRAIN:g} % strain limit"
    ]


def stretch_reasons(
    what: str, lengths: np.ndarray, reference: np.ndarray, one_sided: bool = False
) -> list[str]:
    """The worst stretch of ``lengths`` against ``reference`` (mm) beyond :data:`MAX_STRAIN`.

    ``one_sided``: only lengthening counts (a chord against its arc length
    may shorten freely by bending). Returns at most one reason, naming the
    worst entry (1-based) of ``what``.
    """
    strain = np.asarray(lengths, float) / np.asarray(reference, float) - 1.0
    measure = strain if one_sided else np.abs(strain)
    k = int(np.argmax(measure))
    if not measure[k] > MAX_STRAIN:
        return []
    return [
        f"{_label(what, k, measure.size)} stretched {100.0 * strain[k]:.3g} % "
        f"({lengths[k]:.4g} mm for {reference[k]:.4g} mm; limit {100.0 * MAX_STRAIN:g} %)"
    ]


def rotation_reasons(what: str, angles: np.ndarray, limit: float) -> list[str]:
    """The largest |angle| (rad) beyond ``limit`` (rad), at most one reason naming its entry."""
    measure = np.abs(np.asarray(angles, float))
    k = int(np.argmax(measure))
    if not measure[k] > limit:
        return []
    return [
        f"{_label(what, k, measure.size)} turned {math.degrees(measure[k]):.3g} deg "
        f"(limit {math.degrees(limit):.3g} deg)"
    ]


def _label(what: str, k: int, count: int) -> str:
    """``what`` with the 1-based entry number when there are several."""
    return what if count == 1 else f"{what} {k + 1}"


SHALLOW_RISE = 0.1
"""Largest distance of a curved flexure's centre line from its chord, as a fraction of the
chord, for the flexure to count as shallow: under compression it buckles like a column
(the range of shallow-arch theory), so the sway screen treats it as straight. A deeper
curve bends under its load instead."""


@per_centre_line
def is_shallow(shape) -> bool:
    """Whether ``shape`` is straight or within :data:`SHALLOW_RISE` of its chord (kept per
    centre line: every copy of a study over sections asks it of the same shapes)."""
    if shape.kind in ("segment", "notch"):
        return True
    start, end = (np.asarray(p, float) for p in shape.end_points)
    chord = end - start
    span = float(np.hypot(*chord))
    points = np.asarray(shape.point(np.linspace(0.0, shape.length, 129))) - start
    rise = np.abs(points[:, 0] * chord[1] - points[:, 1] * chord[0]) / span
    return float(rise.max()) <= SHALLOW_RISE * span


def sway_load(flexure, mechanism, parts: int = 1) -> float | None:
    """The compression (N) beyond which a model blind to a straight flexure's sway misses
    its buckling, Euler's load with the flexure's effective EI = L / int ds / EI (its end
    rotation's, exact for a taper or a notch): pi^2 EI / L^2 where both its bodies are held
    by something else too (the ends stay near parallel: a guided leaf's sway, as in a
    parallel guide), pi^2 EI / (4 L^2) where one of them hangs on this flexure alone (a
    cantilever). With ``parts`` > 1, the Euler load pi^2 EI / (L / parts)^2 of one of that
    many equal sub-arcs, each held by its neighbours (a DCMM_n sub-arc, blind to its own
    sway). A shallow curve (:func:`is_shallow`) counts as straight; None for a deeper one
    (an arc or a spline bends under its load instead of staying straight until it
    buckles).

    A screen, not a buckling analysis: ``flexval buckle`` gives the mechanism's own load.
    """
    if not is_shallow(flexure.shape):
        return None
    from flexval.geometry.compliance import curve_compliance

    length = flexure.shape.length
    weight = curve_compliance(flexure.shape, flexure.section, mechanism.material).ellipse.weight
    effective = length / weight  # N mm^2
    if parts > 1:
        return math.pi**2 * effective / (length / parts) ** 2
    held = [
        body == mechanism.ground
        or sum(body in f.bodies for f in mechanism.flexures)
        + sum(body in p.bodies for p in mechanism.pins)
        > 1
        for body in flexure.bodies
    ]
    factor = 1.0 if all(held) else 0.25
    return factor * math.pi**2 * effective / length**2


def sway_reasons(axial: np.ndarray, limit: float, span: str = "leaf") -> list[list[str]]:
    """Per level (rows of ``axial``, N, tension positive, (k, m)), the reason where the
    flexure's largest compression exceeds ``limit`` (N, :func:`sway_load` of the ``span``:
    ``"leaf"`` or ``"sub-arc"``); else none."""
    compression = -np.min(np.atleast_2d(axial), axis=1)
    whose = "its" if span == "leaf" else f"a {span}'s"
    return [
        [
            f"compression {c:.4g} N beyond the {span}'s Euler load {limit:.4g} N: this "
            f"model has no geometric stiffness for {whose} sway and cannot see it buckle "
            "(flexval buckle with a beam model gives the mechanism's load)"
        ]
        if c > limit
        else []
        for c in compression.tolist()
    ]


def linear_sway_verdicts(
    connectors, unit: list, lam: np.ndarray, dead: list | None = None
) -> list[list[str]]:
    """Per level of a linear response, the :func:`sway_reasons` of its connectors.

    ``unit`` and ``dead`` are each connector's section forces (or None) per unit load
    factor and of the weights alone; level k's normal force is dead + lam[k] unit. Each
    reason is prefixed with the connector's name, as the validity monitor's are.
    """
    found: list[list[str]] = [[] for _ in lam]
    for j, c in enumerate(connectors):
        if c.sway_load is None or unit[j] is None:
            continue
        base = 0.0 if dead is None or dead[j] is None else np.asarray(dead[j].axial)
        axial = base + np.outer(lam, np.asarray(unit[j].axial))
        for into, why in zip(found, sway_reasons(axial, c.sway_load, c.sway_span)):
            into.extend(f"{c.name}: {w}" for w in why)
    return found


TAPER_STIFFENING = 1.14
"""How much stiffer than 2D elasticity beam theory's section integrals make a linear taper
under a moment, over its contour slope squared: the slope's share of the error is
TAPER_STIFFENING slope^2, whatever h/L (0.51, 1.64 and 2.77 % at slopes 0.067, 0.12 and
0.156 rad over h/L 0.01-0.2 and h_0/h_1 1-8, ``benchmarks/taper_slope.py``)."""

TAPER_SLOPE = math.sqrt(0.005 / TAPER_STIFFENING)
"""Steepest contour slope |h_0 - h_1| / (2 L) (rad) of a linear taper at which beam theory's
section integrals stay within 0.5 % of 2D elasticity under a moment (0.066 rad, 3.8 deg);
the reduced models take no correction for the slope."""


def taper_slope(section) -> float | None:
    """A linearly tapered ``section``'s contour slope |h_0 - h_1| / (2 L), rad (None for any
    other section)."""
    profile = section.profile
    if profile is None or profile.kind != "taper":
        return None
    return abs(profile.end - profile.start) / (2.0 * profile.length)


def strain_reasons(lp, youngs_modulus: float, flexures: set[str] | None = None) -> list[list[str]]:
    """Per level of ``lp`` (a LoadPath with stresses), the reason where the surface strain of
    a flexure (of ``flexures``, default every one) exceeds :data:`MAX_STRAIN`: its peak
    stress (MPa) over E (MPa), the surface fibre peak where the path records one (a notch
    hinge's, stress concentration included: the continuum's recovered stress, a reduced
    model's K(s) times its beam formula), else the beam formula of its section forces
    (:func:`~flexval.reducedmodels.core.peaks.flexure_peaks`). The judge of the models
    whose own monitor does not see the strain: the continuum (its centre line's stretch
    misses a notch bent beyond the material's range) and a linear response."""
    from .peaks import flexure_peaks

    reasons: list[list[str]] = [[] for _ in lp.load]
    limit = MAX_STRAIN * youngs_modulus  # MPa
    for name, (stresses, places, fibre) in flexure_peaks(lp).items():
        if flexures is not None and name not in flexures:
            continue
        if max(stresses, default=0.0) <= limit and -min(stresses, default=0.0) <= limit:
            continue  # the common case, at a glance
        which = "surface fibre" if fibre else "outer fibre"
        for k, (stress, at) in enumerate(zip(stresses, places)):
            strain = abs(stress) / youngs_modulus
            if strain > MAX_STRAIN:
                reasons[k].append(
                    f"{name}: {which} strain {100 * strain:.3g} % at {at:.2f} of its "
                    f"length beyond the {100 * MAX_STRAIN:g} % limit"
                )
    return reasons


def merge_reasons(
    valid: list[bool], validity: list[str | None], extra: list[list[str]]
) -> tuple[list[bool], list[str | None]]:
    """A path's ``valid`` and ``validity`` with further reasons per level joined in."""
    if not any(extra):
        return valid, validity
    out_valid, out_why = [], []
    for ok, why, more in zip(valid, validity, extra):
        reasons = ([why] if why else []) + more
        out_valid.append(ok and not more)
        out_why.append("; ".join(reasons) if reasons else None)
    return out_valid, out_why


RESOLVED_MOTION = 1e3
"""A load level's motion must exceed the path's round-off floor this many times
(:func:`unresolved_levels`): its answer is then within 0.1 % of the exact one."""

ROUND_OFF_GROWTH = 2.0
"""The round-off of a converged state, in units of double precision times the square root
of the number of unknowns (random accumulation): the largest measured on the open chain's
paths at 1e-9 to 1e-17 of the paper's loads was 1.54 (``beam:100`` under f-, 900
unknowns); ``tests/test_resolution.py`` measures it again."""


def unresolved_levels(
    factors: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    rotation: np.ndarray,
    size: np.ndarray | float,
    unknowns: np.ndarray | int,
    weighted: np.ndarray | bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which levels of traced paths move the target by less than :data:`RESOLVED_MOTION`
    times the path's round-off: their answers are noise.

    ``factors`` (levels,) are the load factors the paths share (or one path's loads: only
    where they are zero matters); ``dx``, ``dy`` (mm) and
    ``rotation`` (rad) are (..., levels), one row per path (a batch's copies at once);
    ``size`` (mm), ``unknowns`` and ``weighted`` one per path. The motion is the target's
    translation over the mechanism's size and its rotation, from the level at rest. The
    floor is the round-off of a state of ``unknowns`` coordinates
    (:data:`ROUND_OFF_GROWTH`) and, where the paths start at rest without weights
    (``weighted`` False), the motion reported there: a model whose rest state is in
    balance only to round-off (the continuum's meshes, to about 1e-13) moves that far
    under no load, and every level carries it. A nonlinear model's Newton stops on
    corrections below a fixed fraction of the size, so below the floor its answer can
    have the wrong sign; a linear response (``ee``) needs no screen.

    Returns
    -------
    mask : bool array (..., levels)
        True at a loaded level within the floor.
    moved, floor : arrays (..., levels) and (...)
        Each level's motion and each path's floor (fractions of the size, rad).
    """
    factors = np.asarray(factors, float)
    size = np.asarray(size, float)[..., None]
    motion = np.stack([np.asarray(dx) / size, np.asarray(dy) / size, np.asarray(rotation)])
    at_rest = factors.size > 0 and factors[0] == 0.0
    base = motion[..., :1] if at_rest else np.zeros_like(motion[..., :1])
    moved = np.abs(motion - base).max(axis=0)
    offset = np.abs(base[..., 0]).max(axis=0)
    eps = np.finfo(float).eps
    floor = ROUND_OFF_GROWTH * eps * np.sqrt(np.maximum(unknowns, 1)) * np.maximum(1.0, offset)
    if at_rest:
        floor = np.where(weighted, floor, np.maximum(floor, offset))
    mask = (moved < RESOLVED_MOTION * floor[..., None]) & (factors != 0.0)
    return mask, moved, floor


def resolution_reason(moved: float, floor: float) -> str:
    """Why a level of :func:`unresolved_levels` is not valid (``moved`` and ``floor`` as
    fractions of the mechanism's size)."""
    return (
        f"the load moves the target by {moved:.2g} of the mechanism's size, within "
        f"{RESOLVED_MOTION:.0f} times the round-off of this model's state ({floor:.2g}): "
        "double precision does not resolve this load"
    )
