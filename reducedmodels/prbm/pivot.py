"""One-pivot pseudo-rigid-body model of a notch hinge (the ``prbm`` of a ``notch`` flexure).

The classic model of a notch hinge (Paros and Weisbord; Howell's
pseudo-rigid-body model of a small-length flexural pivot): the two bodies
turn about a revolute joint at the hinge's centre P (the middle of its axis,
where its symmetric contour puts the centre of elasticity) with a torsion
spring of stiffness

    k = 1 / c_theta,    c_theta = ∫ ds / EI(s)   (the hinge's rotational compliance),

so that a moment turns the hinge exactly as the Euler-Bernoulli integral
says, at any rotation. The joint's translations are kept elastic rather
than rigid, with the hinge's own compliances measured in its current axis
frame {e1 along the axis, e2 across} (turned by the mean rotation of the two
bodies):

    along the axis   c_1 = ∫ ds / EA(s)                (axial stretch),
    across the axis  c_2 = ∫ ds / (k_s G A(s))          (shear, k_s = 5/6),

so the pivot is practically rigid (these compliances are a few 1e-4 of the
bending ones), no Lagrange multiplier is needed and hinges in parallel stay
well posed. Left out of the classic model (the option ``eb``): the transverse
motion of the hinge's centre from bending (the ellipse's w a^2; the compliance
is concentrated at the thinnest section, so a is a small fraction of the
hinge's length). A calibrated hinge (the default,
:mod:`flexval.reducedmodels.notchcorrection`) takes it, c_2 = ∫ ds / (k_s G A) + w a^2
with its corrected E and G, so that the pivot's linear compliance is the hinge's own
(the ellipse of elasticity's, about its centre), and its bending kinematics: a hinge
bent by theta is an arc whose angle grows with the compliance, theta W(s),
W(s) = ∫_0^s ds / EI over ∫_0^L ds / EI, not a joint at P, and its two bodies' points
at P part along the axis (the mid frame's e_1) by

    delta(theta) = ∫_0^L cos(theta (W(s) - 1/2)) ds - L cos(theta / 2)

(0 for the compliance gathered at P, L theta^2 / 12 for a uniform one; O(theta^2),
so the linear compliance stays the same): a filleted hinge with a long flat bends like a
short leaf, and a joint at P puts its end 0.3 % short across the axis under a moment at
0.2 rad. The energy of the relative state is

    E = 1/2 k (theta_b - theta_a)^2 + 1/2 e^T S(phi) e,
    e = d - delta(theta_b - theta_a) u(phi),   d = p_b(P) - p_a(P),
    S(phi) = R(phi) Q diag(1/c_1, 1/c_2) Q^T R(phi)^T,   u(phi) = R(phi) Q e_1,
    phi = (theta_a + theta_b) / 2,

with p_x(P) the material point of body x at P (Q: the axis frame at rest).
Gradient and Hessian are exact (see :meth:`NotchPivotConnector.evaluate`).

Units: mm, N, N mm, rad.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from flexval.geometry import Flexure, Mechanism
from flexval.geometry.compliance import curve_compliance
from flexval.geometry.kinematics import rotate_xy

from ..core.bending import cumulative_compliance, trapezoid
from ..core.connector import Connector
from ..core.inertia import MassPoints, line_density, rigid_pieces
from ..core.sections import SectionForces, statics_section_forces
from ..core.validity import (
    MAX_STRAIN,
    bending_rotation_limit,
    bending_strain_reasons,
    stretch_reasons,
)
from ..dcmm.subarcs import thinnest

_J = np.array([[0.0, -1.0], [1.0, 0.0]])
"""The rotation by +90 deg: d R(theta) / d theta = J R(theta)."""


KINEMATIC_TERMS = 8
"""Terms of the even series of delta(theta) (:meth:`NotchPivotConnector.parting`): the
first left out is below (theta/2)^18 / 18! of L, 4e-22 L at theta = 1 rad."""

STATIONS = 257
"""Evenly spaced stations along a hinge where the pivot model reports its section forces:
where a force across the hinge puts the peak stress off the waist. Its beam-formula peak on
them is within 1.1e-4 of the continuous maximum of 6 F (L - s) / (b h(s)^2) on the four
contours (measured; 129 stations left 3.8e-4 on an elliptical one)."""


def station_fractions(profile) -> np.ndarray:
    """The pivot's stations as arc-length fractions from the hinge's start, 0..1: an even grid
    of :data:`STATIONS` and, on a corner-filleted contour, the ends of its flat (where the
    thickness starts to grow, and where a force across the hinge puts the peak)."""
    grid = np.linspace(0.0, 1.0, STATIONS)
    if profile.contour == "corner-filleted":
        r = profile.fillet_radius / profile.length
        grid = np.concatenate([grid, [r, 1.0 - r]])
    grid = np.unique(grid)
    return np.concatenate([grid[grid <= 0.5], grid[grid >= 0.5]])  # the centre twice


class NotchPivotConnector(Connector):
    """The one-pivot PRBM of a notch hinge (a
    :class:`~flexval.reducedmodels.core.connector.Connector`).

    No internal coordinates: the two bodies' poses carry the hinge.

    Parameters
    ----------
    flexure : Flexure
        A straight flexure with a notch profile (``section.profile.kind == "notch"``).
    mechanism : Mechanism
        For the material and the bodies' reference points.
    """

    def __init__(self, flexure: Flexure, mechanism: Mechanism):
        shape, section, material = flexure.shape, flexure.section, mechanism.material
        self.name = flexure.name
        self.bodies = tuple(flexure.bodies)
        self.length = shape.length
        found = curve_compliance(shape, section, material)
        self.compliance = found.ellipse.weight  # c_theta, 1/(N mm)
        self.stiffness = 1.0 / self.compliance  # k, N mm
        axis = np.asarray(shape.tangent(0.5 * self.length), float)
        across = np.array([-axis[1], axis[0]])
        axial = float(axis @ found.axial @ axis)  # ∫ ds / EA, mm/N
        shear = float(across @ found.shear @ across)  # ∫ ds / (k_s G A), mm/N
        if material.shear_flexible:  # a calibrated hinge: its whole linear compliance
            ell = found.ellipse
            spread = ell.axes @ np.diag([ell.a**2, ell.b**2]) @ ell.axes.T * ell.weight
            shear += float(axis @ spread @ axis)  # the bending term w a^2 across the axis
        self.translation = (1.0 / axial, 1.0 / shear)  # N/mm along and across the axis
        frame = np.column_stack([axis, across])
        self._s0 = frame @ np.diag(self.translation) @ frame.T  # S at rest, N/mm
        self._axis = axis  # Q e_1: the axis at rest, the direction the pivot points part along
        self.pivot = np.asarray(shape.point(0.5 * self.length), float)
        self._forward = flexure.start_body == self.bodies[0]
        ends = shape.end_points
        self._ends = ends if self._forward else ends[::-1]  # flexure ends on a, b
        self._ref = np.array([mechanism.bodies[b].reference for b in self.bodies])
        self._r = self.pivot - self._ref  # the pivot's offsets from a's and b's references
        self._end_rel = self._ends - self._ref
        self._shape, self._section = shape, section
        #: the stations' arc-length fractions: an even grid and the contour's own corners
        self._fractions = station_fractions(section.profile)
        # the series of delta(theta): (-1)^k theta^2k / (2k)! (mu_2k - L / 2^2k), k >= 1
        self._parting = _parting_moments(shape.length, section) if material.shear_flexible else None
        # (k, c_k) of the series, highest k first (Horner)
        self._series = () if self._parting is None else tuple(enumerate(self._parting, 1))[::-1]
        self.rotation_limit = bending_rotation_limit(
            self.compliance,
            material.youngs_modulus,
            section.depth,
            thinnest(flexure),
        )
        """Hinge rotation at which the thinnest section's outer fibre reaches MAX_STRAIN, rad."""

    def _relative(self, pose_a: np.ndarray, pose_b: np.ndarray):
        """d, its derivative columns (2, 6) and the rotated pivot offsets R(theta) r."""
        ta, tb = float(pose_a[2]), float(pose_b[2])
        ra = np.array(rotate_xy(ta, *self._r[0]))
        rb = np.array(rotate_xy(tb, *self._r[1]))
        d = (pose_b[:2] + rb) - (pose_a[:2] + ra)
        D = np.zeros((2, 6))
        D[:, 0:2] = -np.eye(2)
        D[:, 2] = -_J @ ra
        D[:, 3:5] = np.eye(2)
        D[:, 5] = _J @ rb
        return d, D, ra, rb

    def parting(self, turn: float) -> tuple[float, float, float]:
        """delta (mm) at the relative rotation ``turn`` (rad) and its first and second
        derivatives in it: the bending kinematics (module text); zero for the classic
        pivot (``eb``)."""
        if self._parting is None:
            return 0.0, 0.0, 0.0
        # delta = sum c_k x^k with x = turn^2 (Horner), c_k = (-1)^k (mu_2k - L/2^2k)/(2k)!:
        # delta' = 2 turn sum k c_k x^(k-1), delta'' = sum 2k (2k - 1) c_k x^(k-1)
        x = turn * turn
        value = slope = curve = 0.0
        for k, c in self._series:
            value = value * x + c
            slope = slope * x + k * c
            curve = curve * x + k * (2 * k - 1) * c
        return value * x, 2.0 * turn * slope, 2.0 * curve

    def _stiffness(self, phi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """S(phi) and its first and second derivatives in phi, N/mm."""
        c, s = math.cos(phi), math.sin(phi)
        R = np.array([[c, -s], [s, c]])
        S = R @ self._s0 @ R.T
        S1 = _J @ S - S @ _J
        S2 = -2.0 * S - 2.0 * _J @ S @ _J
        return S, S1, S2

    def evaluate(self, pose_a, pose_b, internal):
        """Energy (N mm), gradient (6) and dense Hessian (6, 6) over [pose_a, pose_b].

        With Δθ = θb - θa, spin = dΔθ/dq, phi_q = (0, 0, 1/2, 0, 0, 1/2),
        f = delta(Δθ) u(phi) (u' = J u, u'' = -u), e = d - f and E = de/dq
        = D - delta u' phi_q^T - delta' u spin^T:

            g = k Δθ spin + E^T S e + 1/2 (e^T S' e) phi_q,
            H = k spin spin^T + E^T S E
                + (E^T S' e) phi_q^T + phi_q (E^T S' e)^T + 1/2 (e^T S'' e) phi_q phi_q^T
                + (S e) . d2e/dq2,

        d2e/dq2 = d2d/dq2 - d2f/dq2: d2d/dθa2 = R(θa) r_a and d2d/dθb2 = -R(θb) r_b, and
        d2f = -delta u phi_q phi_q^T + delta' u' (phi_q spin^T + spin phi_q^T)
        + delta'' u spin spin^T (S' = J S - S J, S'' = -2 S - 2 J S J: the derivatives of
        R S0 R^T).
        """
        pose_a, pose_b = np.asarray(pose_a, float), np.asarray(pose_b, float)
        d, D, ra, rb = self._relative(pose_a, pose_b)
        phi = 0.5 * (float(pose_a[2]) + float(pose_b[2]))
        S, S1, S2 = self._stiffness(phi)
        turn = float(pose_b[2] - pose_a[2])
        spin = np.array([0.0, 0.0, -1.0, 0.0, 0.0, 1.0])
        half = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.5])
        delta, slope, curve = self.parting(turn)
        bent = self._parting is not None
        if bent:  # e = d - delta u: its columns of the angles (phi_q, spin: 1/2 and -+1 there)
            ux, uy = rotate_xy(phi, *self._axis)  # u; du = J u = (-uy, ux)
            d[0] -= delta * ux
            d[1] -= delta * uy
            D[0, 2] += slope * ux + 0.5 * delta * uy
            D[1, 2] += slope * uy - 0.5 * delta * ux
            D[0, 5] -= slope * ux - 0.5 * delta * uy
            D[1, 5] -= slope * uy + 0.5 * delta * ux
        Sd = S @ d
        energy = 0.5 * self.stiffness * turn * turn + 0.5 * float(d @ Sd)
        twist = D.T @ (S1 @ d)
        gradient = self.stiffness * turn * spin + D.T @ Sd + 0.5 * float(d @ S1 @ d) * half
        hessian = self.stiffness * np.outer(spin, spin) + D.T @ S @ D
        hessian += np.outer(twist, half) + np.outer(half, twist)
        hessian += 0.5 * float(d @ S2 @ d) * np.outer(half, half)
        hessian[2, 2] += float(Sd @ ra)
        hessian[5, 5] -= float(Sd @ rb)
        if bent:  # - (S e) . d2f, on the angles' 2 x 2 block: half = 1/2 (1, 1), spin = (-1, 1)
            sx, sy = float(Sd[0]), float(Sd[1])
            along, across = sx * ux + sy * uy, sy * ux - sx * uy
            same = 0.25 * delta * along - curve * along  # (theta_a, theta_a), (theta_b, theta_b)
            hessian[2, 2] += same + slope * across
            hessian[5, 5] += same - slope * across
            hessian[2, 5] += 0.25 * delta * along + curve * along
            hessian[5, 2] = hessian[2, 5]
        return energy, gradient, hessian

    def _polyline(self, pose_a, pose_b) -> np.ndarray:
        """end_a, the hinge centre (mean of the two bodies' pivot points), end_b; (3, 2) mm."""
        (xa, ya, ta), (xb, yb, tb) = np.asarray(pose_a, float), np.asarray(pose_b, float)
        ea = np.array(rotate_xy(ta, *self._end_rel[0])) + (xa, ya)
        eb = np.array(rotate_xy(tb, *self._end_rel[1])) + (xb, yb)
        pa = np.array(rotate_xy(ta, *self._r[0])) + (xa, ya)
        pb = np.array(rotate_xy(tb, *self._r[1])) + (xb, yb)
        return np.array([ea, 0.5 * (pa + pb), eb])

    def shape(self, pose_a, pose_b, internal) -> np.ndarray:
        """Polyline flexure end on a, hinge centre, flexure end on b (mm)."""
        return self._polyline(pose_a, pose_b)

    def validity(self, pose_a, pose_b, internal) -> list[str]:
        """Hinge rotation beyond its strain limit; the axis stretched beyond MAX_STRAIN.

        The rotation limit is :func:`~flexval.reducedmodels.core.validity.bending_rotation_limit`
        of the hinge's compliance at its thinnest section; the stretch is the
        pivot points' separation along the axis, less the bending kinematics' delta, over
        the hinge's length.
        """
        turn = float(pose_b[2] - pose_a[2])
        d, _, _, _ = self._relative(np.asarray(pose_a, float), np.asarray(pose_b, float))
        phi = 0.5 * float(pose_a[2] + pose_b[2])
        axis = self._ends[1] - self._ends[0]
        axis = np.array(rotate_xy(phi, *axis)) / self.length
        stretch = float(axis @ d) - self.parting(turn)[0]  # lengthening positive
        reasons = bending_strain_reasons("hinge", np.array([turn]), np.array([self.rotation_limit]))
        if abs(stretch) / self.length > MAX_STRAIN:
            reasons += stretch_reasons(
                "hinge axis", np.array([self.length + stretch]), np.array([self.length])
            )
        return reasons

    def section_forces(self, pose_a, pose_b, internal, gradient=None) -> SectionForces:
        """Normal force (N) and bending moment (N mm) along the hinge, at :data:`STATIONS`.

        The hinge transmits one wrench (the gradient on body b's pose),
        carried by statics along the polyline of :meth:`shape` (each half
        rigid with its body), at stations along both halves, the centre (the
        thinnest section) twice: under a force across the hinge the moment
        grows along it, and the peak stress leaves the waist for where the
        section has not yet thickened enough (a corner-filleted hinge's
        flat ends, which are stations of their own).
        """
        if gradient is None:
            gradient = self.evaluate(pose_a, pose_b, internal)[1]
        ends = self._polyline(pose_a, pose_b)
        fractions = self._fractions
        half = fractions <= 0.5
        along = np.where(half, fractions / 0.5, (fractions - 0.5) / 0.5)[:, None]
        points = np.where(
            half[:, None],
            ends[0] + along * (ends[1] - ends[0]),
            ends[1] + along * (ends[2] - ends[1]),
        )
        return statics_section_forces(
            points,
            fractions,
            np.asarray(gradient, float)[3:6],
            np.asarray(pose_b, float),
            reverse=not self._forward,
        )

    def mass_points(self, density: float) -> MassPoints:
        """The flexure's mass (density t/mm^3) in two rigid halves, one on each body.

        Each half of the hinge (from its end to the centre) rides rigidly on
        its body with its exact mass, centre of mass and rotary inertia
        (:func:`flexval.reducedmodels.core.inertia.rigid_pieces`, rho A(s)).
        """
        bounds = np.array([0.0, 0.5 * self.length, self.length])
        mass, rel, rotary = rigid_pieces(
            self._shape, self._forward, bounds, self._ref, line_density(density, self._section)
        )
        return MassPoints(np.array([np.arange(3), np.arange(3, 6)]), rel, mass, rotary)


@functools.lru_cache(maxsize=256)
def _parting_moments(length: float, section) -> tuple[float, ...]:
    """The coefficients (-1)^k (mu_2k - L / 2^2k) / (2k)!, k = 1..:data:`KINEMATIC_TERMS`, of
    the series of delta(theta) (mm) for a hinge of ``length`` (mm) and varying ``section``:
    mu_j = ∫_0^L (W(s) - 1/2)^j ds, W the normalised cumulative bending compliance
    (:func:`flexval.reducedmodels.core.bending.cumulative_compliance`);
    cos(x) = sum (-1)^k x^2k / (2k)!. Remembered per hinge: a study builds the same hinges
    again and again."""
    along, share = cumulative_compliance(section, 0.0, length)
    centred = share - 0.5
    return tuple(
        (-1) ** k * (trapezoid(centred ** (2 * k), along) - length / 4**k) / math.factorial(2 * k)
        for k in range(1, KINEMATIC_TERMS + 1)
    )
