"""On-disk cache of LoadPaths, keyed by the exact values that determine them.

The key hashes the scene's name, its mechanism, mass data and gravity (a static
path carries the weights) and load case, the model id
and options, the number of levels, what is recorded, and the code version (a
hash of the source of the ``geometry``, ``reducedmodels`` and ``validation``
packages, so any code change invalidates the cache). Numbers enter the key
exactly: floats as ``float.hex``, arrays by their dtype, shape and bytes
(:func:`exact`), never as printed text, so moving a point by any amount
changes the key. Fields that do not define the mechanism (its ``source``,
i.e. how the scene path was typed) are left out.

The same folder keeps JSON records of results that are not load paths (a
model's first critical load, its natural frequencies: see
:mod:`flexval.validation.studies.gatemetrics`), keyed the same way by
:func:`record_key`, which also holds the scene's mass data and gravity.

Location: ``$FLEXVAL_CACHE/results`` or ``~/.cache/flexval/results``
(:func:`flexval.geometry.files.cache_dir`; an unusable folder means no caching,
with a warning). Each entry is one JSON document holding the LoadPath, its
key and a SHA-256 checksum of its canonical text, written atomically under a
unique temporary name, so concurrent runs sharing one cache never see each
other's partial files. An entry that is truncated, empty, binary, of another
format or whose checksum does not match is discarded with a
:class:`flexval.geometry.files.CacheWarning` and recomputed.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import warnings
from collections.abc import Callable
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import TypeVar

import numpy as np

from flexval.geometry.files import CacheWarning, cache_dir, write_bytes
from flexval.reducedmodels import LoadPath

ENTRY_FORMAT = "flexval-loadpath/2"
"""Format tag of a cache entry (a different tag is a foreign entry)."""
RECORD_FORMAT = "flexval-record/1"
"""Format tag of a cache entry holding a JSON record (:meth:`ResultCache.get_record`)."""

T = TypeVar("T")


@lru_cache(maxsize=1)
def code_version() -> str:
    """Hash of the package sources (changes whenever the code does)."""
    h = hashlib.sha256()
    for pkg in ("flexval.geometry", "flexval.reducedmodels", "flexval.validation"):
        root = Path(str(resources.files(pkg)))
        for path in sorted(root.rglob("*")):
            if path.suffix in (".py", ".json", ".toml") and "__pycache__" not in path.parts:
                h.update(path.relative_to(root).as_posix().encode())
                h.update(path.read_bytes())
    return h.hexdigest()[:16]


def exact(value) -> object:
    """A JSON-ready form of ``value`` that keeps every bit of every number.

    Floats become ``float.hex`` strings, arrays their dtype, shape and a
    SHA-256 of their bytes, dataclasses the exact form of each compared
    field (fields declared ``compare=False``, such as a mechanism's source
    file, are left out); containers are converted element by element.

    Raises
    ------
    TypeError
        For a type without an exact form (never fall back to ``repr``).
    """
    if value is None or isinstance(value, (bool, str, np.bool_)):
        return bool(value) if isinstance(value, np.bool_) else value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return {"float": float(value).hex()}
    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value)
        return {
            "array": str(data.dtype),
            "shape": list(data.shape),
            "sha256": hashlib.sha256(data.tobytes()).hexdigest(),
        }
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            "type": type(value).__qualname__,
            "fields": {
                f.name: exact(getattr(value, f.name))
                for f in dataclasses.fields(value)
                if f.compare
            },
        }
    if isinstance(value, dict):
        return {
            "dict": sorted(
                ([exact(k), exact(v)] for k, v in value.items()),
                key=lambda kv: json.dumps(kv[0], sort_keys=True),
            )
        }
    if isinstance(value, (list, tuple)):
        return [exact(v) for v in value]
    if isinstance(value, (set, frozenset)):
        return {
            "set": sorted((exact(v) for v in value), key=lambda v: json.dumps(v, sort_keys=True))
        }
    raise TypeError(f"no exact cache-key form for {type(value).__name__}")


def result_key(scene, model: str, case_name: str, levels: int | None, extra: dict) -> str:
    """Hash of what determines one LoadPath (exact values, see :func:`exact`)."""
    payload = json.dumps(
        {
            "scene": scene.name,
            "mechanism": exact(scene.mechanism),
            "inertia": exact(scene.mechanism.inertia),
            "case": exact(scene.load_case(case_name)),
            "model": model,
            "levels": levels,
            "extra": exact(extra),
            "code": code_version(),
            "format": ENTRY_FORMAT,
        },
        sort_keys=True,
    )
    return hashlib.sha256(payload.encode()).hexdigest()[:32]


def record_key(scene, model: str, what: str, extra: dict) -> str:
    """Hash of what determines one JSON record of ``what`` (e.g. a model's natural
    frequencies) computed for ``model`` on ``scene``: as :func:`result_key`, with the
    scene's mass data and gravity (``mechanism.inertia``, which the mechanism's own
    comparison leaves out) and without a load case (give it in ``extra`` if one applies)."""
    payload = json.dumps(
        {
            "scene": scene.name,
            "mechanism": exact(scene.mechanism),
            "inertia": exact(scene.mechanism.inertia),
            "model": model,
            "what": what,
            "extra": exact(extra),
            "code": code_version(),
            "format": RECORD_FORMAT,
        },
        sort_keys=True,
    )
    return hashlib.sha256(payload.encode()).hexdigest()[:32]


def _checksum(body: dict) -> str:
    return hashlib.sha256(json.dumps(body, sort_keys=True, allow_nan=False).encode()).hexdigest()


class ResultCache:
    """LoadPath store under ``cache_dir()/results`` (disabled or unusable: always misses),
    which also keeps JSON records of other results (:meth:`get_record`, :meth:`put_record`).

    Parameters
    ----------
    enabled : bool
        False: ``get`` always misses and ``put`` stores nothing.
    root : Path, optional
        Cache root instead of :func:`flexval.geometry.files.cache_dir`.
    """

    def __init__(self, enabled: bool = True, root: Path | None = None):
        base = (root if root is not None else cache_dir()) if enabled else None
        self.enabled = base is not None
        self.root = Path(base) / "results" if base is not None else None

    def _entry(self, key: str) -> Path:
        return self.root / f"{key}.json"

    def get(self, key: str) -> LoadPath | None:
        """The cached LoadPath for ``key``, or None (a bad entry is discarded with a warning)."""
        return self._read(key, ENTRY_FORMAT, "loadpath", LoadPath.from_dict)

    def put(self, key: str, lp: LoadPath) -> None:
        """Store a converged LoadPath (failures, and paths with non-finite values, are not)."""
        if lp.converged:
            self._write(key, ENTRY_FORMAT, "loadpath", lp.to_dict())

    def path(self, key: str | None, compute: Callable[[], LoadPath]) -> LoadPath:
        """The path cached under ``key`` (``stats["cached"]`` set), else ``compute()``'s,
        stored under ``key``: the one cached run of every command and study.

        ``key`` None (a run whose outputs are not a path alone, or no cache wanted):
        computed, not stored. What ``compute`` raises (a solver failure) passes through
        and nothing is stored.
        """
        if key is not None:
            hit = self.get(key)
            if hit is not None:
                hit.stats.setdefault("cached", True)
                return hit
        lp = compute()
        if key is not None:
            self.put(key, lp)
        return lp

    def record(
        self,
        key: str | None,
        compute: Callable[[], T],
        read: Callable[[dict], T | None],
        write: Callable[[T], dict | None],
    ) -> T:
        """The result whose JSON record is cached under ``key``, else ``compute()``'s, its record
        stored: the one cached result of the studies that are not a path (critical loads,
        frequencies, batch timings).

        ``read(record)`` makes the result of a stored record (None: a record of another
        form, recomputed); ``write(result)`` gives the record to store (None: not stored,
        a failure). ``key`` None: computed, not stored.
        """
        if key is not None:
            hit = self.get_record(key)
            found = None if hit is None else read(hit)
            if found is not None:
                return found
        result = compute()
        if key is not None:
            kept = write(result)
            if kept is not None:
                self.put_record(key, kept)
        return result

    def get_record(self, key: str) -> dict | None:
        """The JSON record stored under ``key`` (:func:`record_key`), or None (a bad entry
        is discarded with a warning)."""
        return self._read(key, RECORD_FORMAT, "record", dict)

    def put_record(self, key: str, record: dict) -> None:
        """Store a JSON record (one with a non-finite number is not stored)."""
        self._write(key, RECORD_FORMAT, "record", record)

    def _read(self, key: str, fmt: str, field: str, convert: Callable):
        """``convert`` of the checked body of the entry ``key`` of format ``fmt``, or None (a
        damaged or foreign entry is removed with a warning; one that cannot be read is left)."""
        if not self.enabled:
            return None
        path = self._entry(key)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            warnings.warn(
                f"cache entry {path} cannot be read ({exc.strerror or exc}); recomputing",
                CacheWarning,
                stacklevel=3,
            )
            return None
        body = _decode_body(key, data, fmt, field, convert)
        if body is None:
            warnings.warn(
                f"cache entry {path} is damaged or foreign; discarded and recomputed",
                CacheWarning,
                stacklevel=3,
            )
            path.unlink(missing_ok=True)
        return body

    def _write(self, key: str, fmt: str, field: str, body: dict) -> None:
        """Store ``body`` under ``key`` with its checksum (atomically; a body with a
        non-finite number is not stored: strict JSON could not hold it losslessly)."""
        if not self.enabled:
            return
        try:
            checksum = _checksum(body)
        except ValueError:
            return
        doc = {"format": fmt, "key": key, "sha256": checksum, field: body}
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            write_bytes(self._entry(key), json.dumps(doc, allow_nan=False).encode("utf-8"))
        except OSError as exc:
            warnings.warn(f"result not cached: {exc}", CacheWarning, stacklevel=3)


def _decode_body(key: str, data: bytes, fmt: str, field: str, convert: Callable):
    """``convert`` of the body (``doc[field]``) of a cache entry, or None if it is not a
    sound entry of format ``fmt`` for ``key`` (its checksum included) or does not convert."""
    try:
        doc = json.loads(data.decode("utf-8"))
        if (
            not isinstance(doc, dict)
            or doc.get("format") != fmt
            or doc.get("key") != key
            or not isinstance(doc.get(field), dict)
            or _checksum(doc[field]) != doc.get("sha256")
        ):
            return None
        return convert(doc[field])
    except (UnicodeDecodeError, ValueError, KeyError, TypeError, RecursionError):
        return None
