"""The canonical mechanisms built in (geometry/scenes), each against an independent anchor.

Two kinds of reference, both written here and sharing no code with flexval: the textbook
closed forms each scene's header cites, and the direct stiffness method of linear
Euler-Bernoulli frames (each leaf's 6 x 6 matrix, axial stiffness included, joined
through the rigid bodies' poses), which is exact for straight leaves at rest.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from flexval.geometry import MECHANISM_SCENES, load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.run import run_model
from flexval.validation.stiffness import run_stiffness


def leaf_matrix(p0, p1, ea: float, ei: float) -> np.ndarray:
    """A straight leaf's stiffness (6 x 6) in global (x, y, theta) of its two end nodes."""
    d = np.asarray(p1, float) - np.asarray(p0, float)
    length = math.hypot(*d)
    c, s = d / length
    a, b1, b2, b3 = ea / length, 12 * ei / length**3, 6 * ei / length**2, ei / length
    local = np.array(
        [
            [a, 0, 0, -a, 0, 0],
            [0, b1, b2, 0, -b1, b2],
            [0, b2, 4 * b3, 0, -b2, 2 * b3],
            [-a, 0, 0, a, 0, 0],
            [0, -b1, -b2, 0, b1, -b2],
            [0, b2, 2 * b3, 0, -b2, 4 * b3],
        ]
    )
    rotation = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    transform = np.kron(np.eye(2), rotation)
    return transform.T @ local @ transform


def frame_target_stiffness(scene) -> np.ndarray:
    """The 3 x 3 stiffness at the target point by the direct stiffness method: each body's
    pose (x, y, theta) about its own reference (the target point for the target body), the
    ground's removed, every other body condensed out."""
    mech = scene.mechanism
    moving = mech.moving_bodies
    origin = {b: mech.bodies[b].reference for b in moving}
    origin[mech.target_body] = mech.target_point
    index = {b: 3 * k for k, b in enumerate(moving)}
    total = np.zeros((3 * len(moving), 3 * len(moving)))
    E = mech.material.youngs_modulus
    for f in mech.flexures:
        area, inertia = f.section.area, f.section.inertia
        ends = f.shape.end_points
        k = leaf_matrix(ends[0], ends[1], E * area, E * inertia)
        for i, (body, node) in enumerate(zip(f.bodies, ends)):
            if body == mech.ground:
                continue
            rx, ry = np.asarray(node) - origin[body]
            carry_i = np.array([[1, 0, -ry], [0, 1, rx], [0, 0, 1.0]])  # node from body pose
            for j, (other, node_j) in enumerate(zip(f.bodies, ends)):
                if other == mech.ground:
                    continue
                sx, sy = np.asarray(node_j) - origin[other]
                carry_j = np.array([[1, 0, -sy], [0, 1, sx], [0, 0, 1.0]])
                block = carry_i.T @ k[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] @ carry_j
                total[index[body] : index[body] + 3, index[other] : index[other] + 3] += block
    t = index[mech.target_body]
    compliance = np.linalg.inv(total)[t : t + 3, t : t + 3]
    return np.linalg.inv(compliance)


def flexval_stiffness(scene, model: str, case=None, fraction: float = 0.0) -> np.ndarray:
    return run_stiffness(scene, parse_model(model), case, fraction)[1].stiffness


LINEAR_SCENES = (
    "parallel_guide",
    "folded_guide",
    "cross_pivot",
    "cartwheel_hinge",
    "trapezoid_pivot",
)


@pytest.mark.parametrize("name", LINEAR_SCENES)
@pytest.mark.parametrize("model", ["ee", "dcmm:1", "beam:100"])
def test_straight_leaf_mechanisms_match_the_direct_stiffness_method(name, model):
    # straight Euler-Bernoulli leaves with their axial stiffness: these models are exact at
    # rest; the stiffness spans 1 N/mm to 1e5 N mm/rad, compared in its own norm to the
    # round-off of a few solves (measured below 1e-11)
    scene = load_scene(name)
    reference = frame_target_stiffness(scene)
    found = flexval_stiffness(scene, model)
    scale = np.abs(reference).max()
    np.testing.assert_allclose(found, reference, rtol=1e-7, atol=1e-9 * scale)


