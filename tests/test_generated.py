"""Property-based robustness: random valid open and closed chains of arcs and
rigid links (some closed through a pin) under loads that give moderate
deflections, and random corruptions of valid scene files.

Every model either converges with finite results or raises SolverError with
a message at a limit point that arc-length continuation confirms (any other
solver failure fails the test); bad input is always a SceneError that names
a field. Examples are
derandomised so that the run is reproducible and its time bounded.
"""

import copy
import math
import tomllib
from importlib import resources

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, event, given, settings
from hypothesis import strategies as st

from flexval.geometry import Arc, Force, LoadCase, Material, Moment, SceneError, Section
from flexval.geometry.mechanism import FlexureSpec, PinSpec, assemble
from flexval.geometry.scene import parse_scene
from flexval.reducedmodels import SolverError, build_system, run_reduced
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core.continuation import limit_loads, solve_arclength

MODELS = ["dcmm:1", "dcmm:2", "beam:8", "ee", "prbm"]
LEVELS = 5

# no shrinking: a failing chain is reported as drawn (shrinking re-solves it for minutes)
FAST = settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    phases=[Phase.explicit, Phase.generate],
    suppress_health_check=[HealthCheck.too_slow],
)


@st.composite
def arc_from(draw, start: np.ndarray) -> tuple[Arc, bool, np.ndarray]:
    """An arc with one end at ``start``: (arc, whether start is the arc's start, far end).

    Radius 2..20 mm, width 20..300 deg, any orientation and sense.
    """
    r = draw(st.floats(2.0, 20.0))
    width = math.radians(draw(st.floats(20.0, 300.0)))
    phi = draw(st.floats(-math.pi, math.pi))  # polar angle of ``start`` on the circle
    forward = draw(st.booleans())
    center = start - r * np.array([math.cos(phi), math.sin(phi)])
    axis = phi + width / 2 if forward else phi - width / 2
    arc = Arc((float(center[0]), float(center[1])), r, axis, width)
    ends = arc.end_points
    return arc, forward, ends[1] if forward else ends[0]


@st.composite
def link(draw, point: np.ndarray) -> np.ndarray:
    """The next attachment point on the same rigid body: 0..10 mm away in any direction."""
    rho, psi = draw(st.floats(0.0, 10.0)), draw(st.floats(-math.pi, math.pi))
    return point + rho * np.array([math.cos(psi), math.sin(psi)])


@st.composite
def branch(
    draw, start: np.ndarray, bodies: list[str], prefix: str
) -> tuple[list[FlexureSpec], np.ndarray]:
    """Arcs in series from ``start`` on bodies[0] through rigid links to bodies[-1]."""
    specs, point = [], start
    for k in range(len(bodies) - 1):
        arc, forward, far = draw(arc_from(point))
        h = arc.radius * draw(st.floats(0.01, 0.08))
        specs.append(
            FlexureSpec(
                f"{prefix}{k}",
                arc,
                (bodies[k], bodies[k + 1]),
                Section(1.0, h),
                start_body=bodies[k] if forward else bodies[k + 1],
            )
        )
        point = draw(link(far)) if k < len(bodies) - 2 else far
    return specs, point


@st.composite
def chains(draw, closed: bool):
    """(mechanism, unit load case) of a random open or closed chain."""
    n = draw(st.integers(1, 3))
    bodies = ["g"] + [f"b{k}" for k in range(1, n + 1)]
    specs, end = draw(branch(np.zeros(2), bodies, "a"))
    ground_points = [np.zeros(2)]
    pins = []
    if closed:
        start = draw(link(np.zeros(2)))
        ground_points.append(start)
        if draw(st.booleans()):  # a second branch ending rigidly on the last body
            via = ["c1"] if draw(st.booleans()) else []
            more, _ = draw(branch(start, ["g", *via, bodies[-1]], "c"))
        else:  # ... or on its own body, pinned to the last body
            more, tip = draw(branch(start, ["g", "p1"], "c"))
            pins.append(PinSpec("pin", (bodies[-1], "p1"), (float(tip[0]), float(tip[1]))))
        specs += more
    target = draw(link(end))
    try:
        mech = assemble(
            specs,
            "g",
            np.array(ground_points),
            Material(2000.0, 0.3),
            bodies[-1],
            target,
            pin_specs=pins,
        )
    except SceneError as exc:
        # random arcs often cross: such a mechanism must be refused by name
        assert any(
            words in str(exc)
            for words in ("intersects itself", "closes on itself", "outline overlaps")
        ), str(exc)
        event("self-intersecting: refused with a SceneError")
        return None
    if draw(st.booleans()):
        case = LoadCase(
            "F", (Force(bodies[-1], target, draw(st.floats(-math.pi, math.pi)), 1.0),), LEVELS
        )
    else:
        case = LoadCase("M", (Moment(bodies[-1], 1.0),), LEVELS)
    return mech, case, draw(st.floats(0.02, 0.3)), draw(st.floats(0.05, 1.0))


def _moderate(mech, case, disp: float, rot: float) -> LoadCase:
    """``case`` scaled so that the linear (EE) motion is ``disp`` x size or ``rot`` rad."""
    lin = run_reduced(mech, parse_model("ee"), case)
    d, r = float(np.hypot(lin.dx[-1], lin.dy[-1])), abs(lin.rotation[-1])
    scale = min(disp * mech.size() / max(d, 1e-300), rot / max(r, 1e-300))
    comp = case.components[0]
    comp = (
        Force(comp.body, comp.point, comp.angle, scale)
        if isinstance(comp, Force)
        else Moment(comp.body, scale)
    )
    return LoadCase(case.name, (comp,), LEVELS)


