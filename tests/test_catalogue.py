"""The model catalogue: id syntax, options, canonical ids, and a family added from outside.

The toy family ``spring`` (a linear spring between the two bodies of every
flexure, defined in this module) is registered here and nowhere else: it runs
through parse -> build -> run, the CLI and the cache key with no other edit,
which is what "adding a family is one module plus one registration" means.
Its exact answer (a pure moment M turns the tip by M / k) checks that the
resolution and the options reach the connector.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from builders import cantilever, tip_moment

from flexval.geometry import Arc, SceneError, load_scene
from flexval.reducedmodels import Connector, run_reduced
from flexval.reducedmodels.catalogue import (
    Family,
    Option,
    Resolution,
    families,
    family,
    parse_model,
    register,
    unregister,
)
from flexval.reducedmodels.models import connector_system, trace_nonlinear
from flexval.validation.cache import result_key
from flexval.validation.cli import main
from flexval.validation.run import run_model


class SpringConnector(Connector):
    """Linear springs between two bodies' poses: translation k_t and rotation k (N mm/rad)."""

    def __init__(self, flexure, mechanism, rotational: float, translational: float):
        self.name, self.bodies = flexure.name, tuple(flexure.bodies)
        ref = mechanism.bodies
        self.rest = ref[self.bodies[1]].reference - ref[self.bodies[0]].reference
        k = np.array([translational, translational, rotational])
        self.H = np.block([[np.diag(k), -np.diag(k)], [-np.diag(k), np.diag(k)]])

    def evaluate(self, pose_a, pose_b, internal):
        d = np.concatenate([pose_a, pose_b]) - np.concatenate([np.zeros(3), [*self.rest, 0.0]])
        g = self.H @ d
        return 0.5 * d @ g, g, self.H

    def shape(self, pose_a, pose_b, internal) -> np.ndarray:
        return np.array([pose_a[:2], pose_b[:2]])


def _spring(flexure, mechanism, spec, stiffer: float = 1.0):
    k = stiffer * spec.resolution
    return SpringConnector(flexure, mechanism, k, 1e3 * k)


def _spring_system(mechanism, spec, settings=None, **options):
    return connector_system(mechanism, spec, _spring, settings, options)


SPRING = Family(
    "spring",
    "toy: linear springs between the bodies of each flexure",
    trace_nonlinear,
    Resolution("K", "rotational stiffness, N mm/rad", 50, 1, 10**6, True, (10, 40)),
    (Option("stiffer", "multiplies the stiffness", (("1", 1.0), ("2", 2.0), ("4", 4.0)), "1"),),
    frozenset(),
    _spring_system,
)


@pytest.fixture
def spring():
    register(SPRING)
    yield SPRING
    unregister("spring")


def _mech():
    return cantilever(Arc((0.0, 0.0), 3.0, 0.4, 2.0))


def test_toy_family_parses_builds_and_runs(spring):
    spec = parse_model("spring:200[stiffer=4]")
    assert spec.id == "spring:200[stiffer=4]" and spec.kwargs == {"stiffer": 4.0}
    lp = run_reduced(_mech(), spec, tip_moment(8.0))
    assert lp.model == "spring:200[stiffer=4]"
    assert lp.rotation[-1] == pytest.approx(8.0 / 800.0, rel=1e-10)
    default = run_reduced(_mech(), parse_model("spring"), tip_moment(8.0))
    assert default.model == "spring:50"
    assert default.rotation[-1] == pytest.approx(8.0 / 50.0, rel=1e-10)


