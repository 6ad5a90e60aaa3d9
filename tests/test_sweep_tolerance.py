"""Tolerance studies of a sweep: the statistics, their files and first-order propagation."""

import dataclasses
import json
import math
import textwrap

import numpy as np
import pytest
from builders import in_process_client
from scipy.stats import norm

from flexval.geometry import SceneError
from flexval.reducedmodels import parse_model
from flexval.validation.cli import main
from flexval.validation.run import run_model
from flexval.validation.sweep import load_sweep, run_sweep, sweep_rows, write_outputs
from flexval.validation.sweep.spec import Axis
from flexval.validation.sweep.tolerance import (
    OUTPUTS,
    PERCENTILES,
    distribution,
    rounded,
    significant,
    study,
)
from flexval.validation.sweep.tolerancefiles import FILES, JSON_NAME, is_tolerance

TOLERANCE = """
name = "tol"
base = "open_chain"
models = ["ee", "dcmm:1"]
reference = "beam:20"
reference_sample = 5
load_cases = ["f+", "m+"]

[[axes]]
path = "section.thickness"
sample = "normal"
mean = 0.1
std = 0.002
count = 20
seed = 7
"""
"""20 draws of the open chain's thickness h ~ N(0.1, 0.002) mm; the reference on 5 of them."""


