"""The result and mesh caches: exact keys, damaged entries, unusable folders, concurrency."""

import dataclasses
import json
import os
import subprocess
import sys
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest

from flexval.geometry import Segment, load_scene
from flexval.geometry.files import CacheWarning, cache_dir
from flexval.geometry.mesh import mesh_flexure
from flexval.reducedmodels import LoadPath
from flexval.validation.cache import ResultCache, exact, result_key
from flexval.validation.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def cache_root(tmp_path, monkeypatch):
    root = tmp_path / "cache"
    monkeypatch.setenv("FLEXVAL_CACHE", str(root))
    return root


def _path(**changes) -> LoadPath:
    base = dict(
        model="ee",
        load_case="f+",
        load=[0.0, 1.0],
        dx=[0.0, 0.1],
        dy=[0.0, -0.2],
        rotation=[0.0, 0.01],
        seconds=0.5,
        stats={"newton_iterations": 3},
    )
    return LoadPath(**{**base, **changes})


# ---------------------------------------------------------------- exact keys


def _moved(scene, delta: float):
    """``scene`` with the target point moved by ``delta`` mm in x."""
    mech = scene.mechanism
    moved = dataclasses.replace(mech, target_point=mech.target_point + np.array([delta, 0.0]))
    return dataclasses.replace(scene, mechanism=moved)


@pytest.mark.parametrize(
    "offset, delta", [(0.0, 1e-12), (1e8, 0.4), (1e8, 1.5e-8), (1e15, 0.125), (-3e7, 1e-8)]
)
def test_key_changes_with_any_change_of_a_number(offset, delta):
    """Every representable move of a point changes the key (8-digit repr did not at 1e8 mm)."""
    base = _moved(load_scene("open_chain"), offset)  # keys only: nothing is solved
    moved = _moved(base, delta)
    assert not np.array_equal(base.mechanism.target_point, moved.mechanism.target_point)
    assert result_key(base, "ee", "f+", None, {}) != result_key(moved, "ee", "f+", None, {})


@pytest.mark.parametrize(
    "field, value", [("levels", 12), ("model", "ee:x"), ("extra", {"record": True})]
)
def test_key_changes_with_every_input(field, value):
    sc = load_scene("open_chain")
    args = {"model": "ee", "levels": None, "extra": {}}
    k0 = result_key(sc, args["model"], "f+", args["levels"], args["extra"])
    args[field] = value
    assert result_key(sc, args["model"], "f+", args["levels"], args["extra"]) != k0


def test_key_changes_with_gravity_and_mass_data():
    """Static paths carry the weights, which the mechanism's own comparison leaves out."""
    from flexval.validation.studies.modes import with_density

    sc = with_density(load_scene("open_chain"), 1.24e-9)
    inertia = sc.mechanism.inertia
    heavy = dataclasses.replace(
        sc,
        mechanism=dataclasses.replace(
            sc.mechanism, inertia=dataclasses.replace(inertia, gravity=np.array([0.0, -9810.0]))
        ),
    )
    keys = {result_key(s, "ee", "f+", None, {}) for s in (load_scene("open_chain"), sc, heavy)}
    assert len(keys) == 3


def test_key_does_not_depend_on_how_the_scene_path_was_typed(tmp_path, monkeypatch):
    text = (ROOT / "geometry" / "scenes" / "open_chain.toml").read_text()
    (tmp_path / "sub").mkdir()
    scene_file = tmp_path / "sub" / "s.toml"
    scene_file.write_text(text)
    monkeypatch.chdir(tmp_path)
    spellings = [
        str(scene_file),
        "sub/s.toml",
        "./sub/../sub/s.toml",
        str(tmp_path / "sub" / "." / "s.toml"),
    ]
    keys = {result_key(load_scene(p), "ee", "f+", None, {}) for p in spellings}
    assert len(keys) == 1


def test_exact_refuses_types_without_an_exact_form():
    with pytest.raises(TypeError):
        exact(object())
    assert exact(0.1) == {"float": (0.1).hex()}


# ---------------------------------------------------------------- damaged result entries


