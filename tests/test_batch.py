"""Batches: many copies of one mechanism traced together give each copy's solo path.

The reference of every check is the same copy traced alone by
:func:`flexval.reducedmodels.core.recorder.solve_path` (the one tracer on the
copy's own System): the batch must reproduce its load levels, target motion,
validity verdicts, peak stresses and Newton iteration counts. Copies differ
in their flexures' sections (each scaled by its own factor) and in the
magnitude of their loads.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

import flexval.validation.continuum.family  # noqa: F401  (registers continuum:N)
from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.batch import run_batch, trace_batch
from flexval.reducedmodels.core.batchsystem import BatchSystem
from flexval.reducedmodels.core.recorder import solve_path
from flexval.reducedmodels.core.settings import SolverError
from flexval.reducedmodels.models import build_system, run_reduced

AGREEMENT = 1e-12
"""Largest relative difference allowed between a copy's batched and solo outputs on the
cases below (1e-14 to 1e-12 measured on them). The batch's linear solves and predictions
differ from a solo run's in their round-off only; where a Newton test lands within it of its
bound, a copy stops an iteration earlier or later than alone, and its states differ by what
that iteration changes: up to 1.6e-11 of the mechanism's size on one of the built-in
scenes' 236 reduced-model paths (dcmm:4, open chain m+), which these cases do not include."""


STRESS_AGREEMENT = 1e-10
"""Relative agreement of the peak stresses (to their largest value). Where a Newton test lands
within round-off of its bound, batch and solo stop one iteration apart, at two states that
both meet the error test (1e-10, scaled): a notch's fibre stress, the section moment over
the square of a thickness that varies fast, then differs by up to 3e-11 (measured)."""
CONTINUUM_STRESS_AGREEMENT = 1e-7
"""The continuum's fibre stress is recovered from strain gradients over elements h/2 thick,
which magnify the distance between two such states: up to 1.7e-8 of its largest value
(measured)."""
ITERATION_SPREAD = 1
"""Largest difference in Newton iterations at one level between batch and solo on the cases
below (1 measured; 2 on dcmm:4, open chain m+)."""


def variants(scene: str, case_name: str, scales: list[float], loads: list[float]):
    """Mechanisms with every flexure's section scaled, and the case with its loads scaled."""
    sc = load_scene(scene)
    mech = sc.mechanism
    case = next(c for c in sc.load_cases if c.name == case_name)
    mechanisms = [
        dataclasses.replace(
            mech,
            flexures=tuple(
                dataclasses.replace(f, section=f.section.scaled(s)) for f in mech.flexures
            ),
        )
        for s in scales
    ]
    cases = [
        dataclasses.replace(
            case,
            components=tuple(dataclasses.replace(c, value=c.value * w) for c in case.components),
        )
        for w in loads
    ]
    return mechanisms, cases


def solo_and_batch(model: str, mechanisms, cases):
    """Each copy traced alone, and all of them as one batch (fresh Systems for each)."""
    spec = parse_model(model)
    solo = []
    for mech, case in zip(mechanisms, cases):
        try:
            solo.append(solve_path(build_system(mech, spec), case, None, model))
        except SolverError as exc:
            solo.append(exc)
    batched = trace_batch([build_system(m, spec) for m in mechanisms], cases, None, model)
    return solo, batched


