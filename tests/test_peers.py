"""The OpenSees peer model (flexval.validation.studies.peers) solves the same problem as flexval's
beams.

OpenSees' corotational elasticBeamColumn and flexval's beam:N discretise the
flexures the same way (N two-node corotational Euler-Bernoulli elements, nodes
on the centre line), so the two independent solvers must agree on the end
values to far below the discretisation error: the bar of the benchmark,
0.01 %, measured at 0.0000-0.0001 % with N = 100 (``bench_peers.py``). Skipped
where OpenSeesPy is not installed (an optional extra, absent from CI).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from flexval.geometry import load_scene
from flexval.geometry.inertia import MassData
from flexval.validation.studies.peers import (
    AGREEMENT_BAR,
    PeerRow,
    PeerUnavailable,
    agreement,
    compare_with_opensees,
)


def _opensees_or_skip():
    try:
        from flexval.validation.studies.peers import opensees

        return opensees()
    except PeerUnavailable as exc:
        pytest.skip(str(exc))


@pytest.mark.parametrize("scene_name", ["open_chain", "closed_chain"])
def test_opensees_and_flexval_beams_agree_on_every_paper_case(scene_name):
    _opensees_or_skip()
    rows = compare_with_opensees(load_scene(scene_name), n=10, repeats=1)
    assert [r.case for r in rows] == [c.name for c in load_scene(scene_name).load_cases]
    for row in rows:
        assert row.substeps is not None, row.case
        assert row.agreement <= AGREEMENT_BAR, (row.case, row.agreement)
        assert row.ratio > 0 and math.isfinite(row.b2b_ratio)


def test_a_scene_with_gravity_is_refused_before_opensees_is_asked():
    scene = load_scene("open_chain")
    mech = dataclasses.replace(
        scene.mechanism, inertia=MassData(density=7.85e-9, gravity=np.array([0.0, -9810.0]))
    )
    heavy = dataclasses.replace(scene, mechanism=mech)
    with pytest.raises(PeerUnavailable, match="gravity"):
        compare_with_opensees(heavy, n=2, repeats=1)


def test_agreement_is_the_larger_relative_gap_of_displacement_and_rotation():
    assert agreement((3.0, 4.0, 0.5), (3.0, 4.0, 0.5)) == 0.0
    assert agreement((3.0, 4.0, 0.5), (3.0, 4.05, 0.5)) == pytest.approx(1.0)  # 0.05 / 5
    assert agreement((3.0, 4.0, 0.5), (3.0, 4.0, 0.51)) == pytest.approx(2.0)  # 0.01 / 0.5


def test_a_case_opensees_cannot_follow_has_no_times_but_a_reason():
    row = PeerRow("f-", None, reason="OpenSees failed (See stderr output)")
    assert row.to_dict() == {
        "load_case": "f-",
        "substeps": None,
        "reason": "OpenSees failed (See stderr output)",
    }


def test_an_opensees_error_is_a_row_not_a_crash(monkeypatch):
    ops = _opensees_or_skip()
    import flexval.validation.studies.peers as peers

    def broken(*args):
        raise ops.OpenSeesError("See stderr output")

    monkeypatch.setattr(peers, "fewest_substeps", broken)
    rows = compare_with_opensees(load_scene("open_chain"), n=2, repeats=1)
    assert [r.reason for r in rows] == ["OpenSees failed (See stderr output)"] * len(rows)


def test_report_with_peers_says_when_opensees_is_missing(tmp_path, monkeypatch):
    """``flexval report --peers`` reaches the run times, and a missing peer is said there."""
    from test_report import TINY

    import flexval.validation.studies.peers as peers
    from flexval.validation.cli import main

    def missing():
        raise PeerUnavailable("OpenSeesPy is missing or does not load (test)")

    monkeypatch.setattr(peers, "opensees", missing)
    scene = tmp_path / "tiny.toml"
    scene.write_text(TINY)
    out = tmp_path / "out"
    assert (
        main(
            [
                "report",
                str(scene),
                "--out",
                str(out),
                "--model",
                "ee",
                "--repeats",
                "1",
                "--no-bench",
                "--no-converge",
                "--no-cache",
                "--quiet",
                "--jobs",
                "1",
                "--peers",
            ]
        )
        == 0
    )
    assert (
        "Not timed: OpenSeesPy is missing or does not load (test)."
        in (out / "timings.md").read_text()
    )
