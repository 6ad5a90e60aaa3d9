"""The report's plane-stress / plane-strain bracket of the continuum reference.

A flexure much wider than thick lies between plane stress (the reference) and
plane strain: the report runs the reference with the other plane assumption
(the catalogue option ``plane``), tabulates both end displacements and
rotations and their spread, and says whether each reduced model's error is
larger or smaller than that spread. Checked against direct runs of both
continua and the reduced models' errors computed here.
"""

from __future__ import annotations

import math

import pytest

from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.validation.report.data import compute_report
from flexval.validation.report.writer import write_report
from flexval.validation.run import run_model
from flexval.validation.studies.compare import errors

SCENE = "closed_chain"
MODELS = ["continuum", "beam:100", "dcmm:1"]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    data = compute_report(
        [SCENE], MODELS, repeats=1, use_cache=False, progress=False, bench=False, converge=False
    )
    return data, write_report(data, tmp_path_factory.mktemp("bracket"))


def test_bracket_is_the_reference_in_plane_strain(report):
    data, _ = report
    (res,) = data.scenes
    strain = parse_model("continuum").with_options(plane="strain")
    assert res.bracket.model == strain.id == f"{res.reference}[plane=strain]"
    scene = load_scene(SCENE)
    rows = res.bracket_rows()
    assert list(rows) == res.cases
    for case in scene.load_cases:
        direct = run_model(scene, strain, case)
        reference = run_model(scene, parse_model("continuum"), case)
        b = rows[case.name]
        assert b["disp_other"] == pytest.approx(direct.displacement[-1], rel=1e-9)
        assert b["rot_other"] == pytest.approx(direct.rotation[-1], rel=1e-9)
        assert b["disp"] == pytest.approx(reference.displacement[-1], rel=1e-9)
        assert b["disp_spread"] == pytest.approx(
            100 * abs(direct.displacement[-1] / reference.displacement[-1] - 1), rel=1e-9
        )
        # plane strain is stiffer (in-plane modulus E / (1 - nu^2) > E): less displacement
        assert b["disp_other"] < b["disp"]


def test_report_shows_the_bracket_and_compares_every_model_with_it(report):
    data, md = report
    text = md.read_text()
    (res,) = data.scenes
    section = text.split("### Plane-stress / plane-strain bracket")[1].split("\n### ")[0]
    for c, b in res.bracket_rows().items():
        assert (
            f"| {c} | {b['disp']:.6g} | {b['disp_other']:.6g} | {b['disp_spread']:.3g} | "
            f"{math.degrees(b['rot']):.6g} | {math.degrees(b['rot_other']):.6g} | "
            f"{b['rot_spread']:.3g} |"
        ) in section
    # the verdict, from errors computed here against the plane-stress reference
    rows = res.bracket_rows()
    larger = {m: [] for m in MODELS[1:]}
    smaller = {m: [] for m in MODELS[1:]}
    for m in MODELS[1:]:
        for c in res.cases:
            e = errors(res.paths[(m, c)], res.paths[(res.reference, c)], res.scene.mechanism.size())
            for key, spread, what in (
                ("end_disp", "disp_spread", "|d|"),
                ("end_rot", "rot_spread", "rotation"),
            ):
                (larger if e[key] > rows[c][spread] else smaller)[m].append(f"{c} {what}")
    if not any(larger.values()):
        assert "Every reduced model's error" in section and "is smaller than" in section
    elif not any(smaller.values()):
        assert "Every reduced model's error" in section and "is larger than" in section
    else:
        below = ", ".join(f"`{m}`" for m in MODELS[1:] if not larger[m])
        above = ", ".join(f"`{m}`" for m in MODELS[1:] if not smaller[m])
        mixed = "; ".join(
            f"`{m}` (larger on {', '.join(larger[m])})"
            for m in MODELS[1:]
            if larger[m] and smaller[m]
        )
        for text, head in (
            (below, "smaller on every case: "),
            (above, "larger on every case: "),
            (mixed, "mixed: "),
        ):
            assert (head + text in section) == bool(text), (head, text)
    timings = (md.parent / "timings.md").read_text()
    assert f"Computing the `{res.bracket.model}` paths (the plane bracket) takes" in timings


def test_no_bracket_without_a_plane_option():
    data = compute_report(
        [SCENE],
        ["beam:20", "dcmm:1"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    assert data.scenes[0].bracket is None and data.scenes[0].bracket_rows() == {}
