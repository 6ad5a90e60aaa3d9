"""The one stability rule: verdicts that depend neither on the resolution nor on the units.

Straight columns have closed-form critical loads (Timoshenko and Gere,
*Theory of elastic stability*, Sects. 2.1-2.2): a clamped-free column
(tests/scenes/euler_column.toml) buckles at pi^2 EI / (4 L^2), a parallel
leaf guide pushed along its leaves (tests/scenes/leaf_guide.toml: two
clamped-guided leaves) sways at 2 pi^2 EI / L^2. Plain load control past
those loads must stop at the bifurcation, with every model that can buckle
and at every resolution: within 1 % for beams of 10 or more elements, 2 %
for the continuum (the continuum's own plane-stress column is a little
stiffer in shear, and its load reaches the leaf through the end faces).

The rule itself (:mod:`flexval.reducedmodels.core.stability`) is checked against
numpy's eigenvalues on matrices whose smallest eigenvalue is far above
round-off, for every storage (dense, banded, sparse, a batch's blocks) and
for saddle points, and for invariance under a change of units (a diagonal
congruence S K S), which a margin against |K| does not have.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from builders import with_sections_scaled

from flexval.geometry import load_scene
from flexval.reducedmodels.core import stability
from flexval.reducedmodels.core.settings import SolverError
from flexval.reducedmodels.core.tangent import BandedTangent, DenseTangent, SparseTangent
from flexval.validation.run import run_model

SCENES = Path(__file__).parent / "scenes"
COLUMN, GUIDE = SCENES / "euler_column.toml", SCENES / "leaf_guide.toml"


def _critical(path: Path, factor: float) -> float:
    """``factor`` pi^2 EI / L^2 of the scene's first leaf (N)."""
    data = tomllib.loads(path.read_text())
    section, flexure = data["section"], data["flexures"][0]
    ei = data["material"]["youngs_modulus"] * section["depth"] * section["thickness"] ** 3 / 12
    return factor * math.pi**2 * ei / math.dist(flexure["start"], flexure["end"]) ** 2


def _bifurcation(path: Path, model: str) -> float:
    """The load (N) at which plain load control stops at a bifurcation; fails otherwise."""
    import flexval

    scene = load_scene(str(path))
    with pytest.raises(SolverError) as caught:
        run_model(scene, flexval.parse_model(model), scene.load_cases[0])
    path = caught.value.path
    assert path is not None and path.bifurcations, str(caught.value)
    return path.bifurcations[-1]["load"]


def _band(matrix: np.ndarray, b: int) -> np.ndarray:
    """Upper band storage (b + 1, n) of a symmetric band matrix."""
    n = matrix.shape[0]
    band = np.zeros((b + 1, n), order="F")
    for j in range(n):
        for i in range(max(0, j - b), j + 1):
            band[b + i - j, j] = matrix[i, j]
    return band


def _random_band(rng, n: int, b: int, negative: int, multipliers: int = 0) -> np.ndarray:
    """A symmetric band matrix with ``negative`` negative eigenvalues in its stiffness part and
    ``multipliers`` zero-diagonal rows (each coupling to a neighbour) after it, gap >= 0.1."""
    k = n - multipliers
    a = np.zeros((k, k))
    for i in range(k):
        for j in range(i, min(k, i + b + 1)):
            a[i, j] = a[j, i] = rng.normal() if i != j else 0.0
    values, vectors = np.linalg.eigh(a)
    spectrum = np.abs(values) + 0.1
    spectrum[:negative] *= -1.0
    stiffness = (vectors * spectrum) @ vectors.T  # dense: kept banded by projection below
    matrix = np.zeros((n, n))
    for i in range(k):
        for j in range(max(0, i - b), min(k, i + b + 1)):
            matrix[i, j] = stiffness[i, j]
    for m in range(multipliers):
        row, column = k + m, k - 1 - 2 * m
        matrix[row, column] = matrix[column, row] = 1.0 + rng.random()
    return matrix


