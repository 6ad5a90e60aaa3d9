"""Check a built documentation site for what it must hold; exit 1 naming what is missing.

Run by ``make docs`` after ``mkdocs build --strict``::

    python docs/check_site.py site

The expected items come from the code, not from a list typed here: every
field the scene and sweep parsers declare must appear in the reference pages,
every ``flexval`` command in the CLI page, and the API pages must document the
connector contract and the path tracer.
"""

from __future__ import annotations

import html
import re
import sys
from pathlib import Path


def _text(site: Path, page: str) -> str:
    """The visible text of a built page (tags removed, entities decoded)."""
    path = site / page / "index.html"
    if not path.is_file():
        raise SystemExit(f"{path}: missing from the built site")
    return html.unescape(re.sub(r"<[^>]+>", " ", path.read_text(encoding="utf-8")))


def missing_items(site: Path) -> list[str]:
    """What the built ``site`` lacks, one line per item (empty: nothing)."""
    from flexval.geometry.scenefields import SCENE_TABLES
    from flexval.validation.cli.reference import commands
    from flexval.validation.sweep.fields import AXES, SWEEP

    checks = {
        "reference/scene": sorted({f.name for t in SCENE_TABLES for f in t.fields}),
        "reference/sweep": sorted({f.name for t in (SWEEP, AXES) for f in t.fields}),
        "reference/cli": [f"flexval {name}" for name in commands()],
        "reference/api/reducedmodels": ["Connector", "trace", "System", "parse_model", "register"],
        "reference/api/flexval": ["load_scene", "parse_model", "run_model"],
        "validation/paper/report": ["open_chain", "closed_chain"],
    }
    missing = []
    for page, items in checks.items():
        text = _text(site, page)
        for item in items:
            if not re.search(rf"(?<![\w-]){re.escape(item)}(?![\w-])", text):
                missing.append(f"{page}: {item}")
    return missing


def main(argv: list[str]) -> int:
    site = Path(argv[1] if len(argv) > 1 else "site")
    missing = missing_items(site)
    for line in missing:
        print(f"missing from the built site: {line}", file=sys.stderr)
    if not missing:
        print(f"{site}: the scene and sweep references, the CLI and the API pages are complete")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