def test_toy_family_from_the_command_line(spring, tmp_path):
    out = tmp_path / "r.json"
    assert (
        main(
            [
                "run",
                "open_chain",
                "--model",
                "spring:100[stiffer=2]",
                "--model",
                "spring",
                "--load-case",
                "m+",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    data = json.loads(out.read_text())
    assert [r["model"] for r in data["results"]] == ["spring:100[stiffer=2]", "spring:50"]
    rot = [r["rotation"][-1] for r in data["results"]]
    assert rot[0] * 200 == pytest.approx(rot[1] * 50, rel=1e-8)  # chain of springs: 1/k
    assert main(["run", "open_chain", "--model", "spring:100[softer]"]) == 2
    assert main(["converge", "open_chain", "--model", "spring", "--load-case", "m+"]) == 0


def test_unregistered_family_is_unknown():
    with pytest.raises(SceneError, match="expected"):
        parse_model("spring:5")


@pytest.mark.parametrize(
    "text, canonical",
    [
        ("beam", "beam:20"),
        ("beam:100", "beam:100"),
        ("beam:100[shear]", "beam:100[shear]"),
        ("beam:100[shear=true]", "beam:100[shear]"),
        ("beam:100[shear=false]", "beam:100"),
        ("beam:100[]", "beam:100"),
        ("dcmm:2[frame=follower]", "dcmm:2[frame=follower]"),
        ("dcmm:2[frame=leader]", "dcmm:2"),
        ("dcmm[ frame = follower ]", "dcmm:1[frame=follower]"),
        ("continuum", "continuum:1"),
        ("continuum:0[plane=strain]", "continuum:0[plane=strain]"),
        ("continuum:1[plane=strain,law=neo-hookean]", "continuum:1[law=neo-hookean,plane=strain]"),
        ("continuum:1[law=svk,plane=stress]", "continuum:1"),
        ("prbm", "prbm"),
        (" ee ", "ee"),
    ],
)
def test_canonical_ids(text, canonical):
    spec = parse_model(text)
    assert spec.id == canonical
    assert parse_model(spec.id) == spec  # the canonical id reads back as itself


@pytest.mark.parametrize(
    "text, words",
    [
        ("beam:100[sheer]", ["unknown option 'sheer'", "shear"]),
        ("dcmm:2[frame=side]", ["'frame'", "leader, follower", "'side'"]),
        ("dcmm:2[frame]", ["'frame'", "needs a value"]),
        ("continuum:1[law=rubber]", ["'law'", "svk, neo-hookean"]),
        ("continuum:1[plane=3d]", ["'plane'", "stress, strain"]),
        ("prbm[shear]", ["unknown option 'shear'", "allowed: plate"]),
        ("dcmm:2[frame=follower,frame=leader]", ["given twice"]),
        ("beam:0", ["between 1 and"]),
        ("continuum:9", ["between 0 and 8"]),
        ("ee:2", ["takes no resolution"]),
        ("beam:x", ["must be an integer"]),
        ("fem", ["expected", "beam[:N]", "continuum[:LEVEL]"]),
        ("beam:10[shear", ["expected"]),
    ],
)
def test_bad_ids_name_the_option_and_the_allowed_values(text, words):
    with pytest.raises(SceneError) as err:
        parse_model(text, "<test>", "--model")
    msg = str(err.value)
    assert "--model" in msg and repr(text) in msg
    for w in words:
        assert w in msg


@pytest.mark.parametrize(
    "model, option",
    [("beam:4[shear]", {"shear": True}), ("dcmm:2[frame=follower]", {"frame": "follower"})],
)
def test_options_reach_the_connector(model, option):
    """The id's option gives the same path as the Python keyword, and a different one than
    without it (thick arcs of the closed chain: shear turns the link 0.4 % less, the follower
    frame 2 % less); the id (with the option) is in the result."""
    scene = load_scene("closed_chain")
    case = scene.load_case("f+")
    spec = parse_model(model)
    base = parse_model(model.split("[")[0])
    with_id = run_model(scene, spec, case)
    with_kw = run_reduced(scene.mechanism, base, case, **option)
    plain = run_model(scene, base, case)
    assert with_id.model == model and plain.model == base.id
    assert with_id.dx == with_kw.dx and with_id.rotation == with_kw.rotation
    assert abs(with_id.rotation[-1] - plain.rotation[-1]) > 1e-3 * abs(plain.rotation[-1])
    assert with_id.settings == option


def test_continuum_options_reach_the_law():
    """Plane strain is stiffer than plane stress (E / (1 - nu^2) in bending): the tip of a
    slender arc under a moment turns less by about 1 - nu^2 (the thin-beam limit)."""
    mech = cantilever(Arc((0.0, 0.0), 10.0, 0.4, 1.0), h=0.2, nu=0.3)
    case = tip_moment(1e-3)
    from flexval.geometry import Scene

    scene = Scene("arc", "", mech, (case,), (), frozenset(), "<test>")
    stress = run_model(scene, parse_model("continuum:0"), case)
    strain = run_model(scene, parse_model("continuum:0[plane=strain]"), case)
    assert strain.model == "continuum:0[plane=strain]"
    assert strain.rotation[-1] / stress.rotation[-1] == pytest.approx(1 - 0.3**2, rel=0.01)
    neo = run_model(scene, parse_model("continuum:0[law=neo-hookean]"), case)
    assert neo.model == "continuum:0[law=neo-hookean]"
    # small strain: both laws share the linear limit (strain ~ 1e-5 here)
    assert neo.rotation[-1] == pytest.approx(stress.rotation[-1], rel=1e-3)


def test_options_change_the_cache_key():
    scene = load_scene("open_chain")
    keys = {
        result_key(scene, parse_model(m).id, "f+", None, {})
        for m in ("dcmm:2", "dcmm:2[frame=follower]", "dcmm:2[frame=leader]")
    }
    assert len(keys) == 2


def test_request_models_are_checked_when_used(tmp_path):
    """geometry keeps request.models as text; a bad id fails when a command reads it,
    naming the file, the field and the value (exit 2)."""
    from importlib import resources

    text = resources.files("flexval.geometry").joinpath("scenes", "open_chain.toml").read_text()
    head, _, _ = text.partition("[request]")
    scene = tmp_path / "s.toml"
    scene.write_text(head + '[request]\nmodels = ["dcmm:2[frame=up]"]\n')
    assert load_scene(scene).models == ("dcmm:2[frame=up]",)
    proc = subprocess.run(
        [sys.executable, "-m", "flexval.validation.cli", "run", str(scene)],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert str(scene) in proc.stderr and "request.models" in proc.stderr
    assert "'dcmm:2[frame=up]'" in proc.stderr and "Traceback" not in proc.stderr


def test_info_imports_no_model_code():
    code = (
        "import sys; from flexval.validation.cli import main; main(['info', 'closed_chain']); "
        "print(sorted(m for m in sys.modules if m.startswith(("
        "'flexval.reducedmodels.beam.elements', "
        "'flexval.reducedmodels.dcmm.connector', 'flexval.reducedmodels.prbm.connector', "
        "'flexval.validation.continuum.run', "
        "'flexval.validation.continuum.connector', 'skfem'))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_every_family_documents_itself():
    for fam in families():
        assert fam.summary and family(fam.name) is fam
        if fam.resolution:
            res = fam.resolution
            assert res.low <= res.default <= res.high
            assert parse_model(fam.name).resolution == res.default
        for opt in fam.options:
            assert opt.doc and opt.default in opt.allowed


def test_every_family_with_a_system_builds_it_with_its_options():
    """build_system reaches each family's System, the spec's options included (modes, the
    gate-spread benchmark and arc length build Systems this way)."""
    from flexval.reducedmodels import build_system

    mech = _mech()
    system = build_system(mech, parse_model("continuum:0[plane=strain,law=neo-hookean]"))
    conn = system.connectors[0]
    assert (conn.plane, conn.law) == ("strain", "neo-hookean")
    follower = build_system(mech, parse_model("dcmm:2[frame=follower]")).connectors[0]
    leader = build_system(mech, parse_model("dcmm:2")).connectors[0]
    assert follower.bodies == leader.bodies[::-1]


def test_continuum_variants_write_their_own_fields(tmp_path):
    """Two options of one mesh level are two models: each keeps its VTU file."""
    from importlib import resources

    text = resources.files("flexval.geometry").joinpath("scenes", "closed_chain.toml").read_text()
    scene = tmp_path / "s.toml"
    scene.write_text(
        text.replace('models = ["beam:100"', 'outputs = ["vtu"]\nmodels = ["beam:100"')
    )
    out = tmp_path / "fields"
    assert (
        main(
            [
                "run",
                str(scene),
                "--model",
                "continuum:0",
                "--model",
                "continuum:0[plane=strain]",
                "--load-case",
                "f+",
                "--levels",
                "2",
                "--out-dir",
                str(out),
            ]
        )
        == 0
    )
    assert len(list(out.glob("*.vtu"))) == 2