@pytest.mark.parametrize("seed", range(6))
def test_every_storage_counts_sylvesters_inertia(seed):
    rng = np.random.default_rng(seed)
    n, b = 40, 3
    for multipliers in (0, 2):
        matrix = _random_band(rng, n, b, negative=seed % 4, multipliers=multipliers)
        values = np.linalg.eigvalsh(matrix)
        assert np.abs(values).min() > 1e-8 * np.abs(values).max()  # the count is not round-off's
        expected = int(np.sum(values < 0.0))
        width = max(b, int(np.max(np.abs(np.subtract.outer(*np.nonzero(matrix))))))
        banded = BandedTangent(_band(matrix, width), np.arange(n), width, multipliers > 0)
        assert banded.negative_eigenvalues() == expected
        assert DenseTangent(matrix, multipliers > 0).negative_eigenvalues() == expected
        sparse = SparseTangent(sp.csc_matrix(matrix), multipliers)
        if multipliers == 0:
            assert sparse.negative_eigenvalues() == expected


@pytest.mark.parametrize("exponent", [-6, -3, 3, 6])
def test_the_count_is_the_same_in_any_units(exponent):
    """S K S (a change of units) has K's inertia, and the rule counts it so, even where one
    unknown's units make |K| 1e12 times its smallest column's scale."""
    rng = np.random.default_rng(1)
    n, b = 30, 2
    matrix = _random_band(rng, n, b, negative=1)
    scale = np.ones(n)
    scale[::3] = 10.0**exponent  # translations in m instead of mm, say
    scaled = matrix * np.outer(scale, scale)
    expected = int(np.sum(np.linalg.eigvalsh(matrix) < 0.0))
    for m in (matrix, scaled):
        assert BandedTangent(_band(m, b), np.arange(n), b).negative_eigenvalues() == expected
        assert DenseTangent(m).negative_eigenvalues() == expected
        assert SparseTangent(sp.csc_matrix(m), 0).negative_eigenvalues() == expected


def test_a_pivot_within_its_own_round_off_has_no_sign():
    gamma = stability.tolerance(3)
    kernels = stability.kernels()
    assert kernels.one_negative(-1e-17, 1.0, gamma) == 0
    assert kernels.one_negative(-1e-12, 1.0, gamma) == 1
    # a 2 x 2 saddle block: one negative eigenvalue; a positive definite one: none
    assert kernels.pair_negative(0.0, 1.0, 0.0, 0.0, 0.0, gamma) == 1
    assert kernels.pair_negative(2.0, 1.0, 2.0, 2.0, 2.0, gamma) == 0
    assert kernels.pair_negative(-2.0, 1.0, -2.0, 2.0, 2.0, gamma) == 2


@pytest.mark.parametrize("elements", [5, 10, 20, 50, 100, 200, 400])
def test_a_clamped_free_column_stops_at_eulers_load_at_every_resolution(elements):
    found = _bifurcation(COLUMN, f"beam:{elements}")
    tolerance = 0.01 if elements >= 10 else 0.02  # beam:5 is 0.8 % off (measured)
    assert found == pytest.approx(_critical(COLUMN, 0.25), rel=tolerance)


@pytest.mark.parametrize("elements", [5, 20, 100, 400])
def test_a_parallel_leaf_guide_stops_at_its_sway_load_at_every_resolution(elements):
    found = _bifurcation(GUIDE, f"beam:{elements}")
    tolerance = 0.01 if elements >= 10 else 0.04  # beam:5 is 3.3 % off (measured)
    assert found == pytest.approx(_critical(GUIDE, 2.0), rel=tolerance)


@pytest.mark.parametrize("model", ["dcmm:4", "prbm"])
def test_the_discrete_models_stop_at_their_own_buckling_load(model):
    """dcmm:4 and prbm buckle at their own, lower loads (discrete chains: 9 % and 6 % below
    2 pi^2 EI / L^2 on the guide, measured); they must stop there, never go on as valid."""
    found = _bifurcation(GUIDE, model)
    assert 0.85 * _critical(GUIDE, 2.0) < found < _critical(GUIDE, 2.0)


@pytest.mark.slow
@pytest.mark.parametrize("level", [0, 1])
def test_the_continuum_stops_at_eulers_load(level):
    found = _bifurcation(COLUMN, f"continuum:{level}")
    assert found == pytest.approx(_critical(COLUMN, 0.25), rel=0.02)