def relative(a, b) -> float:
    """Largest difference over the largest magnitude of ``a``."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b), initial=0.0) / max(np.max(np.abs(a), initial=0.0), 1e-300))


def assert_same_path(
    solo, batched, mechanism_size: float, stress_agreement: float = STRESS_AGREEMENT
) -> None:
    """Levels, motion, verdicts, counts and stresses of two paths of one copy agree
    (``mechanism_size``, mm: the length a rotation turns into a displacement)."""
    assert solo.load == pytest.approx(batched.load, rel=AGREEMENT, abs=0.0)
    motion = np.hypot(solo.dx, solo.dy)
    scale = max(float(np.max(motion, initial=0.0)), 1e-300)
    for key in ("dx", "dy"):  # components of one vector: relative to its size along the path
        difference = np.abs(np.subtract(getattr(solo, key), getattr(batched, key)))
        assert difference.max() <= AGREEMENT * scale, key
    # a rotation is the same motion: relative to the larger of its own and the displacement's
    turn = max(float(np.max(np.abs(solo.rotation), initial=0.0)), scale / mechanism_size)
    assert np.max(np.abs(np.subtract(solo.rotation, batched.rotation))) <= AGREEMENT * turn
    assert solo.valid == batched.valid
    assert solo.validity == batched.validity
    for key in ("step_cuts", "substeps", "unknowns"):
        assert solo.stats[key] == batched.stats[key], key
    spread = np.abs(np.subtract(solo.stats["iterations"], batched.stats["iterations"]))
    assert spread.max(initial=0) <= ITERATION_SPREAD
    assert (solo.peak_stress is None) == (batched.peak_stress is None)
    for name, peaks in (solo.peak_stress or {}).items():
        assert relative(peaks, batched.peak_stress[name]) <= stress_agreement, name
        # the place of the peak is not compared: under a pure moment the stress is the same
        # along the flexure to round-off, and which sample is largest is round-off's choice
        profile, other = solo.stress_profile[name], batched.stress_profile[name]
        assert profile["at"] == other["at"]
        assert relative(profile["stress"], other["stress"]) <= stress_agreement, name
    # a notch's surface peak (the continuum's recovered one, a reduced model's K(s) times its
    # beam formula) at every level, where the path records one
    assert (solo.fibre_stress or {}).keys() == (batched.fibre_stress or {}).keys()
    for name, fibre in (solo.fibre_stress or {}).items():
        other = batched.fibre_stress[name]
        assert fibre.keys() == other.keys(), name
        for key in ("stress", "path_stress"):
            if key in fibre:
                assert relative(np.atleast_1d(fibre[key]), np.atleast_1d(other[key])) <= (
                    stress_agreement
                ), (name, key)


SCALES = [1.0, 1.004, 0.997, 1.002, 0.999]
LOADS = [1.0, 0.98, 1.01, 1.0, 0.995]


@pytest.mark.parametrize(
    "model, scene, case",
    [
        ("dcmm:1", "open_chain", "f+"),
        ("dcmm:3[frame=follower]", "open_chain", "m-"),
        ("prbm", "open_chain", "m+"),
        ("beam:20", "open_chain", "f+"),
        ("beam:20[shear]", "closed_chain", "f-"),
        ("beam:100", "closed_chain", "f+"),
        ("dcmm:2", "closed_chain", "f-"),
        ("prbm", "closed_chain", "f+"),
        ("beam:10", "tapered_leaf", None),
        ("dcmm:4", "notch_fourbar", None),
        ("prbm", "notch_fourbar", None),
        ("beam:20", "filleted_stage", None),
        ("dcmm:2[eb]", "filleted_stage", None),
        ("beam:12", "spline_flexure", None),
    ],
)
def test_batch_equals_solo(model, scene, case):
    """Every reduced family, open and closed chains, uniform and varying flexures."""
    case = case or load_scene(scene).load_cases[0].name
    mechanisms, cases = variants(scene, case, SCALES, LOADS)
    size = mechanisms[0].size()
    solo, batched = solo_and_batch(model, mechanisms, cases)
    for a, b in zip(solo, batched):
        assert isinstance(b, type(a))
        if isinstance(a, SolverError):
            assert str(a) == str(b)
            continue
        assert_same_path(a, b, size)
    # the copies stayed together where their solo decisions agree: here at least most of them
    assert max(p.stats["batch"] for p in batched if not isinstance(p, SolverError)) >= 3


def test_continuum_batch_equals_solo():
    """The continuum is a connector like any other: two meshed copies in one batch."""
    mechanisms, cases = variants("open_chain", "m+", [1.0, 1.01], [1, 1])
    solo, batched = solo_and_batch("continuum:0", mechanisms, cases)
    for a, b in zip(solo, batched):
        assert_same_path(a, b, mechanisms[0].size(), CONTINUUM_STRESS_AGREEMENT)
    assert batched[0].stats["batch"] == 2


def test_a_hard_copy_leaves_and_equals_its_solo_run():
    """A copy twice as flexible needs its own sub-steps: it leaves, the others stay together."""
    scales = [1.0, 1.001, 0.6, 0.999, 1.0005]
    mechanisms, cases = variants("open_chain", "f+", scales, [1] * 5)
    solo, batched = solo_and_batch("dcmm:1", mechanisms, cases)
    for a, b in zip(solo, batched):
        assert_same_path(a, b, mechanisms[0].size())
    assert batched[2].stats["batch"] < 4
    assert [batched[k].stats["batch"] for k in (0, 1, 3, 4)] == [4, 4, 4, 4]
    assert solo[2].stats["substeps"] != solo[0].stats["substeps"]


@pytest.mark.parametrize("model", ["dcmm:1", "prbm", "beam:20"])
def test_copies_that_part_ways_go_on_from_the_last_point_they_shared(model, monkeypatch):
    """Sections drawn from N(1, 0.03): copies disagree on their sub-steps, leave their batch
    and go on as batches of their own from the last reported level they shared; each path is
    bit for bit the copy's path traced alone (a batch of one from rest), and its solo run's
    to the batch's agreement."""
    from flexval.reducedmodels.core import batch as batch_module
    from flexval.reducedmodels.core.tracer import LoadControl

    rng = np.random.default_rng(3)
    scales = rng.normal(1.0, 0.03, 24).tolist()
    mechanisms, cases = variants("open_chain", "f+", scales, [1.0] * len(scales))
    spec = parse_model(model)
    resumed, batches = [], []
    resume, start = LoadControl.resume, LoadControl.__init__

    def counted(self, carried, take, loads):
        resumed.append(carried["factor"])
        resume(self, carried, take, loads)

    def made(self, factors, batch=None):
        batches.append(batch.n_copies)
        start(self, factors, batch)

    # a clock that ticks once per reading: each batch lasts one tick from its start to its
    # end, and so does building the connectors
    ticks = itertools.count()
    monkeypatch.setattr(batch_module, "path_clock", lambda: float(next(ticks)))
    monkeypatch.setattr(LoadControl, "resume", counted)
    monkeypatch.setattr(LoadControl, "__init__", made)
    batched = run_batch(mechanisms, spec, cases)
    monkeypatch.undo()
    # the paths' seconds share out every batch's time, those whose copies all left included
    assert sum(p.seconds for p in batched) == pytest.approx(len(batches) + 1, rel=1e-12)
    sizes = [p.stats["batch"] for p in batched]
    assert min(sizes) < len(scales)  # some parted ways
    assert resumed and max(resumed) > cases[0].factors()[0]  # past the first level
    for k in range(len(scales)):
        (alone,) = run_batch(mechanisms[k : k + 1], spec, cases[k : k + 1])
        assert batched[k].dx == alone.dx and batched[k].dy == alone.dy
        assert batched[k].rotation == alone.rotation and batched[k].load == alone.load
        assert batched[k].peak_stress == alone.peak_stress
        assert batched[k].stats["iterations"] == alone.stats["iterations"]
        assert batched[k].stats["substeps"] == alone.stats["substeps"]
    solo, _ = solo_and_batch(model, mechanisms[:4], cases[:4])
    for a, b in zip(solo, batched[:4]):
        assert_same_path(a, b, mechanisms[0].size())