def test_parallel_guide_closed_forms():
    scene = load_scene("parallel_guide")
    ei = 70000.0 * 10.0 * 0.625**3 / 12.0
    length = 50.0
    # the frame's primary stiffness is 24 EI / L^3 up to the leaves' axial compliance
    frame = frame_target_stiffness(scene)
    assert frame[0, 0] == pytest.approx(24 * ei / length**3, rel=2e-4)
    # done-when of the library: beam:100 and continuum:2 within 0.5 % of 24 EI / L^3
    # (measured 0.02 % and 0.06 %: plane stress's shear and the clamps' root rotation)
    for model in ("beam:100", "continuum:2"):
        k = flexval_stiffness(scene, model)
        assert k[0, 0] == pytest.approx(24 * ei / length**3, rel=5e-3), model
    # the stroke: (3/5) delta^2 / L of parasitic shortening (beam constraint model)
    for model in ("beam:100", "continuum:1"):
        lp = run_model(scene, model, "stroke", levels=3)
        assert lp.dy[-1] == pytest.approx(-0.6 * 2.5**2 / length, rel=1e-2), model


@pytest.mark.parametrize("model", ["beam:100", "continuum:1"])
def test_parallel_guide_stiffens_under_tension_as_the_beam_constraint_model_says(model):
    # 25 N per leaf: k = 2 (12 EI / L^3 + (6/5) P / L) to first order in P (Awtar et al.
    # 2007); the next term, -P^2 L / (700 EI) per leaf, is 0.16 % of it
    scene = load_scene("parallel_guide")
    ei, length, pull = 70000.0 * 10.0 * 0.625**3 / 12.0, 50.0, 25.0
    expected = 2 * (12 * ei / length**3 + 1.2 * pull / length - pull**2 * length / (700 * ei))
    k = flexval_stiffness(scene, model, scene.load_case("tension"), 1.0)
    assert k[0, 0] == pytest.approx(expected, rel=2e-3)


def test_folded_guide_is_two_guides_in_series():
    scene = load_scene("folded_guide")
    ei, length = 70000.0 * 8.0 * 0.5**3 / 12.0, 40.0
    frame = frame_target_stiffness(scene)
    # two 24 EI / L^3 guides in series; the intermediate stage's tilt and the axial
    # compliance make the exact linear frame differ by less than 1e-3
    assert frame[0, 0] == pytest.approx(12 * ei / length**3, rel=1e-3)
    for model in ("beam:100", "continuum:2"):
        k = flexval_stiffness(scene, model)
        assert k[0, 0] == pytest.approx(12 * ei / length**3, rel=5e-3), model
    # folding: the shuttle's parasitic motion along the leaves is far below a parallel
    # guide's (3/5) delta^2 / L = 0.24 mm at the 4 mm stroke (measured 1e-4 mm)
    lp = run_model(scene, "beam:100", "stroke", levels=3)
    assert abs(lp.dy[-1]) < 0.01 * 0.6 * 4.0**2 / length


def test_cross_pivot_rotational_stiffness():
    scene = load_scene("cross_pivot")
    ei, length = 70000.0 * 8.0 * 0.4**3 / 12.0, math.hypot(20.0, 20.0)
    frame = frame_target_stiffness(scene)  # at the crossing point, the target
    # each leaf's end turns about its midpoint: k = (EI/L)(12 c^2 - 12 c + 4) = EI/L at
    # c = 1/2 (Wittrick 1948); the pair, with the centre free, K = 2 EI / L
    assert wittrick(scene, scene.mechanism.target_point) == pytest.approx(
        2 * ei / length, rel=1e-12
    )
    assert _turning(frame) == pytest.approx(2 * ei / length, rel=1e-3)
    for model in ("beam:100", "continuum:2"):
        assert _turning(flexval_stiffness(scene, model)) == pytest.approx(
            2 * ei / length, rel=5e-3
        ), model
    # turned by its drive, the pure moment it needs is K theta at 1 degree; at 10 degrees
    # the pivot is 0.5 % stiffer (measured: the leaves' tension from the centre shift)
    lp = run_model(scene, "beam:100", "turn", levels=11)
    moments = np.asarray(lp.drive_reactions)[:, 2]
    assert moments[1] == pytest.approx(2 * ei / length * math.radians(1.0), rel=1e-3)
    assert 1.0 < moments[-1] / (10 * moments[1]) < 1.01