def _assert_limit_point_below_full_load(mech, model: str, case: LoadCase, exc: SolverError) -> None:
    """A load-control failure is legitimate only at a limit point: arc-length
    continuation of the same model must find the load turning back below full load,
    at or above the load that load control reached (it stops just before the limit)."""
    system = build_system(mech, parse_model(model))
    path = solve_arclength(
        system,
        case,
        1.0,
        20,
        model=model,
        max_steps=2000,
        stop=lambda p: bool(p.stats["limit_points"]),
    )
    limits = [abs(p) / case.magnitude for p in limit_loads(path)]
    assert limits and exc.load_factor * (1 - 1e-3) <= limits[0] <= 1.0, (
        f"{model} failed under load control without a limit point: {exc}"
    )


def _check_every_model(mech, case) -> None:
    for model in MODELS:
        try:
            lp = run_reduced(mech, parse_model(model), case)
        except SolverError as exc:
            event(f"{model}: SolverError")  # outcome counts: --hypothesis-show-statistics
            assert str(exc).strip() and 0.0 <= exc.load_factor < 1.0
            partial = exc.path
            if partial is not None:
                assert np.all(np.isfinite(partial.dx + partial.dy + partial.rotation))
            _assert_limit_point_below_full_load(mech, model, case, exc)
            continue
        event(f"{model}: converged")
        assert lp.converged and len(lp.load) == LEVELS, model
        values = np.array([lp.load, lp.dx, lp.dy, lp.rotation])
        assert np.all(np.isfinite(values)), (model, values)
        # at zero load the undeformed state, up to the round-off of the rest residual
        assert max(abs(lp.dx[0]), abs(lp.dy[0])) < 1e-12 * mech.size(), model
        assert abs(lp.rotation[0]) < 1e-12, model


@FAST
@given(chains(closed=False))
def test_random_open_chains_converge_or_fail_honestly(example):
    if example is None:
        return
    mech, case, disp, rot = example
    _check_every_model(mech, _moderate(mech, case, disp, rot))


@FAST
@given(chains(closed=True))
def test_random_closed_chains_converge_or_fail_honestly(example):
    if example is None:
        return
    mech, case, disp, rot = example
    _check_every_model(mech, _moderate(mech, case, disp, rot))


# --- bad input ---------------------------------------------------------------


def _scene_dicts() -> list[dict]:
    """The built-in scenes, one extended with a body table, a combined load case,
    outputs and a pin, so that every kind of field is there to corrupt."""
    out = []
    for name in ("open_chain", "closed_chain"):
        text = resources.files("flexval.geometry").joinpath("scenes", f"{name}.toml").read_text()
        out.append(tomllib.loads(text))
    d = out[0]
    d["bodies"] = [{"name": "4", "points": [[15.0805, 15.5321]]}]  # where e34 meets body 4
    d["load_cases"].append(
        {
            "name": "both",
            "levels": 3,
            "loads": [
                {"kind": "moment", "value": 1e-3},
                {"kind": "force", "value": 1e-3, "angle_deg": 0.0},
            ],
        }
    )
    d["request"]["outputs"] = ["poses"]
    d["pins"] = [{"name": "p", "bodies": ["3", "4"], "point": [14.0, 14.0]}]
    return out


def _paths(data, prefix=()):
    yield prefix
    items = (
        data.items()
        if isinstance(data, dict)
        else enumerate(data)
        if isinstance(data, list)
        else ()
    )
    for k, v in items:
        yield from _paths(v, prefix + (k,))


JUNK = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-3, 2**70),
    st.text(max_size=3),
    st.floats(allow_nan=True, allow_infinity=True),
    st.lists(st.one_of(st.integers(-1, 3), st.floats(-5, 5), st.text(max_size=2)), max_size=3),
    st.dictionaries(st.text(max_size=2), st.integers(), max_size=2),
)


def _corrupt(data: dict, path: tuple, value) -> dict:
    """A copy of ``data`` with the entry at ``path`` replaced (None: deleted)."""
    out = copy.deepcopy(data)
    parent = out
    for k in path[:-1]:
        parent = parent[k]
    if value is None:
        if isinstance(parent, dict):
            del parent[path[-1]]
        else:
            parent.pop(path[-1])
    else:
        parent[path[-1]] = value
    return out


@st.composite
def corrupted(draw):
    data = draw(st.sampled_from(_scene_dicts()))
    paths = [p for p in _paths(data) if p]
    path = draw(st.sampled_from(paths))
    return _corrupt(data, path, draw(JUNK)), path


@settings(max_examples=300, deadline=None, derandomize=True)
@given(corrupted())
def test_corrupted_scenes_fail_with_a_scene_error_naming_a_field(example):
    data, path = example
    try:
        parse_scene(data, "fuzz.toml")
    except SceneError as exc:
        assert exc.field and f"field '{exc.field}'" in str(exc) and "fuzz.toml" in str(exc)


@pytest.mark.parametrize(
    "path,value",
    [
        (("bodies",), 0),
        (("bodies", 0), 0),
        (("bodies", 0, "points"), 0),
        (("load_cases",), [1]),
        (("load_cases", 0), 0),
        (("load_cases", 4, "loads"), "x"),
        (("load_cases", 4, "loads", 0), ""),
        (("load_cases", 4, "loads", 0), [1]),
        (("request", "models"), 0),
        (("request", "outputs"), 0),
        (("request", "outputs", 0), []),
    ],
)
def test_wrong_container_types_give_a_scene_error(path, value):
    """Containers of the wrong type (once crashes with TypeError/AttributeError)."""
    with pytest.raises(SceneError):
        parse_scene(_corrupt(_scene_dicts()[0], path, value), "fuzz.toml")