def test_a_failing_copy_fails_as_alone_and_holds_no_one_back():
    """A copy loaded beyond what load control can follow fails with its solo error at the same
    load; the rest converge together."""
    loads = [1.0, 1.0, 2.0, 1.0]
    mechanisms, cases = variants("closed_chain", "f+", [1.0, 1.001, 1.0, 0.999], loads)
    solo, batched = solo_and_batch("dcmm:1", mechanisms, cases)
    size = mechanisms[0].size()
    assert isinstance(solo[2], SolverError)
    assert isinstance(batched[2], SolverError)
    # the same failure at the same load; the residual it quotes differs in its last digits
    # where the batch factorises with other arithmetic than the copy's dense tangent
    assert str(batched[2]).split("(")[0] == str(solo[2]).split("(")[0]
    assert batched[2].load_factor == pytest.approx(solo[2].load_factor, rel=AGREEMENT)
    # the levels reached before it agree; the step cuts spent on the failing step may not
    # (they bisect to the smallest step near a limit point, where round-off decides)
    failed, alone = batched[2].path, solo[2].path
    assert failed.load == pytest.approx(alone.load, rel=AGREEMENT, abs=0.0)
    for key in ("dx", "dy"):
        assert np.max(np.abs(np.subtract(getattr(failed, key), getattr(alone, key)))) <= (
            AGREEMENT * float(np.max(np.hypot(alone.dx, alone.dy)))
        )
    for k in (0, 1, 3):
        assert_same_path(solo[k], batched[k], size)


