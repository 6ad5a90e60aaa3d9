"""ARCHITECTURE.md is the map: every module of the three packages is named in it."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_module_is_named_in_the_architecture():
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    missing = [
        str(path.relative_to(ROOT))
        for package in ("geometry", "reducedmodels", "validation")
        for path in sorted((ROOT / package).rglob("*.py"))
        if path.name != "__init__.py" and "__pycache__" not in path.parts and path.name not in text
    ]
    assert not missing, f"modules ARCHITECTURE.md does not name: {missing}"
