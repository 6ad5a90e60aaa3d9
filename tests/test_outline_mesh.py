"""Meshes of a flexure's true outline (tapers, notches, splines).

References: the Gmsh meshes of uniform arcs and segments (the outline map
must give the same nodes), the thickness law h(s) itself (surface nodes on
c(s) +- h(s)/2 n(s)), the outline's area by scipy's quad, the grading rule
(element length over local thickness) and the nesting of levels.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from flexval.geometry import Arc, Section, Segment
from flexval.geometry.mesh import mesh_flexure
from flexval.geometry.outline import flexure_mesh, mesh_outline, stations
from flexval.geometry.profiles import LinearTaper, NotchProfile
from flexval.geometry.shapes import Spline

pytestmark = pytest.mark.usefixtures("private_mesh_cache")

ARC = Arc((1.0, -2.0), 5.0, math.radians(30.0), math.radians(100.0))
SEGMENT = Segment((0.0, 0.0), (3.0, 4.0))


def _sorted_nodes(nodes: np.ndarray) -> np.ndarray:
    return nodes[np.lexsort(np.round(nodes, 9).T[::-1])]


@pytest.mark.parametrize("shape", [SEGMENT, ARC], ids=["segment", "arc"])
@pytest.mark.parametrize("level", [0, 1, 2])
def test_outline_map_of_a_uniform_flexure_is_the_gmsh_mesh(shape, level):
    """The map c(s) + eta h/2 n(s) of a uniform arc or segment puts its nodes where Gmsh's
    transfinite mesh (snapped to the polar map) has them, to round-off (measured 1e-14 mm)."""
    h = 0.5
    gmsh = mesh_flexure(shape, h, level, use_cache=False)
    outline = mesh_outline(shape, Section(1.0, h), level, use_cache=False)
    assert (outline.n_t, outline.n_l) == (gmsh.n_t, gmsh.n_l)
    np.testing.assert_allclose(
        _sorted_nodes(outline.nodes), _sorted_nodes(gmsh.nodes), rtol=0, atol=1e-12
    )


def test_uniform_arcs_and_segments_keep_their_gmsh_meshes():
    """flexure_mesh gives a uniform arc or segment the same arrays as mesh_flexure (the
    continuum's uniform flexures are unchanged), a varying section its outline."""
    for shape in (SEGMENT, ARC):
        a, b = flexure_mesh(shape, Section(1.0, 0.5), 1), mesh_flexure(shape, 0.5, 1)
        for name in ("nodes", "elements", "start_face", "end_face", "centre_line"):
            assert np.array_equal(getattr(a, name), getattr(b, name))
    taper = Section(1.0, 0.4, LinearTaper(0.6, 0.4, SEGMENT.length))
    c = flexure_mesh(SEGMENT, taper, 1)
    assert c.nodes.shape == mesh_outline(SEGMENT, taper, 1).nodes.shape


def _notch(contour: str = "circular", **extra) -> tuple[Segment, Section]:
    R, t = 2.0, 0.2
    shape = Segment((1.0, 1.0), (1.0 + 2 * R * 0.6, 1.0 + 2 * R * 0.8))
    height = t + 2 * extra.get("fillet_radius", R)
    profile = NotchProfile(contour, t, height, shape.length, **extra)
    return shape, Section(1.0, t, profile)


@pytest.mark.parametrize(
    "contour, extra",
    [
        ("circular", {}),
        ("elliptical", {}),
        ("corner-filleted", {"fillet_radius": 0.5}),
        ("power", {"exponent": 1.0}),
    ],
)
def test_notch_mesh_follows_the_outline_and_is_graded_by_the_thickness(contour, extra):
    """Every node lies on c(s) + eta h(s)/2 n(s) (to round-off); the end faces are the
    normals at the ends, as thick as h(0) and h(L); elements are at most as long as the
    local thickness and the thickness changes across one by about half of itself at most
    (measured up to 0.62 at level 0 for the rule's 0.5, on the steep flanks), both halved
    at level 1; the profile's breakpoints are element boundaries; and every element of
    level 0 is split in two at level 1."""
    shape, section = _notch(contour, **extra)
    L, t = shape.length, shape.tangent(0.0)
    n = np.array([-t[1], t[0]])
    for level in (0, 1):
        mesh = mesh_outline(shape, section, level)
        rel = mesh.nodes - np.asarray(shape.start, float)
        s, v = rel @ t, rel @ n
        h = section.thickness_at(np.clip(s, 0.0, L))
        assert np.all(np.abs(v) <= 0.5 * h + 1e-12)
        surface = np.abs(np.abs(v) - 0.5 * h) < 1e-12
        assert surface.sum() == 2 * (2 * mesh.n_l + 1)
        for face, at in ((mesh.start_face, 0.0), (mesh.end_face, L)):
            np.testing.assert_allclose(s[face], at, atol=1e-12)
            assert v[face].max() - v[face].min() == pytest.approx(
                float(section.thickness_at(at)), rel=1e-12
            )
        np.testing.assert_allclose(v[mesh.centre_line], 0.0, atol=1e-12)
        vertex = stations(L, section, level)[0::2]
        middle = 0.5 * (vertex[1:] + vertex[:-1])
        assert np.max(np.diff(vertex) / section.thickness_at(middle)) * 2**level < 1.0 + 1e-9
        h = section.thickness_at(vertex)
        assert np.max(np.abs(np.diff(h)) / np.minimum(h[1:], h[:-1])) * 2**level < 0.7
        for b in section.profile.breakpoints:
            assert np.min(np.abs(vertex - b)) < 1e-12
    coarse, fine = stations(L, section, 0)[0::2], stations(L, section, 1)[0::2]
    np.testing.assert_allclose(fine[0::2], coarse, rtol=0, atol=1e-12)


def test_mesh_area_is_the_outline_area():
    """The isoparametric mesh's area converges to int h(s) ds (quad): measured relative
    errors 3.8e-3, 6.7e-4, 1.0e-4 at levels 0, 1, 2 on a circular notch (ratios 5.8, 6.6);
    bound: each level at least 4 times closer, level 1 within 1e-3."""
    from flexval.validation.continuum.solid import Solid

    shape, section = _notch()
    exact = quad(lambda s: float(section.thickness_at(s)), 0.0, shape.length, limit=200)[0]
    errors = []
    for level in (0, 1, 2):
        mesh = mesh_outline(shape, section, level)
        solid = Solid(mesh.nodes, mesh.elements, law=None, depth=1.0)
        errors.append(abs(solid.weight.sum() / exact - 1.0))
    assert errors[1] < errors[0] / 4 and errors[2] < errors[1] / 4 and errors[1] < 1e-3


def test_spline_and_taper_outline():
    """A tapered spline: surface nodes at h(s)/2 from the centre line (measured along the
    normal of the station), centre nodes on the spline; an outline thicker than the
    diameter of curvature is refused, naming the arc length."""
    spline = Spline(((0.0, 0.0), (4.0, 1.5), (8.0, 0.0), (12.0, -1.0)))
    section = Section(1.0, 0.3, LinearTaper(0.5, 0.3, spline.length))
    mesh = mesh_outline(spline, section, 1)
    s = stations(spline.length, section, 1)
    np.testing.assert_allclose(mesh.nodes[mesh.centre_line], spline.point(s), atol=1e-12)
    for face in (0, 2 * mesh.n_t):
        side = mesh.nodes[np.arange(s.size) * (2 * mesh.n_t + 1) + face]
        gap = np.hypot(*(side - spline.point(s)).T)
        np.testing.assert_allclose(gap, 0.5 * section.thickness_at(s), rtol=1e-12)
    bent = Spline(((0.0, 0.0), (1.0, 1.0), (2.0, 0.0)))
    with pytest.raises(ValueError, match="folds over"):
        mesh_outline(bent, Section(1.0, 1.5), 0, use_cache=False)


def test_outline_mesh_cache_round_trip():
    """A cached outline mesh is read back identical; another thickness law is another entry."""
    shape, section = _notch()
    fresh = mesh_outline(shape, section, 1, use_cache=False)
    mesh_outline(shape, section, 1)
    again = mesh_outline(shape, section, 1)
    for name in ("nodes", "elements", "start_face", "end_face", "centre_line"):
        assert np.array_equal(getattr(fresh, name), getattr(again, name))
    other = Section(1.0, 0.25, NotchProfile("circular", 0.25, 4.2, shape.length))
    assert not np.array_equal(mesh_outline(shape, other, 1).nodes, fresh.nodes)