def test_batch_numbering_round_trips_and_scales_per_copy():
    """Each copy's coordinates, sizes and load scales are its own inside the batch."""
    mechanisms, cases = variants("closed_chain", "f+", [1.0, 0.5, 2.0], [1.0, 3.0, 0.5])
    spec = parse_model("beam:8")
    systems = [build_system(m, spec) for m in mechanisms]
    batch = BatchSystem(systems)
    states = [s.initial_state() + 1e-3 * np.arange(s.n_dofs) for s in systems]
    q = batch.merge(states)
    for k, state in enumerate(states):
        assert np.array_equal(batch.split(q, k), state)
    loads = batch.use_loads(cases)
    _, grad, _ = batch.assemble(q, loads, 0.7)
    for k, (system, case) in enumerate(zip(systems, cases)):
        own_loads = system.loads(case)
        _, own, _ = system.assemble(states[k], own_loads, 0.7)
        assert np.allclose(batch.split(grad, k), own, rtol=1e-13, atol=1e-13 * np.abs(own).max())
        assert batch.copy_residuals(grad, loads)[k] == pytest.approx(
            system.residual(own, own_loads), rel=1e-12
        )
    dx, dy, rot = batch.copy_targets(np.array([q]))
    for k, system in enumerate(systems):
        assert (dx[0, k], dy[0, k], rot[0, k]) == pytest.approx(system.target(states[k]), rel=1e-14)


def test_batch_refuses_copies_that_cannot_share_it():
    mechanisms, cases = variants("open_chain", "f+", [1.0, 1.0], [1.0, 1.0])
    spec = parse_model("dcmm:1")
    other = parse_model("beam:4")
    with pytest.raises(ValueError, match="connectors differ"):
        BatchSystem([build_system(mechanisms[0], spec), build_system(mechanisms[1], other)])
    with pytest.raises(ValueError, match="different load factors"):
        trace_batch(
            [build_system(m, spec) for m in mechanisms],
            [cases[0], dataclasses.replace(cases[1], levels=cases[1].levels + 1)],
        )


def test_large_sets_of_copies_are_traced_in_batches_of_bounded_size(monkeypatch):
    """Beyond BATCH_UNKNOWNS the copies go in several batches; every path stays its solo one."""
    from flexval.reducedmodels.core import batch as batch_module

    mechanisms, cases = variants("open_chain", "m+", SCALES, LOADS)
    unknowns = build_system(mechanisms[0], parse_model("dcmm:1")).n_dofs
    monkeypatch.setattr(batch_module, "BATCH_UNKNOWNS", 2 * unknowns)
    solo, batched = solo_and_batch("dcmm:1", mechanisms, cases)
    for a, b in zip(solo, batched):
        assert_same_path(a, b, mechanisms[0].size())
    assert [p.stats["batch"] for p in batched] == [2, 2, 2, 2, 1]


@pytest.mark.parametrize("model", ["dcmm:1", "prbm", "beam:20", "beam:100"])
def test_a_copys_path_does_not_depend_on_its_batch(model):
    """Bit for bit the same path for a copy traced alone, with one other copy or with four:
    a sweep's rows must not depend on how its points were grouped into tasks. Copies with
    more than SOLO_UNKNOWNS unknowns (beam:100) are each traced alone."""
    from flexval.reducedmodels.core.batch import SOLO_UNKNOWNS

    mechanisms, cases = variants("open_chain", "f+", SCALES, LOADS)
    spec = parse_model(model)
    paths = [run_batch(mechanisms[:n], spec, cases[:n])[0] for n in (1, 2, 5)]
    alone = build_system(mechanisms[0], spec).n_dofs > SOLO_UNKNOWNS
    assert [p.stats["batch"] for p in paths] == ([1, 1, 1] if alone else [1, 2, 5])
    assert alone == (model == "beam:100")
    for other in paths[1:]:
        assert other.dx == paths[0].dx and other.dy == paths[0].dy
        assert other.rotation == paths[0].rotation
        assert other.peak_stress == paths[0].peak_stress
        assert other.stats["iterations"] == paths[0].stats["iterations"]


def test_copies_of_other_topologies_or_levels_go_in_batches_of_their_own():
    """run_batch groups the copies it can trace together: two mechanisms and two level
    counts in one call give four batches, each path its solo run's."""
    open_m, open_c = variants("open_chain", "f+", [1.0, 1.002], [1.0, 1.0])
    closed_m, closed_c = variants("closed_chain", "f+", [1.0, 0.998], [1.0, 1.0])
    finer = [dataclasses.replace(c, levels=c.levels + 4) for c in open_c]
    mechanisms = [open_m[0], closed_m[0], open_m[1], closed_m[1], *open_m]
    cases = [open_c[0], closed_c[0], open_c[1], closed_c[1], *finer]
    spec = parse_model("dcmm:1")
    paths = run_batch(mechanisms, spec, cases)
    assert [p.stats["batch"] for p in paths] == [2] * 6
    for mech, case, path in zip(mechanisms, cases, paths):
        solo = solve_path(build_system(mech, spec), case, None, "dcmm:1")
        assert len(path.load) == case.levels
        assert_same_path(solo, path, mech.size())


