"""A load path's validity verdicts and section forces, judged in one pass per connector.

The path recorder asks each group of connectors once per path for both
(``ConnectorGroup.path_end_pass``: ``path_validity`` and
``path_section_forces``); the DCMM and PRBM answer with one vectorised pass,
the beams with one compiled pass for both. These tests hold the one-pass
answers to the state-by-state ones (``validity``, ``section_forces``),
exactly (to the last bit), along paths that cross the models' limits and
at states placed on a limit to the last bit, where a screen in array
arithmetic is most likely to disagree with the scalar check.
"""

import dataclasses

import numpy as np
import pytest
from builders import cantilever, tip_moment

from flexval.geometry import Segment, load_scene
from flexval.reducedmodels import LoadControl, build_system, trace
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.recorder import end_pass
from flexval.reducedmodels.core.validity import MAX_RELATIVE_ROTATION, MAX_STRAIN

MODELS = ["dcmm:1", "dcmm:3", "dcmm:2[frame=follower]", "prbm", "beam:6"]


def overloaded_states(model: str, factor: float):
    """The system of ``model`` on the open chain and its states along f- at
    ``factor`` times the load."""
    scene = load_scene("open_chain")
    case = next(c for c in scene.load_cases if c.name == "f-")
    case = dataclasses.replace(
        case,
        components=tuple(dataclasses.replace(c, value=c.value * factor) for c in case.components),
    )
    system = build_system(scene.mechanism, parse_model(model))
    points = trace(system, system.loads(case), LoadControl(case.factors()))
    return system, [p.state for p in points]


@pytest.mark.parametrize("model", MODELS)
def test_one_pass_verdicts_and_forces_are_the_state_by_state_ones(model):
    system, states = overloaded_states(model, 30.0)
    levels = [system.local_states(q) for q in states]
    judgement = end_pass(system, states, with_forces=True)
    verdicts, forces = judgement.reasons[0], judgement.forces[0]
    singles = [
        [f"{c.name}: {w}" for c, local in zip(system.connectors, lv) for w in c.validity(*local)]
        for lv in levels
    ]
    assert verdicts == singles
    assert any(verdicts) and not all(verdicts)  # the path crosses a limit
    assert [c for c, _ in forces] == list(system.connectors)
    for k, (c, stacked) in enumerate(forces):  # the end pass's forces
        check_stacked(c, [lv[k] for lv in levels], stacked)
    for group, run in system.groups:  # all the group's connectors in one pass
        for k, (c, stacked) in enumerate(
            zip(group.connectors, group.path_section_forces([lv[run] for lv in levels]))
        ):
            states = [lv[run][k] for lv in levels]
            check_stacked(c, states, stacked)
    for k, c in enumerate(system.connectors):  # each connector alone
        states = [lv[k] for lv in levels]
        check_stacked(c, states, c.path_section_forces(states))


@pytest.mark.parametrize("model", MODELS)
def test_group_forces_of_given_gradients_are_each_connectors_own(model):
    """A group's section forces from known gradients (the linear response's) are
    each connector's, bit for bit."""
    system, states = overloaded_states(model, 1.0)
    states = system.local_states(states[-1])
    gradients = [c.evaluate(*local)[1] for c, local in zip(system.connectors, states)]
    for group, run in system.groups:
        together = group.section_forces(states[run], gradients[run])
        for c, local, g, forces in zip(group.connectors, states[run], gradients[run], together):
            alone = c.section_forces(*local, gradient=g)
            assert np.array_equal(alone.at, forces.at)
            assert np.array_equal(alone.axial, forces.axial)
            assert np.array_equal(alone.moment, forces.moment)
            assert np.ptp(alone.moment) > 0.0  # a load that bends the flexure


def check_stacked(c, states, stacked):
    """The connector's stacked forces are its state-by-state ones, bit for bit."""
    for row, state in enumerate(states):
        one = c.section_forces(*state)
        assert np.array_equal(one.at, stacked.at)
        assert np.array_equal(one.axial, stacked.axial[row])
        assert np.array_equal(one.moment, stacked.moment[row])