@pytest.mark.parametrize("factor", [1e-3, 1e3])
def test_a_column_in_other_units_buckles_at_the_same_load_factor(tmp_path, factor):
    """The column with E (and so every stiffness) scaled by ``factor``: the load scales with
    it and the bifurcation's load factor is the same."""
    text = COLUMN.read_text()
    data = tomllib.loads(text)
    scaled = text.replace(
        f"youngs_modulus = {data['material']['youngs_modulus']}",
        f"youngs_modulus = {data['material']['youngs_modulus'] * factor!r}",
    ).replace(
        f"value = {data['load_cases'][0]['value']}",
        f"value = {data['load_cases'][0]['value'] * factor!r}",
    )
    path = tmp_path / "column.toml"
    path.write_text(scaled)
    for elements in (20, 400):
        here = _bifurcation(path, f"beam:{elements}") / factor
        there = _bifurcation(COLUMN, f"beam:{elements}")
        assert here == pytest.approx(there, rel=1e-5)


@pytest.mark.parametrize("model", ["beam:20", "beam:100", "prbm", "dcmm:4"])
def test_a_batch_of_copies_stops_at_each_copys_own_bifurcation(model):
    """Copies of the leaf guide with their sections scaled traced as one batch stop where each
    stops alone, at the same bifurcation load bit for bit (one rule, one kernel per storage)."""

    from flexval.reducedmodels.catalogue import parse_model
    from flexval.reducedmodels.core.batch import trace_batch
    from flexval.reducedmodels.core.recorder import solve_path
    from flexval.reducedmodels.models import build_system

    scene = load_scene(str(GUIDE))
    spec, case = parse_model(model), scene.load_cases[0]
    mechanisms = with_sections_scaled(scene.mechanism, (1.0, 1.0, 0.99, 1.02))
    solo = []
    for mechanism in mechanisms:
        with pytest.raises(SolverError) as caught:
            solve_path(build_system(mechanism, spec), case, None, model)
        solo.append(caught.value)
    batched = trace_batch([build_system(m, spec) for m in mechanisms], [case] * 4, None, model)
    for alone, together in zip(solo, batched):
        assert isinstance(together, SolverError)
        assert together.path.bifurcations == alone.path.bifurcations
        assert alone.path.bifurcations


def _buckle(tmp_path, scene: Path, *args: str) -> dict:
    import json

    from flexval.validation.cli import main

    out = tmp_path / "buckle.json"
    assert main(["buckle", str(scene), *args, "--json", str(out)]) == 0
    return json.loads(out.read_text())


def test_buckle_gives_a_columns_euler_loads(tmp_path):
    """Clamped-free: (2k - 1)^2 pi^2 EI / (4 L^2), k = 1, 2, 3 (beam:100 within 0.5 %), and
    load control's bifurcation beside them."""
    record = _buckle(tmp_path, COLUMN, "--model", "beam:100", "--count", "3")
    euler = _critical(COLUMN, 0.25)
    for k, load in enumerate(record["critical_loads"], 1):
        assert load == pytest.approx((2 * k - 1) ** 2 * euler, rel=0.005)
    assert record["load_control"]["kind"] == "bifurcation"
    assert record["load_control"]["load"] == pytest.approx(euler, rel=0.005)
    tip = record["mode_shapes"][0]["tip"]
    assert abs(tip[0]) > 10 * abs(tip[1])  # the first mode sways across the axis


@pytest.mark.parametrize("model", ["beam:100", "continuum:0"])
def test_buckle_gives_a_leaf_guides_sway_load(tmp_path, model):
    record = _buckle(tmp_path, GUIDE, "--model", model, "--count", "1")
    (load,) = record["critical_loads"]
    assert load == pytest.approx(_critical(GUIDE, 2.0), rel=0.005)
    preloaded = _buckle(tmp_path, GUIDE, "--model", model, "--count", "1", "--at", "0.5")
    assert preloaded["critical_loads"][0] == pytest.approx(load, rel=1e-3)


def test_buckle_refuses_a_linear_model_and_a_bad_fraction(tmp_path, capsys):
    from flexval.validation.cli import main

    assert main(["buckle", str(GUIDE), "--model", "ee"]) == 2
    assert "no geometric stiffness" in capsys.readouterr().err
    assert main(["buckle", str(GUIDE), "--model", "beam:20", "--at", "1.5"]) == 2
    assert "--at" in capsys.readouterr().err