def comparable(path) -> dict:
    """Everything a path records but its wall time and the size of the batch it came from."""
    found = path.to_dict()
    found.pop("seconds")
    found["stats"].pop("batch", None)
    return found


def with_gravity(mechanisms):
    """The mechanisms with their flexures' weights (steel's density, gravity along -y)."""
    from flexval.geometry.inertia import MassData

    weights = MassData(density=7.85e-9, gravity=np.array([0.0, -9810.0]))
    return [dataclasses.replace(m, inertia=weights) for m in mechanisms]


@pytest.mark.parametrize(
    "scene, case, gravity",
    [
        ("open_chain", "f+", False),
        ("open_chain", "m-", True),
        ("closed_chain", "f-", False),
        ("closed_chain", "f+", True),
        ("notch_fourbar", None, False),
        ("tapered_leaf", None, True),
        ("spline_flexure", None, False),
    ],
)
def test_ee_batch_is_each_copys_solo_path_bit_for_bit(scene, case, gravity):
    """ee's linear responses of copies with other sections and loads, computed together, are
    their solo runs' paths exactly: levels, motion, validity verdicts, stresses and profiles
    (pins, varying sections, splines and weights included)."""
    case = case or load_scene(scene).load_cases[0].name
    mechanisms, cases = variants(scene, case, SCALES, [1.0, 0.5, 2.0, 1.0, 3.0])
    if gravity:
        mechanisms = with_gravity(mechanisms)
    spec = parse_model("ee")
    solo = [run_reduced(m, spec, c) for m, c in zip(mechanisms, cases)]
    batched = run_batch(mechanisms, spec, cases)
    assert [p.stats["batch"] for p in batched] == [len(mechanisms)] * len(mechanisms)
    for a, b in zip(solo, batched):
        assert comparable(b) == comparable(a)
    assert batched[0].peak_stress


def test_ee_batch_records_the_linear_rotation_limit_as_alone():
    """Copies loaded past the linearised kinematics' rotation limit get the solo verdicts."""
    mechanisms, cases = variants("open_chain", "m+", [1.0, 1.0, 1.0], [0.2, 1.0, 4.0])
    spec = parse_model("ee")
    batched = run_batch(mechanisms, spec, cases)
    assert all(batched[0].valid) and not all(batched[2].valid)
    for m, c, b in zip(mechanisms, cases, batched):
        assert comparable(b) == comparable(run_reduced(m, spec, c))


def test_an_ee_copys_path_does_not_depend_on_its_batch():
    """Bit for bit the same ee path alone, with one other copy or with four."""
    mechanisms, cases = variants("closed_chain", "f+", SCALES, LOADS)
    spec = parse_model("ee")
    paths = [run_batch(mechanisms[:n], spec, cases[:n])[0] for n in (1, 2, 5)]
    assert [p.stats["batch"] for p in paths] == [1, 2, 5]
    for other in paths[1:]:
        assert comparable(other) == comparable(paths[0])


@pytest.mark.parametrize("model", ["dcmm:3", "prbm", "beam:5"])
def test_batch_construction_is_the_per_copy_construction(model, monkeypatch):
    """The numbering, loads and rest state a batch builds for all copies at once are, bit for
    bit, those built copy by copy: each copy's own numbering placed by its bodies' names, its
    loads numbered by them, the core's rest state of the merged System."""
    from flexval.reducedmodels.core.system import System, case_loads

    mechanisms, cases = variants("closed_chain", "f+", [1.0, 0.7, 1.4], [1.0, 2.0, 0.5])
    spec = parse_model(model)
    members = [(m, spec.model_family.connectors(m, spec)) for m in mechanisms]
    batch = BatchSystem(members + [members[0]])
    cases = [*cases, cases[0]]
    assert batch.uniform
    table = batch.copy_dofs
    monkeypatch.setattr(batch, "uniform", False)  # each copy numbered by its own System
    for fast, own in zip(table, batch._copy_numbering()):
        assert np.array_equal(fast, own)
    assert np.array_equal(batch.initial_state(), System.initial_state(batch))
    loads = batch.batch_loads(cases)
    parts = [
        case_loads(
            case,
            lambda body, k=k: batch.pose_dofs(batch.copy_names[k][body]),
            {b: body.reference for b, body in mechanism.bodies.items()},
            mechanism.size(),
            connectors,
        )
        for k, ((mechanism, connectors), case) in enumerate(zip(batch.members, cases))
    ]
    for key in ("dofs", "forces", "rels", "moment_dofs", "moments"):
        alone = np.concatenate([getattr(p, key).reshape(-1) for p in parts])
        assert np.array_equal(getattr(loads, key).reshape(-1), alone), key
    assert np.array_equal(loads.scale, [p.scale for p in parts])


