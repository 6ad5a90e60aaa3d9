"""Result files of studies too long for ``flexval report``, read back by its sections.

A study in ``benchmarks/`` (the dynamic protocol, the 3D reference) writes a
JSON document tagged with a format name and the code version that computed
it; the report renders a section from it. Reading never fails the report: a
missing, unreadable, foreign or incomplete file becomes the reason it cannot
be used, and a file from other code is rendered with a note saying it is
stale and how to refresh it.
"""

from __future__ import annotations

import json
from pathlib import Path


def read_study(path: Path, fmt: str, required: tuple[str, ...]) -> tuple[dict | None, str | None]:
    """The document at ``path`` if it is a ``fmt`` file with every ``required`` field, else
    None and the reason (a sentence fragment naming the file)."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None, f"`{path.as_posix()}` does not exist"
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        return None, f"`{path.as_posix()}` is unreadable ({type(exc).__name__})"
    if not isinstance(doc, dict) or doc.get("format") != fmt:
        return None, f"`{path.as_posix()}` is not a {fmt} file"
    missing = [k for k in required if k not in doc]
    if missing:
        return None, f"`{path.as_posix()}` lacks {', '.join(missing)}"
    return doc, None


def stale_lines(doc: dict, code: str, refresh: str) -> list[str]:
    """A note when ``doc`` was computed by another code version than ``code`` (none otherwise);
    ``refresh`` is the command that recomputes it."""
    if doc["code_version"] == code:
        return []
    return [
        f"**Stale:** these results were computed by flexval code {doc['code_version']}, "
        f"this report by {code}; rerun `{refresh}` to refresh them.",
        "",
    ]
