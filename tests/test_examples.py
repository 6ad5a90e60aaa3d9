"""The examples under examples/ run as they are and meet the checks their docstrings state.

Each example's ``main()`` returns its numbers; these tests hold them to the
independent references the examples describe (closed forms, exact linear
identities, the paper's ordering of the models).
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def load_example(name: str):
    """Import examples/<name>.py as a module (the folder is not a package)."""
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_example_is_tested():
    tested = {
        "pure_moment_circle",
        "compare_models",
        "custom_family",
        "rig_measurements",
        "batch_tolerance",
        "mechanism_library",
    }
    assert {p.stem for p in EXAMPLES.glob("*.py")} == tested


def test_mechanism_library_meets_its_anchors(tmp_path, monkeypatch):
    """beam:100 against each closed form: the guides' stiffness (their shuttles free to
    tilt: measured -0.10 % and -0.03 %), the cross pivot's (0.00 %), the snap-through force
    sampled at 0.1 mm (-0.02 %); the figure is written."""
    monkeypatch.chdir(tmp_path)
    errors = load_example("mechanism_library").main()
    assert abs(errors["parallel_guide"]) < 2e-3 and abs(errors["folded_guide"]) < 1e-3
    assert abs(errors["cross_pivot"]) < 1e-4 and abs(errors["bistable_truss"]) < 1e-3
    # the cartwheel's and the trapezoid's 8 EI/L and 26 EI/L are for inextensible leaves
    # (measured -0.07 % and -0.14 %: the leaves' axial compliance)
    assert abs(errors["cartwheel_hinge"]) < 2e-3 and abs(errors["trapezoid_pivot"]) < 3e-3
    # the bridge's hinges stretch: 1.6 % below the ideal pivots' cot(alpha) / 2 at a small
    # stroke (measured -1.5 % at its first 1 um level, the arms' flattening adding 0.1 %)
    assert -0.02 < errors["bridge_amplifier"] < -0.01
    assert (tmp_path / "mechanisms.png").stat().st_size > 10_000


def test_pure_moment_circle_converges_at_second_order():
    """beam:N tip error against the circle falls as 1/N^2 (measured orders 2.00)."""
    errors = load_example("pure_moment_circle").main()
    ns = sorted(errors)
    orders = [math.log2(errors[a] / errors[b]) for a, b in zip(ns, ns[1:])]
    assert all(1.9 < p < 2.1 for p in orders), orders
    assert errors[40] < 1e-4  # 5.8e-5 of the length measured


def test_compare_models_orders_the_models_as_the_paper():
    """Linear EE worst, DCMM better when split, the beam within 1 % of beam:100."""
    err = load_example("compare_models").main()
    assert err["ee"] > err["dcmm:1"] > err["dcmm:2"] > err["beam:20"]
    assert err["beam:20"] < 0.01  # 0.42 % measured


def test_custom_family_is_the_ellipse_of_elasticity():
    """The spring family equals ee to round-off where both are exactly linear.

    Measured differences are 1e-15 (rotation) and 9e-15 (displacement);
    1e-12 leaves room for the conditioning of the solves, far below any
    modelling difference (beam:100 differs by 7e-5 in rotation).
    """
    from flexval.reducedmodels.catalogue import families

    diff = load_example("custom_family").main()
    assert diff["rotation vs ee"] < 1e-12
    assert diff["linear f+ vs ee"] < 1e-12
    assert diff["rotation vs beam:100"] > 1e-6
    assert "ellipse-spring" not in {f.name for f in families()}


def test_rig_measurements_scores_the_models_as_the_report(tmp_path):
    """Against the synthetic rig (beam:100 with a uniform scatter of ±s of each column's
    range), each model's largest difference is its path error against beam:100 in the
    published report (reports/paper/gates.json: dcmm:1 14.80 %, beam:20 0.42 %), moved at
    most by the scatter: the difference by s, the measured range (the displacement at full
    load) by 2 s, in units of that range."""
    import json

    example = load_example("rig_measurements")
    scores = example.main(tmp_path)
    gates = json.loads((EXAMPLES.parent / "reports" / "paper" / "gates.json").read_text())
    s = example.SCATTER
    for model, score in scores.items():
        known = gates["open_chain"]["beam:100"][model]["f+"]["path_disp"]
        assert (known - 100 * s) / (1 + 2 * s) <= score <= (known + 100 * s) / (1 - 2 * s), model
    assert (tmp_path / "rig_open_chain_f+.png").is_file()


def test_batch_tolerance_traces_the_solo_paths_and_the_first_order_spread():
    """The batched copies are the solo paths (to 1e-12 of the displacement) and stay mostly
    in one batch; the spread of |d| over the draws is |d'| std(h) up to the response's
    curvature: with d = d0 + a x + b x^2 (x = h - h0 ~ N(0, s), a = d', b = d''/2) the
    spread's square is a^2 s^2 + 2 b^2 s^4 in expectation, and the sample's cross term of
    x and x^2 moves it by about 2 |b| s / sqrt(n) of a s relative; three of those bound the
    gap."""
    example = load_example("batch_tolerance")
    out = example.main()
    assert out["largest batch-solo difference (of |d|)"] <= 1e-12
    assert out["copies in the largest batch"] >= example.DRAWS / 2
    ratio = abs(out["d''(h) (mm/mm^2)"] / 2 * example.STD / out["d'(h) (mm/mm)"])
    bound = ratio**2 + 3 * 2 * ratio / math.sqrt(example.DRAWS)
    assert abs(out["std |d| (mm)"] / out["first-order std (mm)"] - 1) <= bound


def test_every_notebook_is_tested():
    assert {p.stem for p in EXAMPLES.glob("*.ipynb")} == {"designer_walkthrough"}


def test_designer_walkthrough_runs_and_its_numbers_hold(monkeypatch, capsys):
    """The notebook's code cells, run in order as Jupyter would (Agg backend): the calibrated
    reduced models meet the continuum on the notch hinges (within 0.2 %: measured 0.07 %),
    plain Euler-Bernoulli (``beam:20[eb]``) is 5-8 % stiff (measured 6.5 %); two of the four
    hinges made thicker turn the mechanism less, but not less than all four would (a
    circular notch's compliance scales as t^(-5/2): 0.5 -> 0.6 mm is a factor of 0.634)."""
    import json

    import matplotlib.pyplot as plt

    monkeypatch.setenv("MPLBACKEND", "Agg")
    notebook = json.loads((EXAMPLES / "designer_walkthrough.ipynb").read_text())
    names: dict = {}
    for cell in notebook["cells"]:
        if cell["cell_type"] == "code":
            exec(compile("".join(cell["source"]), "designer_walkthrough.ipynb", "exec"), names)
    plt.close("all")
    printed = capsys.readouterr().out
    assert "beam:20[eb]" in printed and "end rotation" in printed
    from flexval.validation.studies.compare import errors

    size = names["scene"].mechanism.size()
    for lp in names["paths"]:
        found = errors(lp, names["reference"], size)
        if lp.model.endswith("[eb]"):
            assert 5.0 < found["end_disp"] < 8.0
            assert lp.dx[-1] < names["reference"].dx[-1]  # stiffer than the continuum
        else:
            assert found["end_disp"] < 0.2, lp.model
    ratio = names["stiffer"].dx[-1] / names["paths"][0].dx[-1]
    assert (0.6 / 0.5) ** -2.5 < ratio < 1.0
