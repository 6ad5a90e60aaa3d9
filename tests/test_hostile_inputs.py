"""Hostile input, found by generating a few hundred bad and extreme inputs: each class
below could run long, crash or be accepted silently; each must fail up front with a
message naming the field and the value (exit 2), over several values each."""

import pytest
from test_scene_errors import _base, _dump

from flexval.geometry import BUILTIN_SCENES, SceneError, load_scene
from flexval.geometry.loads import MAX_LOAD_SUBSTEPS
from flexval.reducedmodels.core.settings import SolverSettings
from flexval.validation.cli import EXIT_INPUT, MAX_LOCAL_WORKERS, main


def test_the_level_cap_is_the_solvers_sub_step_cap():
    assert SolverSettings().max_substeps == MAX_LOAD_SUBSTEPS


@pytest.mark.parametrize("levels", [MAX_LOAD_SUBSTEPS + 1, 50_000, 100_000, 2**63])
def test_scene_levels_beyond_the_sub_step_cap_are_refused(tmp_path, levels):
    """``levels`` the solver cannot reach (one sub-step per increment at least) are refused
    while reading the scene, not after a long run ending in exit 3."""
    data = _base()
    data["load_cases"][0]["levels"] = levels
    path = tmp_path / "levels.toml"
    path.write_text(_dump(data))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    msg = str(info.value)
    assert "load_cases.m+.levels" in msg and str(levels) in msg, msg
    assert str(MAX_LOAD_SUBSTEPS) in msg


@pytest.mark.parametrize("levels", [2, 11, MAX_LOAD_SUBSTEPS])
def test_scene_levels_within_the_cap_are_accepted(tmp_path, levels):
    data = _base()
    data["load_cases"][0]["levels"] = levels
    path = tmp_path / "levels.toml"
    path.write_text(_dump(data))
    assert load_scene(path).load_cases[0].levels == levels


@pytest.mark.parametrize(
    "key,value",
    [("point", [1.0, 1.0]), ("point", [20.0, 15.8]), ("angle_deg", 30.0), ("angle_deg", 0.0)],
)
def test_a_moment_with_a_point_or_direction_is_refused(tmp_path, key, value):
    """A moment acts on its whole body: a ``point`` or ``angle_deg`` given with it was
    silently ignored, hiding a scene that meant a force."""
    data = _base()
    data["load_cases"][0][key] = value
    path = tmp_path / "moment.toml"
    path.write_text(_dump(data))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert f"'load_cases.m+.{key}'" in str(info.value), str(info.value)


@pytest.mark.parametrize(
    "model,levels",
    [("dcmm", "2"), ("beam", "20001"), ("beam", "5:9"), ("dcmm", "3:5"), ("continuum", "1")],
)
def test_a_study_of_one_resolution_is_refused_before_work(model, levels, monkeypatch, capsys):
    """One resolution gives no ratio, order or Richardson value (the table printed
    'refinement ratio nan'); a large single N ran for minutes before saying so."""
    import flexval.validation.studies.convergence

    def forbidden(*args, **kwargs):
        raise AssertionError("the study ran although --levels was refused")

    monkeypatch.setattr(flexval.validation.studies.convergence, "study", forbidden)
    argv = ["converge", "open_chain", "--model", model, "--levels", levels]
    assert main(argv) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "'--levels'" in err and levels in err and "single resolution" in err, err