def test_stresses_of_many_flexures_at_once_are_each_flexures_alone():
    """path_peaks and state_peaks stack flexures of one kind of section (a batch's), in stacks
    of at most STACK_SIZE; each entry must be what its own SectionForces.fibre_stress gives
    (max, argmax and profile, bit for bit), stacked or not, in the first stack or a later one."""
    from flexval.reducedmodels.core.peaks import STACK_FROM, STACK_SIZE, path_peaks, state_peaks
    from flexval.reducedmodels.core.sections import SectionForces
    from flexval.reducedmodels.notchcorrection import factors_of

    uniform = load_scene("open_chain").mechanism.flexures[0].section
    varying = load_scene("notch_fourbar").mechanism.flexures[0].section
    sections = [uniform.scaled(1.0 + 0.01 * k) for k in range(2 * STACK_SIZE + STACK_FROM + 2)]
    sections.insert(3, varying)
    rng = np.random.default_rng(7)
    at = np.linspace(0.0, 1.0, 9)
    paths = [SectionForces(at, rng.normal(size=(5, 9)), rng.normal(size=(5, 9))) for _ in sections]
    for forces, section, found in zip(paths, sections, path_peaks(list(zip(paths, sections)))):
        unit = forces.fibre_stress(section)
        assert found == (
            unit.max(axis=1).tolist(),
            at[unit.argmax(axis=1)].tolist(),
            at.tolist(),
            unit[-1].tolist(),
            None,
        )
    scales = [0.0, -0.5, 1.0]
    states = [SectionForces(at, f.axial[0], f.moment[0]) for f in paths]
    for forces, section, found in zip(
        states, sections, state_peaks(list(zip(states, sections)), scales)
    ):
        unit = forces.fibre_stress(section)
        top, place = float(unit.max()), float(at[unit.argmax()])
        expected = ([abs(s) * top for s in scales], [place] * 3, at.tolist(), unit.tolist(), None)
        assert found == expected
    # a few alone give the same
    assert path_peaks(list(zip(paths, sections))[:3]) == path_peaks(list(zip(paths, sections)))[:3]
    # a varying section's surface stress, where its connector has one: the largest of it
    hinge = load_scene("notch_fourbar").mechanism.flexures[0]
    surface = factors_of(hinge, 0.33).surface_stress
    kinds = [None] * len(sections)
    kinds[3] = surface
    found = path_peaks(list(zip(paths, sections)), kinds)
    where, true = surface(paths[3], varying)
    assert found[3][:4] == path_peaks([(paths[3], varying)])[0][:4]
    assert found[3][4] == (true.max(axis=1).tolist(), where[true.argmax(axis=1)].tolist())
    assert all(f[4] is None for j, f in enumerate(found) if j != 3)
    found = state_peaks(list(zip(states, sections)), scales, kinds)
    where, true = surface(states[3], varying)
    peak = int(np.argmax(true))
    assert found[3][4] == ([abs(s) * float(true[peak]) for s in scales], [float(where[peak])] * 3)


