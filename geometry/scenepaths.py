"""Paths to a scene's numeric fields: ``section.thickness``, ``flexures.e34.width_deg``.

The one syntax by which a sweep's axes (:mod:`flexval.validation.sweep.spec`) and
:meth:`flexval.geometry.scene.Scene.with_changes` name the number they change: dotted
steps through the scene file's tables, an array of named tables (flexures, load cases,
bodies, pins) stepped into by name, any other array by index. A field the base scene
leaves out may be set where its table declares it (a flexure's own thickness, the
material's density).
"""

from __future__ import annotations

from typing import Any

from .errors import SceneError, did_you_mean
from .scenefields import BODIES, FLEXURES, LOAD_CASES, MATERIAL, PINS, SECTION

NAMED_ARRAYS = ("flexures", "load_cases", "bodies", "pins")
SETTABLE_TABLES = {
    "section": SECTION,
    "material": MATERIAL,
    "flexures": FLEXURES,
    "load_cases": LOAD_CASES,
    "bodies": BODIES,
    "pins": PINS,
}
"""The scene tables whose declared fields an axis may set where the base scene leaves
them out (a flexure's own thickness, the material's density)."""


def _fail(source: str, field: str, value: Any, reason: str) -> None:
    raise SceneError(source, field, value, reason)


def field_slot(data: dict, path: str, source: str, field: str) -> tuple[Any, Any]:
    """The container and key that ``path`` addresses in the scene data ``data``.

    Raises SceneError (naming ``field``, of ``source``) when a step of the path
    does not exist or the addressed value is not a number.
    """
    parts = path.split(".")
    node: Any = data
    walked = []
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        where = ".".join(walked) or "<scene>"
        if isinstance(node, dict):
            if last:
                if part in node and (
                    isinstance(node[part], bool) or not isinstance(node[part], (int, float))
                ):
                    _fail(source, field, path, f"'{part}' of {where} is not a number")
                declared = SETTABLE_TABLES.get(walked[0]) if walked else None
                if part not in node and (declared is None or part not in declared):
                    known = set(node) | (set() if declared is None else declared.keys())
                    _fail(
                        source,
                        field,
                        path,
                        f"unknown field '{part}' of {where}{did_you_mean(part, known)}",
                    )
                return node, part
            if part not in node:
                hint = did_you_mean(part, node)
                _fail(source, field, path, f"{where} has no field '{part}'{hint}")
            node = node[part]
        elif isinstance(node, list):
            if walked and walked[-1] in NAMED_ARRAYS and all(isinstance(x, dict) for x in node):
                match = [x for x in node if str(x.get("name")) == part]
                if not match:
                    names = [str(x.get("name")) for x in node]
                    _fail(
                        source,
                        field,
                        path,
                        f"{where} has no entry named '{part}'{did_you_mean(part, names)}; "
                        f"names are {names}",
                    )
                if last:
                    _fail(source, field, path, f"{where}.{part} is a table, not a number")
                node = match[0]
            else:
                if not part.isdigit() or int(part) >= len(node):
                    _fail(
                        source,
                        field,
                        path,
                        f"{where} is an array of {len(node)}: expected an index",
                    )
                if last:
                    if isinstance(node[int(part)], bool) or not isinstance(
                        node[int(part)], (int, float)
                    ):
                        _fail(source, field, path, f"{where}[{part}] is not a number")
                    return node, int(part)
                node = node[int(part)]
        else:
            _fail(source, field, path, f"{where} is a value, not a table")
        walked.append(part)
    raise AssertionError("unreachable: the loop returns at the last part")