@pytest.mark.parametrize(
    "law,field,shown",
    [
        ("t1 = 1e-300\n", "t1", "1e-300"),
        ("t1 = 5e-324\n", "t1", "5e-324"),
        ("t1 = 1e-12\n", "t1", "1e-12"),
        ("t1 = 1.0\nend_time = 1e-200\n", "end_time", "1e-200"),
    ],
)
def test_a_time_law_too_short_to_integrate_is_refused(tmp_path, capsys, law, field, shown):
    """A run shorter than the integrator's smallest first step ended in ZeroDivisionError."""
    from test_dynamics import SCENE

    scene = tmp_path / "short.toml"
    scene.write_text(SCENE + 'ramp = "eq15"\n' + law, encoding="utf-8")
    assert main(["run", str(scene), "--dynamic", "--model", "ee"]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert f"'load_cases.m.{field}'" in err and shown in err and "Traceback" not in err, err


@pytest.mark.parametrize("duration", ["1e-300", "5e-324", "1e-10", "0", "1e7", "nan", "inf"])
def test_a_duration_outside_the_integrators_range_is_refused(tmp_path, capsys, duration):
    from test_dynamics import SCENE

    scene = tmp_path / "dyn.toml"
    scene.write_text(SCENE, encoding="utf-8")
    assert (
        main(["run", str(scene), "--dynamic", "--model", "ee", "--duration", duration])
        == EXIT_INPUT
    )
    err = capsys.readouterr().err
    assert "'--duration'" in err and str(float(duration)) in err, err


@pytest.mark.parametrize("workers", [MAX_LOCAL_WORKERS + 1, 1024, 100_000, 2**63])
def test_a_local_cluster_larger_than_the_cpu_count_is_refused(tmp_path, capsys, workers):
    """--workers up to 1024 started that many Python processes on one machine (~100 MB
    each): runaway memory. The local cluster is capped at the logical CPU count."""
    with pytest.raises(SystemExit) as info:
        main(["sweep", "slenderness", "--workers", str(workers), "--out", str(tmp_path)])
    assert info.value.code == EXIT_INPUT
    err = capsys.readouterr().err
    assert "--workers" in err and str(workers) in err and str(MAX_LOCAL_WORKERS) in err, err
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("value", [1e-320, 5e-324, 2e-308])
@pytest.mark.parametrize("field", ["material.density", "bodies.4.mass", "bodies.4.inertia"])
def test_subnormal_mass_data_is_refused(tmp_path, field, value):
    """A subnormal density gave masses that vanish: ``flexval modes`` crashed with a shape
    mismatch (no eigenpairs); subnormal body masses and inertias are the same class."""
    data = _base()
    data["material"]["density"] = 1.2e-9
    body = {"name": "4", "mass": 1e-6, "inertia": 1e-5, "center_of_mass": [20.0, 15.8]}
    data["bodies"] = [body]
    table, key = field.rsplit(".", 1)
    (data["material"] if table == "material" else body)[key] = value
    path = tmp_path / "mass.toml"
    path.write_text(_dump(data))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert f"'{field}'" in str(info.value) and "smallest normal" in str(info.value)


def test_the_mass_data_base_is_valid(tmp_path):
    data = _base()
    data["material"]["density"] = 1.2e-9
    data["bodies"] = [{"name": "4", "mass": 1e-6, "inertia": 1e-5, "center_of_mass": [20.0, 15.8]}]
    path = tmp_path / "mass.toml"
    path.write_text(_dump(data))
    assert load_scene(path).mechanism.inertia.bodies["4"].mass == 1e-6


@pytest.mark.parametrize(
    "argv",
    [
        ["info", "open_chain", "--json", ""],
        ["run", "open_chain", "--model", "ee", "--load-case", "m+", "--json", ""],
        ["converge", "open_chain", "--model", "dcmm", "--levels", "1:2", "--json", ""],
        ["modes", "open_chain", "--model", "ee", "--density", "1.2e-9", "--json", ""],
        ["modes", "open_chain", "--model", "ee", "--density", "1.2e-9", "--plot", ""],
        ["sweep", "slenderness", "--out", ""],
    ],
)
def test_an_empty_output_path_is_refused_not_ignored(argv, tmp_path, monkeypatch, capsys):
    """``--json ''`` was taken as 'no JSON' (the run went on and wrote nothing) and
    ``sweep --out ''`` as the default folder sweeps/NAME: an empty path is an error."""
    monkeypatch.chdir(tmp_path)
    assert main(argv) == EXIT_INPUT
    err = capsys.readouterr().err
    option = argv[-2]
    assert f"'{option}'" in err, err
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("density", ["1e-300", "1e-320", "5e-324", "0", "nan", "1"])
def test_modes_density_option_is_range_checked(density, capsys):
    assert main(["modes", "open_chain", "--model", "ee", "--density", density]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "'--density'" in err and "Traceback" not in err, err


_MASSLESS_SCENES = [
    name
    for name in BUILTIN_SCENES
    if load_scene(name).mechanism.inertia.density is None
    and load_scene(name).mechanism.inertia.massless_bodies(load_scene(name).mechanism.moving_bodies)
]


@pytest.mark.parametrize("scene", _MASSLESS_SCENES)
@pytest.mark.parametrize(
    "argv",
    [
        ["modes", "{scene}", "--model", "dcmm:2"],
        ["modes", "{scene}", "--model", "ee", "--at", "0.5"],
        ["run", "{scene}", "--model", "ee", "--dynamic", "--duration", "0.01"],
    ],
)
def test_a_massless_scene_is_refused_naming_the_density_option(scene, argv, capsys):
    """Modes and time histories of a scene without density or body masses are undefined:
    refused up front naming --density with PLA as the example (the report, which
    assumes PLA, says so), never a refusal naming a body's mass the user cannot give
    on the command line."""
    assert main([a.format(scene=scene) for a in argv]) == EXIT_INPUT
    captured = capsys.readouterr()
    assert "field '--density' = None" in captured.err and "1.24e-09 (PLA)" in captured.err
    assert "Traceback" not in captured.err and "bodies." not in captured.err, captured.err


def test_there_are_massless_builtin_scenes():
    assert "open_chain" in _MASSLESS_SCENES


@pytest.mark.parametrize("density", ["1e-320", "5e-324", "0", "-1.24e-9", "nan", "inf", "1240"])
def test_dynamic_density_option_is_range_checked(density, capsys):
    argv = ["run", "open_chain", "--model", "ee", "--dynamic", "--duration", "0.01"]
    assert main([*argv, f"--density={density}"]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "'--density'" in err and "Traceback" not in err, err


@pytest.mark.parametrize(
    "path, words",
    [
        ("section.thicknes", "did you mean 'thickness'?"),
        ("materail.youngs_modulus", "did you mean 'material'?"),
        ("material.youngs_modulos", "did you mean 'youngs_modulus'?"),
        ("flexures.e122.radius", "did you mean 'e12'?"),
        ("flexures.e12.raduis", "did you mean 'radius'?"),
        ("load_cases.m+.vlaue", "did you mean 'value'?"),
    ],
)
def test_a_sweep_path_that_names_no_scene_field_names_the_nearest(tmp_path, capsys, path, words):
    """A misspelt axis path is refused on the sweep file's field, naming the closest scene
    field, before any point is built or any output folder made."""
    sweep = tmp_path / "sw.toml"
    sweep.write_text(
        f'base = "open_chain"\nmodels = ["ee"]\nreference = "dcmm:1"\n'
        f'[[axes]]\npath = "{path}"\nvalues = [0.1, 0.2]\n',
        encoding="utf-8",
    )
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "o")]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "'axes[0].path'" in err and repr(path) in err and words in err, err
    assert not (tmp_path / "o").exists()


def _flexval_peak(argv, env_memory=None, timeout=60):
    """Run ``flexval argv`` in a fresh process; (exit code, stderr, seconds, peak RSS bytes)."""
    import os
    import subprocess
    import sys
    import time

    from peakmemory import PEAK_KB as _PEAK_KB

    code = (
        "import sys\n"
        "from flexval.validation.cli import main\n"
        f"rc = main({list(argv)!r})\n"
        f"print('peak', {_PEAK_KB}, file=sys.stderr)\n"
        "sys.exit(rc)\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "FLEXVAL_MEMORY"}
    if env_memory is not None:
        env["FLEXVAL_MEMORY"] = env_memory
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=timeout
    )
    seconds = time.perf_counter() - t0
    peak = int(done.stderr.rsplit("peak", 1)[1]) * 1024  # VmHWM: kB
    return done.returncode, done.stderr, seconds, peak


def _lower_fitting(scene_name, level, budget):
    """The finest continuum level below ``level`` whose estimate fits ``budget`` bytes."""
    import flexval.validation  # noqa: F401  (registers the continuum)
    from flexval.reducedmodels import parse_model

    mechanism = load_scene(scene_name).mechanism
    for r in range(level - 1, -1, -1):
        spec = parse_model(f"continuum:{r}")
        if spec.model_family.cost(mechanism, spec, None).bytes <= budget:
            return spec.id
    return None


@pytest.mark.parametrize("budget,level", [("1G", 8), ("1G", 3), ("300M", 2), ("4G", 5)])
def test_a_continuum_level_beyond_the_memory_budget_is_refused_before_work(budget, level):
    """A mesh level whose estimated peak memory exceeds the budget ($FLEXVAL_MEMORY here, so
    the test does not depend on the machine) exits 2 at once, naming the estimate, the budget
    and the finest level that fits; deciding stays small in time and memory."""
    from flexval.validation.resources import _parse_size

    argv = ["run", "open_chain", "--model", f"continuum:{level}", "--load-case", "m+"]
    rc, err, seconds, peak = _flexval_peak(argv, budget)
    assert rc == EXIT_INPUT, err
    assert "'--model'" in err and f"continuum:{level}" in err and "of memory" in err, err
    assert "$FLEXVAL_MEMORY" in err and "unknowns" in err, err
    lower = _lower_fitting("open_chain", level, _parse_size(budget))
    assert lower is not None and f"{lower} needs about" in err, err
    assert seconds < 15 and peak < 1e9, (seconds, peak)


def test_continuum_level_8_is_refused_on_this_machine():
    """Without a budget the machine's available memory is the bound: level 8 of the open
    chain (about 1.8 TB) is refused here, quickly and without growing."""
    argv = ["run", "open_chain", "--model", "continuum:8", "--load-case", "m+"]
    rc, err, seconds, peak = _flexval_peak(argv)
    assert rc == EXIT_INPUT, err
    assert "continuum:8" in err and ("the memory available" in err or "cgroup" in err), err
    assert seconds < 15 and peak < 1e9, (seconds, peak)


@pytest.mark.parametrize(
    "argv",
    [
        ["converge", "open_chain", "--model", "continuum", "--levels", "0:8"],
        ["modes", "open_chain", "--model", "continuum:7"],
        ["stress", "open_chain", "--model", "continuum:6", "--quick"],
        ["report", "--model", "continuum:6", "--model", "ee", "--no-bench"],
    ],
)
def test_every_command_checks_the_continuum_memory_before_work(argv, tmp_path, capsys):
    """converge, modes, stress and report refuse a level beyond the budget before any work."""
    if argv[0] in ("stress", "report"):
        argv = [*argv, "--out", str(tmp_path / "out")]
    import os

    os.environ["FLEXVAL_MEMORY"] = "2G"
    try:
        assert main(argv) == EXIT_INPUT
    finally:
        del os.environ["FLEXVAL_MEMORY"]
    err = capsys.readouterr().err
    assert "of memory" in err and "$FLEXVAL_MEMORY" in err and "continuum:" in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("text", ["lots", "-1G", "0", "1X", "nan"])
def test_a_malformed_memory_budget_is_refused(text, monkeypatch, capsys):
    monkeypatch.setenv("FLEXVAL_MEMORY", text)
    assert main(["run", "open_chain", "--model", "continuum:1", "--load-case", "m+"]) == 2
    err = capsys.readouterr().err
    assert "FLEXVAL_MEMORY" in err and repr(text) in err, err


def _huge_sweep(tmp_path, count=100_000, combine="grid"):
    path = tmp_path / "huge.toml"
    path.write_text(
        'name = "huge"\nbase = "open_chain"\nmodels = ["ee"]\nreference = "beam:20"\n'
        f'combine = "{combine}"\n'
        f'[[axes]]\npath = "section.thickness"\nlinspace = [0.08, 0.12, {count}]\n'
        f'[[axes]]\npath = "material.youngs_modulus"\nlinspace = [2000.0, 2200.0, {count}]\n'
    )
    return path


def test_a_ten_billion_point_sweep_is_refused_from_its_axes(tmp_path):
    """Two axes of 100,000 values: 10^10 points, counted from the axes (no point built),
    refused at once naming the count and the option that accepts it."""
    path = _huge_sweep(tmp_path)
    rc, err, seconds, peak = _flexval_peak(["sweep", str(path), "--out", str(tmp_path / "o")])
    assert rc == EXIT_INPUT, err
    assert "10,000,000,000 points" in err and "--max-points 1,000,000" in err, err
    assert seconds < 15 and peak < 1e9, (seconds, peak)
    assert not (tmp_path / "o").exists()


def test_a_sweep_accepted_by_max_points_is_still_refused_by_memory(tmp_path):
    """--max-points lifts the count bound, not the memory the points would hold."""
    from flexval.validation.sweep.fields import BYTES_PER_POINT

    path = _huge_sweep(tmp_path)
    argv = ["sweep", str(path), "--out", str(tmp_path / "o"), "--max-points", str(10**10)]
    rc, err, seconds, peak = _flexval_peak(argv, "8G")
    assert rc == EXIT_INPUT, err
    assert "10,000,000,000 points" in err and "of memory" in err and "$FLEXVAL_MEMORY" in err
    assert f"{10**10 * BYTES_PER_POINT / 1e9:.2e} GB" in err, err
    assert seconds < 15 and peak < 1e9, (seconds, peak)


@pytest.mark.parametrize("max_points,count", [(99, 10), (10, 4)])
def test_max_points_bounds_a_small_sweep_too(tmp_path, capsys, max_points, count):
    """The bound is exact: count^2 grid points above --max-points are refused, at or below
    it the sweep is built (zip: count points)."""
    from flexval.validation.sweep import load_sweep

    path = _huge_sweep(tmp_path, count)
    if count * count > max_points:
        with pytest.raises(SceneError) as info:
            load_sweep(path, max_points)
        assert f"{count * count:,} points" in str(info.value)
    assert len(load_sweep(_huge_sweep(tmp_path, count, "zip"), max_points).points) == count