def test_a_resolution_beyond_double_precision_is_refused_at_rest():
    """beam:10000 on the open chain: the rest tangent's Cholesky fails in double precision
    (the tip pivots are 10^-12 of their columns' scale, their terms cancel to round-off), and
    Newton cannot converge from there (the previous behaviour: a stall after minutes). The
    run stops at once at rest with the reason; beam:3000 (rest Cholesky intact) runs."""
    import flexval

    scene = load_scene("open_chain")
    case = next(c for c in scene.load_cases if c.name == "m+")
    with pytest.raises(SolverError, match="not positive definite in double precision"):
        run_model(scene, flexval.parse_model("beam:10000"), case)
    path = run_model(scene, flexval.parse_model("beam:3000"), case)
    assert path.converged and all(path.valid) and "stability" not in path.stats


def _cross_pivot_critical(path: Path) -> float:
    """The cross-axis pivot's critical load (N) by classical matrix stability analysis,
    independent of flexval's models: each leaf a beam-column clamped in the ground, its top
    end's stiffness in its own axes from Livesley's stability functions under the axial
    compression N = P / (2 sin a) that the symmetric pre-buckling state carries (s =
    l (sin l - l cos l) / D, s c = l (l - sin l) / D, D = 2 - 2 cos l - l sin l, l = L
    sqrt(N / EI); Livesley and Chandler, Stability functions for structural frameworks,
    1956), transformed to the top body's (x, y, theta) at the load point, plus the axial
    force's work on the second-order motion of the clamp as the body turns (N r.t); the
    critical load is where the 3 x 3 stiffness first turns singular."""
    from scipy.optimize import brentq

    data = tomllib.loads(path.read_text())
    e, section = data["material"]["youngs_modulus"], data["section"]
    ei = e * section["depth"] * section["thickness"] ** 3 / 12
    ea = e * section["depth"] * section["thickness"]
    point = np.array(data["load_cases"][0]["point"])

    def stiffness(load: float) -> np.ndarray:
        total = np.zeros((3, 3))
        for leaf in data["flexures"]:
            start, end = np.array(leaf["start"]), np.array(leaf["end"])
            length = float(np.linalg.norm(end - start))
            t = (end - start) / length
            n = np.array([-t[1], t[0]])
            axial = load / (2.0 * abs(t[1]))
            lam = length * math.sqrt(axial / ei)
            d = 2.0 - 2.0 * math.cos(lam) - lam * math.sin(lam)
            s = lam * (math.sin(lam) - lam * math.cos(lam)) / d
            sc = lam * (lam - math.sin(lam)) / d
            local = np.array(
                [
                    [ea / length, 0.0, 0.0],
                    [0.0, (2 * (s + sc) - lam**2) * ei / length**3, -(s + sc) * ei / length**2],
                    [0.0, -(s + sc) * ei / length**2, s * ei / length],
                ]
            )
            offset = end - point
            motion = np.array([[1.0, 0.0, -offset[1]], [0.0, 1.0, offset[0]]])
            transform = np.vstack([t @ motion, n @ motion, [0.0, 0.0, 1.0]])
            total += transform.T @ local @ transform
            total[2, 2] += axial * float(offset @ t)
        return total

    def lowest(load: float) -> float:
        return float(np.linalg.eigvalsh(stiffness(load)).min())

    loads = np.linspace(1.0, data["load_cases"][0]["value"], 200)
    signs = [lowest(p) > 0.0 for p in loads]
    k = signs.index(False)
    return brentq(lowest, loads[k - 1], loads[k])


CROSS = SCENES / "cross_pivot.toml"


@pytest.mark.parametrize("model", ["beam:10", "beam:40", "beam:160", "continuum:0"])
def test_a_cross_axis_pivot_buckles_at_its_stability_function_load(model):
    """52.09 N by stability functions; beam:100 52.12 N, continuum:0 52.08 N measured."""
    tolerance = 0.02 if model.startswith("continuum") else 0.01
    assert _bifurcation(CROSS, model) == pytest.approx(_cross_pivot_critical(CROSS), rel=tolerance)


FOLDED = SCENES / "folded_guide.toml"


@pytest.mark.parametrize("model", ["beam:10", "beam:40", "beam:400", "continuum:0", "continuum:1"])
def test_a_folded_guide_stops_where_its_inner_leaves_sway(model):
    """The inner pair of a folded guide sways at 2 pi^2 EI / L^2 while the outer pair is
    stretched (tests/scenes/folded_guide.toml); measured 71.93 N (beam:400), 71.92 N
    (continuum:1) against 71.96 N."""
    tolerance = 0.02 if model.startswith("continuum") else 0.01
    assert _bifurcation(FOLDED, model) == pytest.approx(_critical(FOLDED, 2.0), rel=tolerance)