def test_stacks_of_section_forces_hold_each_connectors_columns():
    """column_stacks puts connectors of equal stations (equal arrays, whether the same objects
    or not) in one stack, each member's rows its own columns; a connector without forces is in
    none; stack_peaks gives what path_peaks gives each member alone, across STACK_SIZE."""
    from flexval.reducedmodels.core.peaks import (
        STACK_SIZE,
        path_peaks,
        section_constants,
        stack_peaks,
    )
    from flexval.reducedmodels.core.sections import SectionForces, column_stacks

    rng = np.random.default_rng(3)
    at_a, base_a = np.linspace(0.0, 1.0, 4), np.arange(4)
    at_b, base_b = np.array([0.0, 0.5, 1.0]), np.array([2, 0, 1])  # columns out of order
    kinds = [(at_a, base_a), (at_a.copy(), base_a.copy()), (at_b, base_b), None]
    stations = [kinds[j % 4] for j in range(2 * STACK_SIZE + 9)]
    offsets = 4 * np.arange(len(stations))
    axial, moment = rng.normal(size=(2, 6, 4 * len(stations)))
    stacks = column_stacks(axial, moment, stations, offsets)
    assert sorted(len(s.members) for s in stacks) == [
        sum(entry is kinds[2] for entry in stations),
        sum(entry is not None and entry[0].size == 4 for entry in stations),
    ]
    for stack in stacks:
        for row, j in enumerate(stack.members):
            at, base = stations[j]
            assert np.array_equal(stack.at, at)
            assert np.array_equal(stack.axial[row], axial[:, offsets[j] + base])
            assert np.array_equal(stack.moment[row], moment[:, offsets[j] + base])
    stacked = sorted(j for stack in stacks for j in stack.members)
    assert stacked == [j for j, entry in enumerate(stations) if entry is not None]
    # each connector's kind of stations named instead (a batch's copies of one connector)
    by_kind = column_stacks(axial, moment, kinds, offsets, np.arange(len(stations)) % 4)
    assert [s.members for s in by_kind] == [s.members for s in stacks]
    for mine, theirs in zip(by_kind, stacks):
        assert np.array_equal(mine.at, theirs.at)
        assert np.array_equal(mine.axial, theirs.axial)
        assert np.array_equal(mine.moment, theirs.moment)
    section = load_scene("open_chain").mechanism.flexures[0].section
    for stack in stacks:
        sections = [section.scaled(1.0 + 0.01 * j) for j in stack.members]
        alone = path_peaks(
            [
                (SectionForces(stack.at, a, m), s)
                for a, m, s in zip(stack.axial, stack.moment, sections)
            ]
        )
        assert stack_peaks(stack, section_constants(sections)) == alone
        # a NaN force: its level's peak is NaN where numpy's max and argmax put it
        axial = stack.axial.copy()
        axial[-1, 1, -1] = np.nan
        nan = stack._replace(axial=axial)
        alone = path_peaks(
            [(SectionForces(nan.at, a, m), s) for a, m, s in zip(axial, nan.moment, sections)]
        )
        np.testing.assert_equal(stack_peaks(nan, section_constants(sections)), alone)


@pytest.mark.parametrize("model", ["prbm", "dcmm:2"])
def test_a_groups_stacked_forces_are_its_connectors_own(model):
    """A batch's group stacks its copies' section forces (path_end_stacks); each connector's
    rows must be the forces that connector computes alone (Connector.path_section_forces),
    copies with other sections included."""
    mechanisms = variants("open_chain", "f+", [1.0, 1.02, 0.97], [1.0, 1.0, 1.0])[0]
    copies = [*mechanisms, mechanisms[0], mechanisms[0]]
    spec = parse_model(model)
    batch = BatchSystem([build_system(m, spec) for m in copies])
    rest = batch.initial_state()
    rng = np.random.default_rng(5)
    states = [rest + 1e-3 * rng.normal(size=rest.size) for _ in range(3)]
    for (group, _), coordinates in zip(batch.groups, batch.group_coordinates(states)):
        verdicts, stacks = group.path_end_stacks(coordinates)
        levels = group.local_levels(coordinates)
        stacked = 0
        for stack in stacks:
            for row, j in enumerate(stack.members):
                own = group.connectors[j].path_section_forces([lv[j] for lv in levels])
                assert np.array_equal(stack.at, own.at)
                assert np.array_equal(stack.axial[row], own.axial)
                assert np.array_equal(stack.moment[row], own.moment)
                stacked += 1
        assert stacked == len(group.connectors)
        assert len(verdicts) == len(group.connectors)


