"""On-disk cache of LoadPaths, keyed by everything that determines them.

The key hashes the scene's mechanism and load case (their full dataclass
representation), the model id and options, the number of levels, what is
recorded, and the code version: a hash of the source of the ``geometry``,
``reducedmodels`` and ``validation`` packages, so any code change
invalidates the cache. Location: ``$FLEXVAL_CACHE`` or ``~/.cache/flexval``.
"""

from __future__ import annotations

import hashlib
import json
import os
from functools import lru_cache
from importlib import resources
from pathlib import Path

from reducedmodels import LoadPath


def cache_dir() -> Path:
    """Root of flexval's caches."""
    return Path(os.environ.get("FLEXVAL_CACHE", Path.home() / ".cache" / "flexval"))


@lru_cache(maxsize=1)
def code_version() -> str:
    """Hash of the package sources (changes whenever the code does)."""
    h = hashlib.sha256()
    for pkg in ("geometry", "reducedmodels", "validation"):
        root = Path(str(resources.files(pkg)))
        for path in sorted(root.rglob("*")):
            if path.suffix in (".py", ".json", ".toml") and "__pycache__" not in path.parts:
                h.update(path.relative_to(root).as_posix().encode())
                h.update(path.read_bytes())
    return h.hexdigest()[:16]


def result_key(scene, model: str, case_name: str, levels: int | None, extra: dict) -> str:
    """Hash of what determines one LoadPath."""
    payload = json.dumps({
        "mechanism": repr(scene.mechanism),
        "case": repr(scene.load_case(case_name)),
        "model": model,
        "levels": levels,
        "extra": extra,
        "code": code_version(),
    }, sort_keys=True, default=str)
    return hashlib.sha256(payload.encode()).hexdigest()[:24]


class ResultCache:
    """LoadPath store under ``cache_dir()/results`` (disabled: always misses)."""

    def __init__(self, enabled: bool = True, root: Path | None = None):
        self.enabled = enabled
        self.root = (root or cache_dir()) / "results"

    def get(self, key: str) -> LoadPath | None:
        """The cached LoadPath for ``key`` or None."""
        path = self.root / f"{key}.json"
        if not self.enabled or not path.is_file():
            return None
        return LoadPath.from_json(path.read_text(encoding="utf-8"))

    def put(self, key: str, lp: LoadPath) -> None:
        """Store a converged LoadPath (failures are never cached)."""
        if not self.enabled or not lp.converged:
            return
        self.root.mkdir(parents=True, exist_ok=True)
        tmp = self.root / f"{key}.tmp"
        tmp.write_text(lp.to_json(), encoding="utf-8")
        tmp.replace(self.root / f"{key}.json")