def test_a_column_a_thousand_times_larger_buckles_at_the_same_load_factor(tmp_path):
    """Every length times 1000 (mm to um, as it were) and the load times 10^6 (P_cr ~ E b h^3 /
    L^2 grows with length squared): the same bifurcation factor at beam:20 and beam:400."""
    data = tomllib.loads(COLUMN.read_text())
    k = 1000.0
    text = f"""name = "column_scaled"
[material]
youngs_modulus = {data["material"]["youngs_modulus"]!r}
poisson_ratio = {data["material"]["poisson_ratio"]!r}
[section]
depth = {data["section"]["depth"] * k!r}
thickness = {data["section"]["thickness"] * k!r}
[ground]
name = "g"
points = [[0.0, 0.0]]
[target]
body = "tip"
point = [0.0, {100.0 * k!r}]
[[flexures]]
name = "column"
bodies = ["g", "tip"]
shape = "segment"
start = [0.0, 0.0]
end = [0.0, {100.0 * k!r}]
[[load_cases]]
name = "P"
kind = "force"
body = "tip"
point = [0.0, {100.0 * k!r}]
angle_deg = -90.0
value = {data["load_cases"][0]["value"] * k * k!r}
"""
    path = tmp_path / "column.toml"
    path.write_text(text)
    for elements in (20, 400):
        here = _bifurcation(path, f"beam:{elements}") / (k * k)
        assert here == pytest.approx(_bifurcation(COLUMN, f"beam:{elements}"), rel=1e-5)


def test_buckle_says_when_the_path_passes_its_linearised_loads(tmp_path):
    """The closed chain under f+ turns far at small loads: about rest the linearised tangent
    turns singular at 0.5 % of the load, while load control is stable to the full load; the
    record says the linearisation does not hold (the leaf guide's does)."""
    record = _buckle(tmp_path, Path("closed_chain"), "--model", "beam:20", "--load-case", "f+")
    assert record["load_control"]["kind"] == "none"
    assert record["critical_factors"][0] < 0.01 and not record["linearisation_holds"]
    guide = _buckle(tmp_path, GUIDE, "--model", "beam:20", "--count", "1")
    assert guide["linearisation_holds"]


@pytest.mark.parametrize(
    "path, model, per_leaf",
    [
        (COLUMN, "ee", 0.25),  # a cantilever leaf: pi^2 EI / (4 L^2)
        (GUIDE, "ee", 1.0),  # guided leaves: pi^2 EI / L^2 each
        (GUIDE, "dcmm:1", 1.0),
        (FOLDED, "ee", 1.0),
        (FOLDED, "dcmm:1", 1.0),
    ],
)
def test_a_model_blind_to_sway_is_invalid_past_the_leafs_euler_load(path, model, per_leaf):
    """ee is linear and dcmm:1's single compliance has no geometric stiffness for a leaf whose
    ends stay parallel: they reach the full load, but every level whose leaf compression
    passes the leaf's Euler load is outside their validity, the first valid level below
    it (the guide's two leaves share the push: 2 pi^2 EI / L^2 in all)."""
    import flexval

    scene = load_scene(str(path))
    case = scene.load_cases[0]
    lp = run_model(scene, flexval.parse_model(model), case)
    leaves = 1 if path == COLUMN else 2
    critical = leaves * _critical(path, per_leaf)
    for load, valid, why in zip(lp.load, lp.valid, lp.validity):
        assert valid == (abs(load) <= critical), (load, why)
        if not valid:
            assert "no geometric stiffness for its sway" in why


@pytest.mark.parametrize("model", ["ee", "dcmm:1"])
def test_a_batch_of_sway_blind_copies_flags_the_same_levels_as_each_alone(model):

    from flexval.reducedmodels.catalogue import parse_model
    from flexval.reducedmodels.core.batch import run_batch
    from flexval.reducedmodels.models import run_reduced

    scene = load_scene(str(GUIDE))
    case = scene.load_cases[0]
    mechanisms = with_sections_scaled(scene.mechanism, (0.98, 1.0, 1.03))
    spec = parse_model(model)
    batched = run_batch(mechanisms, spec, [case] * 3)
    for mechanism, together in zip(mechanisms, batched):
        alone = run_reduced(mechanism, spec, case)
        assert together.valid == alone.valid and together.validity == alone.validity
        assert not all(alone.valid)
