"""Where a report is written: a folder named after its scenes, never another scene's report.

``flexval report`` without ``--out`` writes into a folder of the current
directory named after the scenes it reports on (:func:`default_report_folder`),
so that a user's own mechanism never lands in, or overwrites, the paper's
report; and a folder that already holds the report of other scenes (its
``results.json`` says which) is refused unless the user says ``--force``
(:func:`other_report`), since the files of the two would mix.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE
from flexval.geometry.scene import PAPER_SCENES

from ..outputs import safe_name


def default_report_folder(scenes: Sequence[str]) -> Path:
    """``paper_report`` for the paper's two scenes, else ``<scene>+<scene>..._report``, in the
    current folder (scene names made harmless file-name components)."""
    label = "paper" if tuple(scenes) == PAPER_SCENES else "+".join(safe_name(s) for s in scenes)
    return Path(f"{label}_report")


def reported_scenes(folder: Path) -> list[str] | None:
    """The scenes of the report in ``folder`` (its ``results.json``), None where it holds none
    that can be read."""
    try:
        data = json.loads((folder / "results.json").read_text(encoding="utf-8"))
        return sorted(data["scenes"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def other_report(folder: str | Path, scenes: Sequence[str], force: bool) -> None:
    """Refuse ``folder`` where it holds the report of other scenes than ``scenes`` (unless
    ``force``).

    Raises
    ------
    SceneError
        Naming ``--out``, the folder and the scenes reported there.
    """
    found = reported_scenes(Path(folder))
    if force or found is None or found == sorted(scenes):
        return
    raise SceneError(
        COMMAND_LINE,
        "--out",
        str(folder),
        f"holds the report of {', '.join(found)}, not of {', '.join(scenes)} (another "
        "folder, or --force to write over it)",
    )