def wittrick(scene, centre) -> float:
    """The rotational stiffness (N mm/rad) of the mechanism's leaves when its moving body
    turns about ``centre`` (mm): each leaf's moving end turns about a point at c L from it
    along the leaf (c from the geometry, positive towards the fixed end), k = (EI / L)
    (12 c^2 - 12 c + 4) (beam theory, inextensible leaves; Wittrick 1948), summed."""
    mech = scene.mechanism
    total = 0.0
    for f in mech.flexures:
        start, end = (np.asarray(p, float) for p in f.shape.end_points)
        fixed, moving = (start, end) if f.bodies[0] == mech.ground else (end, start)
        length = math.hypot(*(fixed - moving))
        c = float((np.asarray(centre, float) - moving) @ (fixed - moving)) / length**2
        ei = mech.material.youngs_modulus * f.section.inertia
        total += ei / length * (12 * c**2 - 12 * c + 4)
    return total


def _turning(k: np.ndarray) -> float:
    """The rotational stiffness with the point free to move (N mm/rad): k condensed."""
    return k[2, 2] - k[2, :2] @ np.linalg.solve(k[:2, :2], k[:2, 2])


def test_cartwheel_hinge_is_four_times_the_cross_pivot():
    scene = load_scene("cartwheel_hinge")
    ei, length = 70000.0 * 8.0 * 0.4**3 / 12.0, math.hypot(20.0, 20.0)
    # K = 8 EI / L for inextensible leaves; the frame's axial compliance: 0.06 % below
    assert _turning(frame_target_stiffness(scene)) == pytest.approx(8 * ei / length, rel=1e-3)
    for model in ("beam:100", "continuum:2"):  # continuum:2 measured 0.08 % below the frame
        turn = _turning(flexval_stiffness(scene, model))
        assert turn == pytest.approx(8 * ei / length, rel=3e-3), model
    # symmetry: the hub turns half as far as the top and does not move sideways (to first
    # order; measured 3e-4 of the top's motion at 2.7 degrees; its drop, from the leaves'
    # shortening, is second order)
    lp = run_model(scene, "beam:100", "moment", levels=11, record_poses=True)
    hub, top = np.asarray(lp.poses["hub"]), np.asarray(lp.poses["top"])
    np.testing.assert_allclose(hub[1:, 2], top[1:, 2] / 2, rtol=1e-3)
    moved = np.hypot(*(top[-1, :2] - top[0, :2]))
    assert abs(hub[-1, 0] - hub[0, 0]) < 1e-3 * moved


def test_trapezoid_pivot_turns_about_its_remote_centre():
    scene = load_scene("trapezoid_pivot")
    ei, length = 70000.0 * 8.0 * 0.4**3 / 12.0, math.hypot(10.0, 30.0)
    # the centre lies 15.81 mm beyond each moving end: c = -1/2, 13 EI / L per leaf
    expected = wittrick(scene, scene.mechanism.target_point)
    assert expected == pytest.approx(26 * ei / length, rel=1e-12)
    # at the remote centre (the target); the leaves' axial compliance: 0.13 % below
    assert _turning(frame_target_stiffness(scene)) == pytest.approx(expected, rel=2e-3)
    for model in ("beam:100", "continuum:2"):  # continuum:2 measured 1e-4 from the frame
        assert _turning(flexval_stiffness(scene, model)) == pytest.approx(expected, rel=3e-3)
    # the centre is remote but real: a pure moment moves it far less than the top
    lp = run_model(scene, "beam:100", "moment", levels=3)
    arm = 15.0  # the top body's leaf ends lie 15 mm below the centre
    assert math.hypot(lp.dx[-1], lp.dy[-1]) < 0.05 * arm * abs(lp.rotation[-1])


