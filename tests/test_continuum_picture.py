"""The continuum picture: its colour range leaves out the end layers, and the PNG is drawn.

The range and the mesh helpers are tested on hand-built quad9 strips (no Gmsh), the
picture on the open chain at mesh level 0 and on a scene with a pin.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexval.validation.continuum.picture import (
    boundary_loops,
    interior_nodes,
    quad9_triangles,
    robust_range,
)

pytestmark = pytest.mark.usefixtures("private_mesh_cache")


def strip(length: float, h: float, n_l: int, n_t: int, bend: float = 0.0):
    """A quad9 strip along x (mm), optionally bent into y = bend x^2; nodes, elements,
    centre line."""
    nx, ny = 2 * n_l + 1, 2 * n_t + 1
    x, y = np.meshgrid(np.linspace(0, length, nx), np.linspace(-h / 2, h / 2, ny), indexing="ij")
    nodes = np.column_stack([x.ravel(), y.ravel() + bend * x.ravel() ** 2])
    idx = np.arange(nx * ny).reshape(nx, ny)
    elements = []
    for i in range(0, nx - 1, 2):
        for j in range(0, ny - 1, 2):
            elements.append(
                [
                    idx[i, j],
                    idx[i + 2, j],
                    idx[i + 2, j + 2],
                    idx[i, j + 2],
                    idx[i + 1, j],
                    idx[i + 2, j + 1],
                    idx[i + 1, j + 2],
                    idx[i, j + 1],
                    idx[i + 1, j + 1],
                ]
            )
    return nodes, np.array(elements), idx[:, n_t]


def test_interior_nodes_are_those_beyond_the_layers():
    length, h = 10.0, 0.5
    nodes, _, line = strip(length, h, 20, 2)
    layer = 2 * h
    inside, fraction = interior_nodes(nodes, line, layer)
    x = nodes[:, 0]
    assert np.array_equal(inside, (x >= layer - 1e-12) & (length - x >= layer - 1e-12))
    assert np.allclose(fraction, x / length)


def test_robust_range_leaves_out_the_end_layers():
    length, h = 10.0, 0.5
    layer = 2 * h
    fields = []
    for scale in (1.0, 0.5):
        nodes, _, line = strip(length, h, 20, 2)
        x, y = nodes.T
        stress = scale * 40.0 * (2 * y / h) * (1.0 + x / length)  # bending, MPa
        corners = (np.isclose(x, 0) | np.isclose(x, length)) & np.isclose(np.abs(y), h / 2)
        stress[corners] = -1000.0  # the singular corners of the end faces
        fields.append((stress, interior_nodes(nodes, line, layer)[0], nodes))
    values = [f[0] for f in fields]
    inside = [f[1] for f in fields]
    rng = robust_range(values, inside, signed=True)
    expected = np.max(np.abs(values[0][inside[0]]))
    assert rng.high == pytest.approx(expected) and rng.low == -rng.high
    assert rng.high == pytest.approx(40.0 * (2.0 - layer / length))  # at x = L - layer
    assert rng.flexure == 0 and inside[0][rng.node]
    assert rng.peak == pytest.approx(values[0][rng.node]) and abs(rng.peak) == rng.high
    x_peak = fields[0][2][rng.node, 0]
    assert layer <= x_peak <= length - layer
    assert rng.excluded_peak == pytest.approx(1000.0) and not rng.by_percentile
    # von Mises: the range starts at zero
    unsigned = robust_range([np.abs(v) for v in values], inside, signed=False)
    assert unsigned.low == 0.0 and unsigned.high == pytest.approx(expected)


def test_robust_range_falls_back_to_a_percentile_when_the_layers_cover_the_flexure():
    nodes, _, line = strip(2.0, 0.5, 4, 1)
    inside, _ = interior_nodes(nodes, line, layer=1.5)
    assert not inside.any()
    values = np.linspace(-5.0, 5.0, nodes.shape[0])
    rng = robust_range([values], [inside], signed=True, percentile=90.0)
    assert rng.by_percentile
    assert rng.high == pytest.approx(np.percentile(np.abs(values), 90.0))
    assert rng.excluded_peak == pytest.approx(5.0)


def test_mesh_outline_and_triangles_of_a_bent_strip():
    n_l, n_t = 6, 2
    nodes, elements, _ = strip(5.0, 0.4, n_l, n_t, bend=0.1)
    (loop,) = boundary_loops(elements)
    assert loop[0] == loop[-1]
    assert len(loop) - 1 == 2 * (2 * n_l) + 2 * (2 * n_t)  # every boundary node once
    assert set(loop) == set(np.flatnonzero(_on_strip_boundary(nodes, n_l, n_t)))
    tri = quad9_triangles(elements)
    assert tri.shape == (8 * len(elements), 3)
    p = nodes[tri]
    a, b = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = 0.5 * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    assert np.all(area > 0)  # counterclockwise, none degenerate


def _on_strip_boundary(nodes, n_l, n_t):
    i, j = np.divmod(np.arange(nodes.shape[0]), 2 * n_t + 1)
    return (i == 0) | (i == 2 * n_l) | (j == 0) | (j == 2 * n_t)


def _trace(scene_name: str, case_name: str, levels: int):
    from flexval.geometry import load_scene
    from flexval.reducedmodels import LoadControl, PathRecorder, trace
    from flexval.validation.continuum.run import build_system

    scene = load_scene(scene_name)
    case = scene.load_case(case_name)
    system = build_system(scene.mechanism, 0)
    _, full = PathRecorder(system, case, "continuum:0", scene.name, {}).run(
        trace(system, system.loads(case), LoadControl(case.factors(levels)))
    )
    return scene, case, system, full.state


def test_picture_of_the_open_chain_is_written(tmp_path):
    import matplotlib.image

    from flexval.validation.continuum.output import ContinuumConnector, flexure_fields, render_png

    scene, case, system, state = _trace("open_chain", "f+", 3)
    png = render_png(tmp_path / "open_chain.png", system, state, case, "open_chain f+")
    assert [p.name for p in tmp_path.iterdir()] == ["open_chain.png"]  # no temporary left
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 50_000
    image = matplotlib.image.imread(png)[..., :3]
    assert image.shape[0] > 800 and image.shape[1] > 1400
    assert np.mean(np.any(image < 0.95, axis=-1)) > 0.05  # not a blank page
    colours = np.unique((image * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > 500  # a filled colour field, not lines on white
    # the range the picture uses: the largest fibre stress outside the end layers
    conns = [c for c in system.connectors if isinstance(c, ContinuumConnector)]
    fields = flexure_fields(scene.mechanism, conns, system.local_states(state)[: len(conns)])
    rng = robust_range([f.stress["fibre_stress"] for f in fields], [f.interior for f in fields])
    for f in fields:
        assert np.max(np.abs(f.stress["fibre_stress"][f.interior])) <= rng.high
        assert not f.interior[f.centre_line[[0, -1]]].any()  # the end faces are left out
        assert f.layer == pytest.approx(2 * f.thickness)
    assert rng.high > 1.0  # MPa: the open chain's f+ bends its arcs to several MPa
    # ... which is the reported peak fibre stress of the most stressed flexure
    from flexval.validation.continuum.fibre import fibre_stresses

    reported = fibre_stresses(system, state)
    name = fields[rng.flexure].name
    assert max(reported.values(), key=lambda r: r["stress"]) is reported[name]
    assert rng.high == pytest.approx(reported[name]["stress"], rel=1e-12)
    assert fields[rng.flexure].arc_fraction[rng.node] == pytest.approx(reported[name]["at"])


def test_picture_of_an_unloaded_scene_with_a_pin(tmp_path):
    from pathlib import Path

    from flexval.geometry import load_scene
    from flexval.validation.continuum.output import render_png
    from flexval.validation.continuum.run import build_system

    scene = load_scene(Path(__file__).parent / "scenes" / "deep_arch.toml")
    system = build_system(scene.mechanism, 0)
    png = render_png(
        tmp_path / "arch.png", system, system.initial_state(), scene.load_cases[0], "deep arch"
    )
    assert png.stat().st_size > 20_000