def _damage(kind: str, path: Path, key: str) -> None:
    good = path.read_bytes()
    doc = json.loads(good)
    if kind == "truncated":
        path.write_bytes(good[: len(good) // 2])
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "binary":
        path.write_bytes(os.urandom(64) + b"\xff\xfe\x00")
    elif kind == "foreign":
        path.write_text(json.dumps({"model": "ee", "hello": "world"}))
    elif kind == "old format":
        path.write_text(json.dumps(doc["loadpath"]))
    elif kind == "tampered value":
        doc["loadpath"]["dx"][-1] += 1.0
        path.write_text(json.dumps(doc))
    elif kind == "other key":
        doc["key"] = "0" * len(key)
        path.write_text(json.dumps(doc))
    elif kind == "a folder":
        path.unlink()
        path.mkdir()
    elif kind == "deeply nested":
        path.write_text("[" * 100000 + "]" * 100000)


@pytest.mark.parametrize(
    "kind",
    [
        "truncated",
        "empty",
        "binary",
        "foreign",
        "old format",
        "tampered value",
        "other key",
        "a folder",
        "deeply nested",
    ],
)
def test_damaged_result_entry_is_discarded_with_a_warning(kind, cache_root):
    cache = ResultCache()
    key = "k" * 32
    cache.put(key, _path())
    entry = cache_root / "results" / f"{key}.json"
    assert cache.get(key) == _path()
    _damage(kind, entry, key)
    with pytest.warns(CacheWarning):
        assert cache.get(key) is None
    if kind != "a folder":
        assert not entry.exists()  # discarded: the next put stores a good one
        cache.put(key, _path())
        assert cache.get(key) == _path()


def test_cli_recomputes_after_a_damaged_entry(cache_root, capsys):
    argv = [
        "run",
        "open_chain",
        "--model",
        "dcmm:1",
        "--load-case",
        "f+",
        "--levels",
        "4",
        "--cache",
    ]
    assert main(argv) == 0
    first = capsys.readouterr().out
    (entry,) = (cache_root / "results").iterdir()
    entry.write_bytes(entry.read_bytes()[:10])
    assert main(argv) == 0
    out = capsys.readouterr()
    assert "damaged" in out.err and "Traceback" not in out.err
    assert first.splitlines()[1].split()[:7] == out.out.splitlines()[1].split()[:7]


def test_non_finite_and_failed_paths_are_not_cached(cache_root):
    cache = ResultCache()
    cache.put("a" * 32, _path(dx=[0.0, float("nan")]))
    cache.put("b" * 32, _path(converged=False))
    assert not (cache_root / "results").exists() or not any((cache_root / "results").iterdir())


def test_run_uses_the_cache_only_when_asked(cache_root):
    argv = ["run", "open_chain", "--model", "ee", "--load-case", "f+", "--levels", "3"]
    assert main(argv) == 0
    assert not (cache_root / "results").exists()
    assert main(argv + ["--cache"]) == 0
    assert len(list((cache_root / "results").iterdir())) == 1


# ---------------------------------------------------------------- unusable cache folder


@pytest.mark.parametrize("make", ["regular file", "under a regular file", "device"])
def test_unusable_cache_folder_warns_and_computes(make, tmp_path, monkeypatch, capsys):
    regular = tmp_path / "f"
    regular.write_text("x")
    root = {
        "regular file": regular,
        "under a regular file": regular / "sub",
        "device": Path("/dev/null"),
    }[make]
    monkeypatch.setenv("FLEXVAL_CACHE", str(root))
    with pytest.warns(CacheWarning, match="FLEXVAL_CACHE"):
        assert cache_dir() is None
    with pytest.warns(CacheWarning):
        assert not ResultCache().enabled
    with pytest.warns(CacheWarning):
        mesh = mesh_flexure(Segment((0.0, 0.0), (1.0, 0.0)), 0.5, 0)
    assert mesh.elements.shape[1] == 9
    assert main(["run", "open_chain", "--model", "ee", "--load-case", "f+", "--cache"]) == 0
    assert "computing without a cache" in capsys.readouterr().err
    assert regular.read_text() == "x"


# ---------------------------------------------------------------- damaged mesh entries


def _damage_npz(kind: str, path: Path) -> None:
    good = path.read_bytes()
    if kind == "truncated":
        path.write_bytes(good[: len(good) // 3])
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "binary":
        path.write_bytes(os.urandom(256))
    elif kind == "text":
        path.write_text('{"nodes": []}')
    elif kind == "foreign npz":
        with open(path, "wb") as fh:
            np.savez(fh, nodes=np.zeros((3, 2)))
    elif kind == "pickled object":
        with open(path, "wb") as fh:
            np.savez(fh, nodes=np.array([{"a": 1}], dtype=object))
    elif kind == "tampered nodes":
        with np.load(path) as z:
            arrays = {k: z[k] for k in z.files}
        arrays["nodes"] = arrays["nodes"] + 1e-9
        with open(path, "wb") as fh:
            np.savez(fh, **arrays)
    elif kind == "corrupt member":
        with zipfile.ZipFile(path, "w") as zf:
            zf.writestr("nodes.npy", b"\x93NUMPY garbage")


@pytest.mark.parametrize(
    "kind",
    [
        "truncated",
        "empty",
        "binary",
        "text",
        "foreign npz",
        "pickled object",
        "tampered nodes",
        "corrupt member",
    ],
)
def test_damaged_mesh_entry_is_discarded_and_rebuilt(kind, cache_root):
    seg = Segment((0.0, 0.0), (3.0, 4.0))
    fresh = mesh_flexure(seg, 0.5, 0, use_cache=False)
    mesh_flexure(seg, 0.5, 0)
    (entry,) = (cache_root / "meshes").iterdir()
    _damage_npz(kind, entry)
    with pytest.warns(CacheWarning, match="discarded"):
        again = mesh_flexure(seg, 0.5, 0)
    np.testing.assert_array_equal(again.nodes, fresh.nodes)
    np.testing.assert_array_equal(again.elements, fresh.elements)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the rebuilt entry is sound
        mesh_flexure(seg, 0.5, 0)


# ---------------------------------------------------------------- concurrency

_MESH_WORKER = """
import sys
import numpy as np
from flexval.geometry import Segment
from flexval.geometry.mesh import mesh_flexure
for level in (0, 1, 2):
    m = mesh_flexure(Segment((0.0, 0.0), (3.0, 4.0)), 0.25, level)
    print(level, float(np.abs(m.nodes).sum()).hex(), int(m.elements.sum()))
"""


def _spawn(argv: list[str], cache: Path) -> subprocess.Popen:
    env = {
        **os.environ,
        "FLEXVAL_CACHE": str(cache),
        "PYTHONPATH": str(ROOT),
        "OPENBLAS_NUM_THREADS": "1",
    }
    return subprocess.Popen(
        [sys.executable, *argv],
        env=env,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_two_reports_share_an_empty_cache(tmp_path):
    """Two identical ``flexval report`` runs started together on one empty cache both succeed
    with identical results (with fixed temporary names one of them would fail 5 times in 6)."""
    cache = tmp_path / "cache"
    outs = [tmp_path / f"out{k}" for k in range(2)]
    argv = [
        "-m",
        "flexval.validation.cli",
        "report",
        "open_chain",
        "--model",
        "ee",
        "--model",
        "dcmm:1",
        "--model",
        "prbm",
        "--repeats",
        "1",
        "--no-bench",
        "--no-converge",
        "--quiet",
    ]
    procs = [_spawn(argv + ["--out", str(o)], cache) for o in outs]
    for p in procs:
        _, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
        assert "Traceback" not in err and "warning" not in err
    results = []
    for o in outs:
        data = json.loads((o / "results.json").read_text())
        results.append(
            {
                (r["model"], r["load_case"]): (r["dx"], r["dy"], r["rotation"])
                for r in data["scenes"]["open_chain"]["results"]
            }
        )
    assert results[0] == results[1] and len(results[0]) == 3 * 4
    assert not [p for p in cache.rglob("*") if ".tmp" in p.name]


def test_two_processes_share_an_empty_mesh_cache(tmp_path):
    cache = tmp_path / "cache"
    procs = [_spawn(["-c", _MESH_WORKER], cache) for _ in range(2)]
    outputs = []
    for p in procs:
        out, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
        assert "warning" not in err.lower()
        outputs.append(out)
    assert outputs[0] == outputs[1] and len(outputs[0].splitlines()) == 3
    assert len(list((cache / "meshes").glob("*.npz"))) == 3
    assert not [p for p in cache.rglob("*") if ".tmp" in p.name]


def test_a_cached_record_is_read_computed_once_and_failures_are_not_kept(tmp_path):
    """``ResultCache.record``: the first call computes and stores the record ``write`` gives;
    the next reads it back without computing; a record ``read`` refuses is recomputed; a
    result ``write`` declines (a failure) and a call without a key are never stored."""
    cache = ResultCache(root=tmp_path)
    calls = []

    def compute(value):
        def run():
            calls.append(value)
            return value

        return run

    def read(hit):
        return hit["value"] if set(hit) == {"value"} else None

    def write(found):
        return None if found < 0 else {"value": found}

    assert cache.record("a", compute(3.5), read, write) == 3.5
    assert cache.record("a", compute(9.0), read, write) == 3.5 and calls == [3.5]
    cache.put_record("a", {"other": 1.0})  # a record of another form: recomputed
    assert cache.record("a", compute(4.0), read, write) == 4.0 and calls == [3.5, 4.0]
    assert cache.record("b", compute(-1.0), read, write) == -1.0  # a failure: not kept
    assert cache.get_record("b") is None
    assert cache.record(None, compute(2.0), read, write) == 2.0
    assert calls == [3.5, 4.0, -1.0, 2.0]