def _write(tmp_path, text, name="tol.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


# --- the statistics against numpy and against the population they sample ----------------


def test_distribution_is_numpy_on_the_finite_values():
    rng = np.random.default_rng(3)
    a = rng.normal(2.0, 0.5, 37)
    values = list(a) + [None, float("nan"), None]
    d = distribution(values)
    assert d["n"] == 37
    assert d["mean"] == np.mean(a)
    assert d["std"] == np.std(a, ddof=1)
    q = np.percentile(a, PERCENTILES)  # numpy's default method is linear
    assert [d["p1"], d["p50"], d["p99"]] == list(q)
    assert distribution([None, None]) == {
        "n": 0,
        "mean": None,
        "std": None,
        "p1": None,
        "p50": None,
        "p99": None,
    }
    one = distribution([4.0])
    assert one["n"] == 1 and one["mean"] == 4.0 and one["std"] is None and one["p99"] == 4.0


def test_distribution_of_normal_draws_within_their_sampling_error():
    """Each statistic within 4 standard errors of the population's value: the mean's
    sigma / sqrt(n), the standard deviation's sigma / sqrt(2 (n - 1)), a percentile's
    sqrt(p (1 - p) / n) / phi(z_p) sigma (the asymptotic variance of a sample quantile)."""
    mu, sigma, n = 0.1, 0.002, 4000
    d = distribution(np.random.default_rng(11).normal(mu, sigma, n))
    assert d["n"] == n
    assert abs(d["mean"] - mu) < 4 * sigma / math.sqrt(n)
    assert abs(d["std"] - sigma) < 4 * sigma / math.sqrt(2 * (n - 1))
    for p in PERCENTILES:
        z = norm.ppf(p / 100)
        se = math.sqrt(p / 100 * (1 - p / 100) / n) / norm.pdf(z) * sigma
        assert abs(d[f"p{p:g}"] - (mu + z * sigma)) < 4 * se


def _row(model, case, status="ok", **values):
    return {"model": model, "load_case": case, "status": status, "load_unit": "N"} | values


def test_study_counts_the_rows_that_carry_each_quantity():
    """Errors on 3 of 10 points, a failed run, a limit load on one row: n counts the rows
    with a value, ``rows`` every row of that model and case."""
    rng = np.random.default_rng(5)
    rows = []
    for i in range(10):
        dx, dy, rot = rng.normal(3.0, 0.1), rng.normal(4.0, 0.1), rng.normal(0.2, 0.01)
        target = dict(target_dx=dx, target_dy=dy, target_rotation=rot, peak_stress=10.0 + i)
        rows.append(_row("ref", "f", **target) if i < 3 else _row("ref", "f", status="skip"))
        err = dict(end_disp_vec=float(i), end_rot=None) if i < 3 else {}
        status = "solver_failure" if i == 9 else "ok"
        rows.append(_row("m", "f", status=status, **target, **err))
    rows[-1]["limit_load"] = 1.5
    data = study(rows, "ref", ["m"], ["f"])
    m = {k: v["models"]["m"]["f"] for k, v in data["outputs"].items()}
    assert m["displacement"]["n"] == 9 and m["displacement"]["rows"] == 10
    assert m["peak_stress"]["n"] == 9 and m["limit_load"]["n"] == 1
    ok = [r for r in rows if r["model"] == "m" and r["status"] == "ok"]
    want = [math.hypot(r["target_dx"], r["target_dy"]) for r in ok]
    assert m["displacement"]["mean"] == np.mean(want)
    assert m["rotation"]["std"] == np.std([math.degrees(r["target_rotation"]) for r in ok], ddof=1)
    assert data["outputs"]["displacement"]["models"]["ref"]["f"]["n"] == 3
    e = data["errors"]["end_disp_vec"]["models"]
    assert set(e) == {"m"} and e["m"]["f"]["n"] == 3 and e["m"]["f"]["mean"] == 1.0
    assert data["errors"]["end_rot"]["models"]["m"]["f"]["n"] == 0
    assert data["outputs"]["limit_load"]["units"] == {"f": "N"}
    text = json.dumps(rounded(data), allow_nan=False)
    assert "NaN" not in text


def test_rounding_keeps_significant_digits_and_never_writes_nan():
    assert significant(0.000123456) == 0.0001235 and significant(98765.4) == 98770.0
    assert significant(float("nan")) is None and significant(None) is None
    assert rounded({"a": [1.23456789, None, 3], "b": {"c": float("inf")}}) == {
        "a": [1.235, None, 3],
        "b": {"c": None},
    }


# --- reference_sample in the sweep file ---------------------------------------------------


def test_reference_sample_is_read(tmp_path):
    sweep = load_sweep(_write(tmp_path, TOLERANCE))
    assert sweep.reference_sample == 5 and is_tolerance(sweep)
    plain = load_sweep(_write(tmp_path, TOLERANCE.replace("reference_sample = 5\n", "")))
    assert plain.reference_sample is None


@pytest.mark.parametrize("value", ["0", "-3", "2.5", '"5"', "true"])
def test_bad_reference_sample_exits_2_naming_the_field(tmp_path, capsys, value):
    text = TOLERANCE.replace("reference_sample = 5", f"reference_sample = {value}")
    with pytest.raises(SceneError, match="reference_sample"):
        load_sweep(_write(tmp_path, text))
    code = main(["sweep", str(_write(tmp_path, text)), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and "reference_sample" in err and value.strip('"') in err.lower()
    assert not (tmp_path / "o").exists()


# --- the linear model: first-order propagation of the thickness's spread ------------------


def test_linear_model_spread_is_first_order_propagation(tmp_path):
    """For ``ee`` (linear), std(output) against |d output / d h| std(h) from central
    differences at the mean thickness.

    Writing x = h - h0 and output = y0 + g x + r(x), the triangle inequality of the
    standard deviation bounds |std(y) - |g| std(x)| by std(r), and r = g2 x^2 / 2 + O(x^3):
    the bound is |g2| std(x^2) / 2 with g2 from the same three runs, 10 % added for the
    cubic term (its share is ~ 4 sigma / h = 2 % of the quadratic one here) and the
    differences' truncation. With sigma / h = 0.5 % it is ~1.7 % of the spread (measured
    deviation 1.0 %: the sample's skewness couples x and x^2). With the quadratic term in the
    prediction, what is left is the cubic one, (5 / 3) x / h ~ 1 % of the quadratic term for
    an output ~ h^-3: a tenth of the first bound holds it (measured 1e-4 of the spread)."""
    h0, sigma, n = 0.1, 0.0005, 40
    cases = ("f+", "m+")
    text = TOLERANCE.replace("std = 0.002", f"std = {sigma}").replace("= 20", f"= {n}")
    sweep = load_sweep(_write(tmp_path, text))
    steps = load_sweep(
        _write(
            tmp_path,
            TOLERANCE.split("[[axes]]")[0]
            + f'[[axes]]\npath = "section.thickness"\nvalues = {[h0 - sigma, h0, h0 + sigma]}\n',
            "steps.toml",
        )
    )
    ee = parse_model("ee")

    def outputs(point, case):
        lp = run_model(point.scene, ee, point.scene.load_case(case))
        return lp.dx[-1], lp.dy[-1], lp.rotation[-1]

    rows, h = [], []
    for p in sweep.valid_points:
        h.append(p.params["section.thickness"])
        for case in cases:
            dx, dy, rot = outputs(p, case)
            rows.append(_row("ee", case, target_dx=dx, target_dy=dy, target_rotation=rot))
    x = np.array(h) - h0
    data = study(rows, "ee", [], cases, OUTPUTS[:2], ())
    for case in cases:
        at = []
        for p in steps.points:
            dx, dy, rot = outputs(p, case)
            at.append((math.hypot(dx, dy), math.degrees(rot)))
        for j, name in enumerate(("displacement", "rotation")):
            g = (at[2][j] - at[0][j]) / (2 * sigma)
            g2 = (at[2][j] - 2 * at[1][j] + at[0][j]) / sigma**2
            d = data["outputs"][name]["models"]["ee"][case]
            assert d["n"] == n
            bound = 1.1 * 0.5 * abs(g2) * np.std(x**2, ddof=1)
            assert abs(d["std"] - abs(g) * np.std(x, ddof=1)) <= bound, (case, name)
            assert bound < 0.02 * d["std"]
            second = np.std(g * x + 0.5 * g2 * x**2, ddof=1)
            assert abs(d["std"] - second) <= 0.1 * bound, (case, name)


# --- a real tolerance sweep: the summary's table, tolerance.json and the histograms -------


@pytest.fixture(scope="module")
def tolerance_run(tmp_path_factory):
    """The 20-point sweep run through the Python API, its summary written."""
    tmp = tmp_path_factory.mktemp("tolerance")
    sweep = load_sweep(_write(tmp, TOLERANCE))
    out = tmp / "out"
    with in_process_client() as client:
        run_sweep(sweep, out, client, use_cache=False)
    rows = sweep_rows(sweep, out)
    written = write_outputs(sweep, rows, out)
    return sweep, rows, out, written, _strict_json(out / JSON_NAME)


def _strict_json(path):
    def refuse(token):
        raise AssertionError(f"{path.name} holds {token}")

    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


def test_tolerance_sweep_writes_its_table_json_and_histograms(tolerance_run):
    sweep, rows, out, written, data = tolerance_run
    assert data["reference_sample"] == 5 and data["axes"][0]["count"] == 20
    summary = (out / "summary.md").read_text(encoding="utf-8")
    assert "## Tolerance study" in summary
    ref_points = {
        r["point"] for r in rows if r["model"] == sweep.reference.id and r["status"] == "ok"
    }
    for model in ("ee", "dcmm:1"):
        for case in sweep.load_cases:
            mine = [r for r in rows if r["model"] == model and r["load_case"] == case]
            peak = data["outputs"]["peak_stress"]["models"][model][case]
            assert peak["n"] == peak["rows"] == 20
            assert peak["mean"] == significant(np.mean([r["peak_stress"] for r in mine]))
            assert peak["p99"] == significant(np.percentile([r["peak_stress"] for r in mine], 99))
            assert f"| {model} | {case} | 20 / 20 |" in summary
            for metric in ("end_disp_vec", "end_rot"):
                err = data["errors"][metric]["models"][model][case]
                assert err["n"] == len(ref_points) and err["rows"] == 20
    assert sweep.reference.id not in data["errors"]["end_disp_vec"]["models"]
    pictures = {p.name for p in written if p.name.startswith("tolerance_")}
    assert {"tolerance_peak_stress.png", "tolerance_end_disp_vec.png"} <= pictures
    for name in pictures:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the same rows summarised as a sweep of listed values: no tolerance study, its files gone
    listed = dataclasses.replace(
        sweep, axes=tuple(Axis(a.path, a.values, False) for a in sweep.axes)
    )
    write_outputs(listed, rows, out)
    assert not any((out / name).exists() for name in FILES)
    assert "## Tolerance study" not in (out / "summary.md").read_text(encoding="utf-8")


def test_errors_only_on_the_reference_sample(tolerance_run):
    sweep, rows, out, _, data = tolerance_run
    for model in ("ee", "dcmm:1"):
        for case in sweep.load_cases:
            assert data["errors"]["end_disp_vec"]["models"][model][case]["n"] == 5
            assert data["outputs"]["peak_stress"]["models"][model][case]["n"] == 20
    assert data["outputs"]["peak_stress"]["models"][sweep.reference.id]["f+"]["n"] == 5


def test_target_displacement_and_rotation_of_every_point(tolerance_run):
    """The distributed target outputs of ``ee`` against its runs on the same scenes."""
    sweep, rows, out, written, data = tolerance_run
    ee = parse_model("ee")
    for case in sweep.load_cases:
        paths = [run_model(p.scene, ee, p.scene.load_case(case)) for p in sweep.valid_points]
        disp = data["outputs"]["displacement"]["models"]["ee"][case]
        rot = data["outputs"]["rotation"]["models"]["ee"][case]
        assert disp["n"] == rot["n"] == 20
        assert disp["mean"] == significant(np.mean([math.hypot(p.dx[-1], p.dy[-1]) for p in paths]))
        assert rot["std"] == significant(
            np.std([math.degrees(p.rotation[-1]) for p in paths], ddof=1)
        )
    assert {"tolerance_displacement.png", "tolerance_rotation.png"} <= {p.name for p in written}
