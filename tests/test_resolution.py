"""Loads too small for double precision: a level whose answer is round-off is not valid.

A nonlinear model's Newton iteration stops on corrections below a fixed
fraction of the mechanism's size, and its states are positions rounded to
that size: under a load that moves the target by 1e-14 of the size its
answer can have the wrong sign. The validity monitor's screen
(:func:`flexval.reducedmodels.core.validity.resolution_reasons`) must flag every
level whose answer is further than 0.1 % from the exact one, at any load
scale, and no level whose answer is right.

The independent answer is each model's own response at a load a million
times smaller than the paper's, scaled linearly: its rotations are about
1e-6 rad, so the linear scaling holds to about 1e-6, and its motion is
a million times its round-off.
"""

import dataclasses
import math

import numpy as np
import pytest
from builders import with_sections_scaled

from flexval.geometry import Force, LoadCase, Moment, load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.batch import run_batch
from flexval.reducedmodels.core.validity import RESOLVED_MOTION, ROUND_OFF_GROWTH
from flexval.reducedmodels.models import run_reduced
from flexval.validation.run import run_model

REFERENCE_SCALE = 1e-6  # of the paper's loads: linear to ~1e-6, far above round-off
TOLERANCE = 2.0 / RESOLVED_MOTION  # a level the screen keeps: round-off within 1 / RESOLVED


def _scaled(case: LoadCase, factor: float) -> LoadCase:
    comps = tuple(
        dataclasses.replace(c, value=factor * c.value) if isinstance(c, Force | Moment) else c
        for c in case.components
    )
    return dataclasses.replace(case, components=comps)


def _motions(path, size: float) -> np.ndarray:
    """(levels, 3): the target's dx / size, dy / size and rotation (rad)."""
    return np.column_stack([np.asarray(path.dx) / size, np.asarray(path.dy) / size, path.rotation])


@pytest.fixture(scope="module")
def chain():
    return load_scene("open_chain")


MODELS = ["beam:20", "beam:100", "dcmm:2", "prbm"]


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("case_name", ["m+", "f+"])
def test_every_level_kept_is_right_and_round_off_is_flagged(chain, model, case_name):
    spec = parse_model(model)
    case = next(c for c in chain.load_cases if c.name == case_name)
    size = chain.mechanism.size()
    reference = run_model(chain, spec, _scaled(case, REFERENCE_SCALE))
    assert all(reference.valid)
    per_load = _motions(reference, size)[1:] / np.asarray(reference.load[1:])[:, None]
    worst = 0.0  # largest round-off seen, in units of eps sqrt(unknowns)
    for scale in (1e-9, 1e-11, 1e-12, 1e-13, 1e-14, 1e-17):
        path = run_model(chain, spec, _scaled(case, scale))
        exact = per_load * np.asarray(path.load[1:])[:, None]
        found = _motions(path, size)[1:]
        error = np.abs(found - exact).max(axis=1)
        moved = np.abs(exact).max(axis=1)
        worst = max(worst, error.max() / (np.finfo(float).eps * math.sqrt(path.stats["unknowns"])))
        for k, (ok, why) in enumerate(zip(path.valid[1:], path.validity[1:])):
            if ok:
                assert error[k] <= TOLERANCE * moved[k], (scale, k, error[k] / moved[k])
            else:
                assert "double precision does not resolve this load" in why
        if scale <= 1e-14:  # motions of 1e-15 of the size and less: all noise
            assert not any(path.valid[1:]), scale
    assert path.valid[0]  # the rest is the rest
    assert worst <= ROUND_OFF_GROWTH, worst


def test_a_linear_response_is_exact_at_any_load(chain):
    """ee solves for displacements, not positions: nothing to flag, and exact."""
    spec = parse_model("ee")
    case = chain.load_cases[0]
    reference = run_model(chain, spec, case)
    tiny = run_model(chain, spec, _scaled(case, 1e-14))
    assert all(tiny.valid)
    assert np.allclose(np.asarray(tiny.rotation) * 1e14, reference.rotation, rtol=1e-12)


@pytest.mark.slow
def test_the_continuum_flags_loads_within_its_rest_balance(chain):
    """The continuum's mesh is in balance at rest only to round-off: it reports that motion at
    rest, and every level within a thousand times it is flagged."""
    spec = parse_model("continuum:0")
    case = chain.load_cases[0]
    size = chain.mechanism.size()
    reference = run_model(chain, spec, _scaled(case, REFERENCE_SCALE))
    per_load = _motions(reference, size)[1:] / np.asarray(reference.load[1:])[:, None]
    for scale in (1e-9, 1e-12):
        path = run_model(chain, spec, _scaled(case, scale))
        exact = per_load * np.asarray(path.load[1:])[:, None]
        error = np.abs(_motions(path, size)[1:] - exact).max(axis=1)
        moved = np.abs(exact).max(axis=1)
        for k, ok in enumerate(path.valid[1:]):
            if ok:
                assert error[k] <= TOLERANCE * moved[k], (scale, k, error[k] / moved[k])
        if scale == 1e-12:
            assert not any(path.valid[1:])


@pytest.mark.parametrize("model, scale", [("beam:20", 3e-11), ("dcmm:2", 1e-11)])
def test_a_batch_flags_the_same_levels_as_each_copy_alone(chain, model, scale):
    """At these scales the first levels are within the screen's floor and the last not."""
    spec = parse_model(model)
    case = _scaled(chain.load_cases[0], scale)
    mechanisms = with_sections_scaled(chain.mechanism, (0.97, 1.0, 1.02))
    batched = run_batch(mechanisms, spec, [case] * 3)
    flagged = 0
    for mechanism, together in zip(mechanisms, batched):
        alone = run_reduced(mechanism, spec, case)
        assert together.valid == alone.valid and together.validity == alone.validity
        flagged += alone.valid.count(False)
    assert 0 < flagged < 3 * (len(alone.valid) - 1)