@pytest.mark.parametrize("model", ["dcmm:1", "dcmm:2"])
def test_dcmm_screen_defers_to_the_exact_check_on_the_limits(model):
    length = 10.0
    mech = cantilever(Segment((0.0, 0.0), (length, 0.0)))
    system = build_system(mech, parse_model(model))
    c = system.connectors[0]
    rest = system.local_states(system.initial_state())[0]
    ground, _, internal = rest
    n = len(internal) // 3 + 1
    states = []
    # every sub-arc turned by the rotation limit, to the last bit
    for t in (
        np.nextafter(MAX_RELATIVE_ROTATION, 0.0),
        MAX_RELATIVE_ROTATION,
        np.nextafter(MAX_RELATIVE_ROTATION, 4.0),
    ):
        cuts = internal.reshape(-1, 3).copy()
        cuts[:, 2] = t * np.arange(1, n)
        states.append((ground, np.array([length, 0.0, t * n]), cuts.ravel()))
    # chords stretched to the strain limit, to the last bit, along the axis
    for stretch in (MAX_STRAIN, np.nextafter(MAX_STRAIN, 0.0), np.nextafter(MAX_STRAIN, 1.0)):
        scale = 1.0 + stretch
        cuts = internal.reshape(-1, 3).copy()
        cuts[:, 0] *= scale
        states.append((ground, np.array([length * scale, 0.0, 0.0]), cuts.ravel()))
    verdicts = c.path_validity(states)
    assert verdicts == [c.validity(*s) for s in states]
    assert any(verdicts) and not all(verdicts)


def test_prbm_screen_defers_to_the_exact_check_on_the_limits():
    length = 10.0
    mech = cantilever(Segment((0.0, 0.0), (length, 0.0)))
    system = build_system(mech, parse_model("prbm"))
    c = system.connectors[0]
    ground, _, internal = system.local_states(system.initial_state())[0]
    limit = c._fitted_rotation
    states = [
        (ground, np.array([length, 0.0, t]), internal)
        for t in (np.nextafter(limit, 0.0), limit, np.nextafter(limit, 4.0))
    ]
    states += [
        (ground, np.array([length * (1.0 + s), 0.0, 0.0]), internal)
        for s in (np.nextafter(MAX_STRAIN, 0.0), MAX_STRAIN, np.nextafter(MAX_STRAIN, 1.0))
    ]
    verdicts = c.path_validity(states)
    assert verdicts == [c.validity(*s) for s in states]
    assert any(verdicts) and not all(verdicts)


def test_recorded_path_matches_the_state_by_state_judgement():
    mech = cantilever(Segment((0.0, 0.0), (10.0, 0.0)))
    moment = 1.5 * MAX_RELATIVE_ROTATION * 2100.0 * 0.1**3 / 12.0 / 10.0
    system = build_system(mech, parse_model("dcmm:1"))
    case = tip_moment(moment, levels=5)
    from flexval.reducedmodels.core.recorder import solve_path

    lp = solve_path(system, case)
    states = [p.state for p in trace(system, system.loads(case), LoadControl(case.factors()))]
    assert lp.validity == ["; ".join(r) if r else None for r in map(system.validity, states)]
    c = system.connectors[0]
    section = mech.flexures[0].section
    for level, q in enumerate(states):
        sigma, at = c.section_forces(*system.local_states(q)[0]).peak(section)
        assert lp.peak_stress["f"][level] == sigma and lp.peak_stress_at["f"][level] == at


@pytest.mark.parametrize("model", ["dcmm:1", "dcmm:2", "beam:4"])
def test_a_path_of_many_alike_flexures_has_each_flexures_own_stresses(model):
    """A path alone whose group stacks more flexures than ``STACK_FROM`` (one compiled pass for
    the stack) records each flexure's peak stress and its place as that flexure's own section
    forces give them, bit for bit, at every level: a path alone is judged by the same end pass
    as a batch's copies."""
    from flexval.geometry import Force, LoadCase, Material, Section
    from flexval.geometry.mechanism import FlexureSpec, assemble
    from flexval.reducedmodels.core.peaks import STACK_FROM
    from flexval.reducedmodels.core.recorder import solve_path

    count = STACK_FROM + 1  # leaves of a parallel guide, each of its own thickness
    specs = [
        FlexureSpec(
            f"f{i}",
            Segment((2.0 * i, 0.0), (2.0 * i, 10.0)),
            ("g", "t"),
            Section(1.0, 0.1 + 0.01 * i),
            start_body="g",
        )
        for i in range(count)
    ]
    ground = np.array([[2.0 * i, 0.0] for i in range(count)])
    mech = assemble(specs, "g", ground, Material(2100.0, 0.3), "t", np.array([0.0, 10.0]))
    case = LoadCase("F", (Force("t", mech.target_point, 0.0, 0.02),), 4)
    system = build_system(mech, parse_model(model))
    lp = solve_path(system, case, record_shapes=True)
    states = [p.state for p in trace(system, system.loads(case), LoadControl(case.factors()))]
    sections = {f.name: f.section for f in mech.flexures}
    assert list(lp.peak_stress) == [c.name for c in system.connectors]
    for level, q in enumerate(states):
        for c, local in zip(system.connectors, system.local_states(q)):
            forces = c.section_forces(*local)
            sigma, at = forces.peak(sections[c.name])
            assert lp.peak_stress[c.name][level] == sigma
            assert lp.peak_stress_at[c.name][level] == at
            assert lp.section_forces[c.name]["moment"][level] == forces.moment.tolist()