@pytest.mark.parametrize("model", ["beam:4", "dcmm:3", "continuum:0"])
def test_bistable_truss_snaps_through_as_the_closed_form_says(model):
    scene = load_scene("bistable_truss")
    E, area, a, h0 = 2200.0, 30.0, 50.0, 6.0
    full = math.hypot(a, h0)

    def load(w):
        h = h0 - np.asarray(w, float)
        return 2.0 * E * area * h * (1.0 / np.hypot(a, h) - 1.0 / full)

    lp = run_model(scene, model, "snap")
    w = -np.asarray(lp.dy)
    force = -np.asarray(lp.drive_reactions)[:, 1]  # the push the apex needs, N
    peak = load(np.linspace(0.0, 2 * h0, 12001)).max()
    # the pinned bars are exact trusses in beams and DCMM (1e-9 of the peak); solid bars
    # of L/h = 8 are 0.5 % softer (measured 0.3 %), but zero exactly where the truss is
    # up to the mirrored state; beyond it the solid's bars stretch past 1 % and its SVK
    # law leaves the truss's linear one
    tolerance = 1e-9 if model != "continuum:0" else 5e-3
    level, mirrored = int(np.argmin(abs(w - h0))), int(np.argmin(abs(w - 2 * h0)))
    np.testing.assert_allclose(
        force[: mirrored + 1], load(w[: mirrored + 1]), atol=tolerance * peak
    )
    assert abs(force[level]) < 1e-9 * peak and abs(force[mirrored]) < 1e-9 * peak
    # the snap-through force, 43.27 N, between the levels 0.5 mm apart (within 0.2 %)
    assert force[:level].max() == pytest.approx(peak, rel=2e-3)


@pytest.mark.parametrize("name", MECHANISM_SCENES)
@pytest.mark.parametrize("model", ["beam:20", "dcmm:2", "prbm", "ee", "continuum:0"])
def test_every_family_runs_every_mechanism_or_says_why(name, model):
    from flexval.reducedmodels import SolverError

    scene = load_scene(name)
    for case in scene.load_cases:
        try:
            lp = run_model(scene, model, case, levels=3)
        except SolverError as exc:
            # the PRBM holds the pinned truss rigid (inextensible links): refused up front
            assert (model, name) == ("prbm", "bistable_truss"), str(exc)
            assert "holds rigid" in str(exc) or "double precision" in str(exc)
            continue
        assert np.isfinite(lp.dx + lp.dy + lp.rotation).all()


def test_width_on_straight_leaves_is_refused_by_name(capsys, tmp_path):
    # the strip theory's ratio is 1 on a straight uniform leaf and it knows no clamps: on a
    # mechanism of such leaves only, [width] would be plain beam theory under a name that
    # promises the 3D stiffening, so it is refused, naming the leaves and what to use
    from flexval.geometry import SceneError
    from flexval.validation.cli import main

    code = main(["run", "parallel_guide", "--model", "beam:20[width]", "--load-case", "lateral"])
    assert code == 2
    err = capsys.readouterr().err
    assert "[width] has no correction for straight uniform leaves" in err
    assert "left (b/h 16), right (b/h 16)" in err and "continuum:1[3d]" in err
    for model in ("beam:100[width]", "dcmm:1[width]", "ee[width]", "prbm[width]"):
        with pytest.raises(SceneError, match="straight uniform leaves"):
            run_model(load_scene("folded_guide"), model, "lateral")
    # arcs keep it (the correction applies); one arc among straight leaves: the run says
    # which leaves it leaves at plane-stress beam theory
    assert main(["run", "open_chain", "--model", "beam:20[width]", "--load-case", "f+"]) == 0
    assert "[width] leaves" not in capsys.readouterr().out
    guide = (Path(__file__).parents[1] / "geometry" / "scenes" / "parallel_guide.toml").read_text()
    right = guide.index('name = "right"')
    bow = (  # an arc through the right leaf's ends, bowed 5.9 mm outwards
        'name = "bow"\nbodies = ["ground", "shuttle"]\ncenter = [-30.0, 25.0]\n'
        f"radius = {math.hypot(50.0, 25.0)!r}\naxis_deg = 0.0\n"
        f"width_deg = {2 * math.degrees(math.atan(0.5))!r}\n"
    )
    end = guide.index("[[load_cases]]")
    path = tmp_path / "mixed.toml"
    path.write_text(guide[:right] + bow + "\n" + guide[end:])
    assert main(["run", str(path), "--model", "beam:20[width]", "--load-case", "lateral"]) == 0
    assert "[width] leaves the straight leaves left (b/h 16)" in capsys.readouterr().out
