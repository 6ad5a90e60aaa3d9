"""What makes a sweep's stored rows its own: the identity kept beside its results.

A sweep's output folder holds the rows of one sweep, appended run after run (a
resumed run, or one whose axes gained values, adds to them). Rows of another
sweep (another base scene, models, reference, load cases, swept fields or
outputs) in the same folder would be mixed into its summary. The first run
writes ``sweep.json`` with :func:`identity`; a later run with another
identity over the same folder is refused (exit 2), naming what differs.
"""

from __future__ import annotations

import json
from pathlib import Path

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import write_json

IDENTITY_FILE = "sweep.json"
"""The file in a sweep's output folder that holds its identity."""


def identity(sweep) -> dict:
    """The fields of a sweep that its rows depend on, beyond each point's values."""
    return {
        "base": sweep.base,
        "models": [spec.id for spec in sweep.models],
        "reference": sweep.reference.id,
        "load_cases": list(sweep.load_cases),
        "axes": [axis.path for axis in sweep.axes],
        "outputs": list(sweep.outputs),
        "metric": sweep.metric,
    }


def check_identity(sweep, out: Path) -> None:
    """Refuse an output folder that holds another sweep's rows (its ``sweep.json``).

    Raises
    ------
    SceneError
        Naming ``--out``, the folder and the fields that differ.
    """
    path = Path(out) / IDENTITY_FILE
    if not path.is_file():
        return
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        stored = {}
    mine = identity(sweep)
    differ = sorted(k for k in mine if stored.get(k) != mine[k])
    if differ:
        raise SceneError(
            COMMAND_LINE,
            "--out",
            str(out),
            f"holds the rows of another sweep (its {', '.join(differ)} differ from this "
            "one's): give another --out, or remove the folder to start afresh",
        )


def keep_identity(sweep, out: Path) -> None:
    """Write the sweep's identity into its output folder (once its first rows are there)."""
    path = Path(out) / IDENTITY_FILE
    if not path.is_file():
        write_json(path, identity(sweep))
