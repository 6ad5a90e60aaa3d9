"""The report's continuum stress picture at full load, one per load case of each scene.

A tiny scene (one arc and a link) with the coarsest continuum as reference, whose run on
one load case is made to fail: the section shows the picture of the case the reference
reached (drawn by the continuum's own picture function after solving the case again) and
a sentence naming the failure for the other. Without a continuum reference the section
says so and draws nothing.
"""

from __future__ import annotations

import pytest
from test_report import TINY

from flexval.reducedmodels import SolverError
from flexval.validation import failures
from flexval.validation.report import figures
from flexval.validation.report.data import compute_report
from flexval.validation.report.writer import render_markdown, write_report
from flexval.validation.studies import campaign

REFERENCE = "continuum:0"
FAILING_CASE = "twist"
HEADING = "### Continuum stress at full load"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _section(text: str) -> str:
    """The stress-picture section of the report's only scene."""
    return text.split(HEADING)[1].split("\n### ")[0]


@pytest.fixture(scope="module")
def failing_reference(tmp_path_factory):
    """The report's data and report.md, the reference failing at half load on ``twist``."""
    d = tmp_path_factory.mktemp("picture")
    (d / "tiny.toml").write_text(TINY)
    real = campaign.run_model

    def fail_on_twist(scene, spec, case, *args, **kwargs):
        if spec.id == REFERENCE and case.name == FAILING_CASE:
            raise SolverError("no convergence", 0.5)
        return real(scene, spec, case, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(campaign, "run_model", fail_on_twist)
        mp.setattr(failures, "first_limit", lambda *args: None)  # no arc-length search
        data = compute_report(
            [str(d / "tiny.toml")],
            [REFERENCE, "beam:10"],
            repeats=1,
            use_cache=False,
            progress=False,
            bench=False,
            converge=False,
        )
    return data, write_report(data, d / "out")


def test_the_case_the_reference_reached_has_its_picture(failing_reference):
    data, md = failing_reference
    section = _section(md.read_text())
    png = md.parent / "tiny_up_continuum_stress.png"
    assert f"![tiny up: continuum stress]({png.name})" in section
    assert png.read_bytes().startswith(PNG_SIGNATURE)
    assert f"solved again with `{REFERENCE}`" in section


def test_the_case_the_reference_failed_has_a_sentence(failing_reference):
    data, md = failing_reference
    (res,) = data.scenes
    fail = res.failure(REFERENCE, FAILING_CASE)
    assert fail is not None and fail.factor == 0.5
    section = _section(md.read_text())
    assert (
        f"`{FAILING_CASE}`: not drawn, `{REFERENCE}` {fail.summary()}: "
        "there is no state at full load." in section
    )
    assert not (md.parent / f"tiny_{FAILING_CASE}_continuum_stress.png").exists()


def test_the_picture_is_drawn_by_the_figure_function(failing_reference, tmp_path):
    """The section hands the scene, the reference and the case to
    :func:`figures.field_picture` (on the figure workers), once per case reached."""
    data, _ = failing_reference
    calls = []
    render_markdown(data, tmp_path, lambda fn, *args: calls.append((fn, args)))
    drawn = [args for fn, args in calls if fn is figures.field_picture]
    (res,) = data.scenes
    assert [(a[0], a[1], a[2], a[3].name) for a in drawn] == [
        (res.scene, REFERENCE, "up", "tiny_up_continuum_stress.png")
    ]


def test_without_a_continuum_reference_the_section_says_why(tmp_path):
    (tmp_path / "tiny.toml").write_text(TINY)
    data = compute_report(
        [str(tmp_path / "tiny.toml")],
        ["beam:10", "ee"],
        repeats=1,
        use_cache=False,
        progress=False,
        bench=False,
        converge=False,
    )
    calls = []
    text = render_markdown(data, tmp_path, lambda fn, *args: calls.append(fn))
    assert _section(text).strip() == (
        "Not drawn: the report's models include no continuum reference "
        "(a model with stress fields, e.g. `continuum`)."
    )
    assert figures.field_picture not in calls