@pytest.mark.parametrize("scene", ["open_chain", "closed_chain"])
@pytest.mark.parametrize("model", ["dcmm:1", "dcmm:3", "beam:4", "prbm"])
def test_a_batch_numbers_copies_as_one_table_as_the_loop_over_its_connectors(scene, model):
    """Copies all numbered as copy 0 get the batch's unknowns from copy 0's numbering shifted
    per copy, without the core's loop over every connector; it must give that loop's numbers
    exactly: every connector's dofs and places in [q, ground pose], where each starts, and
    which unknowns are angles (internal coordinates: dcmm:3's cut bodies, beam:4's nodes,
    prbm's link angles and multipliers; pins on the closed chain), the loop run on the
    connectors renamed to the batch's bodies (the batch keeps them as they are). Copies share
    connectors or have their own."""
    import copy

    from flexval.reducedmodels.core.batchsystem import _shallow_copy
    from flexval.reducedmodels.core.system import System

    spec = parse_model(model)
    mechanisms, _ = variants(scene, "f+", [1.0, 1.2, 0.9], [1.0, 1.0, 1.0])
    own = [(m, spec.model_family.connectors(m, spec)) for m in mechanisms]
    members = [own[0], own[1], own[0], own[2], own[0]]
    batch = BatchSystem(members)
    assert batch.uniform
    origin = batch.origin_table.tolist()
    assert [c is members[k][1][j] for c, (k, j) in zip(batch.connectors, origin)] == [True] * len(
        origin
    )
    named = copy.copy(batch)
    named.connectors = [
        _shallow_copy(c, "bodies", tuple(batch.copy_names[k][b] for b in c.bodies))
        for c, (k, _) in zip(batch.connectors, origin)
    ]
    table, loop = batch.number_connectors(), System.number_connectors(named)
    for fast, slow in zip(table, loop):
        assert type(fast) is type(slow)
        assert np.array_equal(fast, slow) and np.asarray(fast).dtype == np.asarray(slow).dtype
    assert batch.n_dofs == loop[3].size and batch.is_rotation.any()


@pytest.mark.parametrize("seed", [0, 4])
def test_a_batch_judges_each_copys_stability_as_its_own_system(seed):
    """The negative eigenvalues beyond the multipliers of each copy's tangent block (prbm: a
    saddle point) are those the copy's own System counts on its own tangent, at states far
    from equilibrium where copies differ."""
    mechanisms, cases = variants("open_chain", "f+", [1.0, 0.8, 1.3, 1.1], [1.0, 2.0, 0.5, 1.0])
    spec = parse_model("prbm")
    batch = BatchSystem([(m, spec.model_family.connectors(m, spec)) for m in mechanisms])
    loads = batch.use_loads(cases)
    rng = np.random.default_rng(seed)
    q = batch.initial_state() + rng.normal(0.0, 2.5, batch.n_dofs) * batch.is_rotation
    found = []
    for factor in (1.0, 5.0, -5.0):
        _, _, tangent = batch.assemble(q, loads, factor)
        negative = batch._block_inertia(tangent, np.ones(batch.n_copies, bool))
        for k in range(batch.n_copies):
            system = batch.copy_system(k)
            _, _, own = system.assemble(batch.split(q, k), batch.copy_loads(k), factor)
            assert negative[k] == system.instability(own)
            found.append(negative[k])
    assert 0 in found and max(found) > 0


def test_a_batch_pauses_the_garbage_collector_only_while_it_runs():
    import gc

    mechanisms, cases = variants("open_chain", "f+", [1.0, 1.01], [1.0, 1.0])
    spec = parse_model("dcmm:1")
    assert gc.isenabled()
    run_batch(mechanisms, spec, cases)
    assert gc.isenabled()
    gc.disable()
    try:
        run_batch(mechanisms, spec, cases)
        assert not gc.isenabled()
    finally:
        gc.enable()


def test_ee_copies_of_other_topologies_are_refused_together_and_run_apart():
    """linear_responses refuses copies that do not share copy 0's numbering; run_batch
    groups them by topology first, so each still gets its solo path."""
    from flexval.reducedmodels.core.linearbatch import linear_responses

    open_m, open_c = variants("open_chain", "f+", [1.0, 1.1], [1.0, 1.0])
    closed_m, closed_c = variants("closed_chain", "f+", [1.0], [1.0])
    spec = parse_model("ee")
    members = [(m, spec.model_family.connectors(m, spec)) for m in (*open_m, *closed_m)]
    with pytest.raises(ValueError, match="one topology"):
        linear_responses(members, [*open_c, *closed_c])
    mechanisms, cases = [open_m[0], closed_m[0], open_m[1]], [open_c[0], closed_c[0], open_c[1]]
    paths = run_batch(mechanisms, spec, cases)
    assert [p.stats["batch"] for p in paths] == [2, 1, 2]
    for m, c, p in zip(mechanisms, cases, paths):
        assert comparable(p) == comparable(run_reduced(m, spec, c))
