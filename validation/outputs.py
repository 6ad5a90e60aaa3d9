"""Every output file of flexval: checked before the work, named safely, written atomically.

* :func:`check_file` and :func:`check_folder` test, before any computation,
  that an output given on the command line can be written: a missing folder,
  a folder where a file is expected (or the reverse), a path under a regular
  file, a device such as ``/dev/full``, or a place where no file can be
  created is a :class:`geometry.SceneError` naming the option and the path
  (CLI exit code 2, nothing computed).
* :func:`safe_name` turns any text (a scene or load-case name) into one file
  name component, and :func:`inside` resolves a name in the user's folder and
  refuses any result outside it (``..``, absolute names, symlinks out).
* :func:`write_text`, :func:`write_json` and :func:`save_figure` write through
  :func:`flexval.geometry.files.atomic_path`; a write that still fails (device full,
  I/O error) raises :class:`flexval.geometry.files.OutputError` (CLI exit code 4).
* :func:`write_json` writes strict JSON: non-finite floats (NaN, ±inf) become
  ``null``, never the non-standard ``NaN``/``Infinity`` tokens.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import tempfile
from pathlib import Path

import numpy as np

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE
from flexval.geometry.files import OutputError, atomic_path, write_bytes

__all__ = [
    "OutputError",
    "check_figure_file",
    "check_file",
    "check_folder",
    "inside",
    "json_safe",
    "safe_name",
    "output_path",
    "save_figure",
    "write_json",
    "write_text",
]

_UNSAFE = re.compile(r"[^A-Za-z0-9._+-]+")
MAX_NAME_CHARS = 80
"""Longest name component :func:`safe_name` returns (file systems allow 255 bytes)."""


def _probe(folder: Path) -> str | None:
    """Why no file can be created in ``folder`` (None if one can)."""
    try:
        fd, name = tempfile.mkstemp(dir=folder, prefix=".flexval-probe-")
    except OSError as exc:
        return f"no file can be created in {folder} ({exc.strerror or exc})"
    os.close(fd)
    os.unlink(name)
    return None


def use_file_backend() -> None:
    """Draw with Matplotlib's Agg backend (files, no window: the command line, reports,
    workers), unless ``MPLBACKEND`` names another one, as Jupyter's inline backend does, so
    that ``flexval.plot`` shows its pictures in a notebook."""
    import matplotlib

    if not os.environ.get("MPLBACKEND"):
        matplotlib.use("Agg")


def distinct_files(*given: tuple[str, Path | None]) -> None:
    """Refuse two output options that name the same file (one would overwrite the other).

    ``given`` are (option, checked path or None) pairs, in the command line's order.

    Raises
    ------
    SceneError
        Naming the later option and its path.
    """
    seen: dict[Path, str] = {}
    for option, path in given:
        if path is None:
            continue
        key = Path(os.path.realpath(path))
        if key in seen:
            raise SceneError(
                COMMAND_LINE, option, str(path), f"is the file {seen[key]} writes already"
            )
        seen[key] = option


def check_file(path: str | Path, option: str) -> Path:
    """Check, before any work, that output file ``path`` (given as ``option``) can be written.

    Raises
    ------
    SceneError
        Naming ``option`` and ``path`` when the file cannot be written.
    """
    text = str(path)
    target = Path(path)
    if not text or text.endswith(("/", os.sep)) or target.name in ("", ".", ".."):
        raise SceneError(COMMAND_LINE, option, text, "names a folder, expected a file path")
    if target.is_dir():
        raise SceneError(COMMAND_LINE, option, text, "is a folder, expected a file path")
    if target.exists() and not target.is_file():
        raise SceneError(
            COMMAND_LINE,
            option,
            text,
            "is not a regular file (a device, pipe or socket); give a file path",
        )
    folder = target.parent
    if not folder.exists():
        raise SceneError(COMMAND_LINE, option, text, f"folder {folder} does not exist")
    if not folder.is_dir():
        raise SceneError(COMMAND_LINE, option, text, f"{folder} is not a folder")
    reason = _probe(folder)
    if reason:
        raise SceneError(COMMAND_LINE, option, text, reason)
    return target


def check_figure_file(path: str | Path, option: str) -> Path:
    """:func:`check_file` for a picture: its suffix must be a format Matplotlib writes
    (no suffix: PNG).

    Raises
    ------
    SceneError
        Naming ``option`` and ``path`` when the file cannot be written or
        the format is unknown.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    target = check_file(path, option)
    fmt = target.suffix.lstrip(".").lower()
    formats = FigureCanvasAgg.get_supported_filetypes()
    if fmt and fmt not in formats:
        raise SceneError(
            COMMAND_LINE,
            option,
            str(path),
            f"unknown picture format '.{fmt}'; use one of "
            f"{', '.join('.' + f for f in sorted(formats))}",
        )
    return target


def check_folder(path: str | Path, option: str) -> Path:
    """Check, before any work, that output folder ``path`` can be written; create it if missing.

    Raises
    ------
    SceneError
        Naming ``option`` and ``path`` when the folder cannot be created or written.
    """
    text = str(path)
    if not text:
        raise SceneError(COMMAND_LINE, option, text, "empty folder name")
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise SceneError(COMMAND_LINE, option, text, "is a file, expected a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SceneError(
            COMMAND_LINE, option, text, f"cannot create the folder ({exc.strerror or exc})"
        ) from None
    reason = _probe(folder)
    if reason:
        raise SceneError(COMMAND_LINE, option, text, reason)
    return folder


def safe_name(text: str) -> str:
    """``text`` as one harmless file-name component.

    Keeps letters, digits and ``. _ + -``; any other run of characters
    (path separators, ``..``, spaces, control characters) becomes ``_``,
    leading dots and dashes are dropped and the length is bounded. When the
    name had to change, a short hash of the original is appended so that
    distinct names stay distinct (``a/b`` and ``a_b`` do not collide).
    """
    clean = _UNSAFE.sub("_", text).lstrip(".-")[:MAX_NAME_CHARS]
    if clean and clean == text:
        return clean
    digest = hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:8]
    return f"{clean or 'unnamed'}-{digest}"


def inside(folder: str | Path, name: str) -> Path:
    """``folder / name``, verified to resolve inside ``folder``.

    Raises
    ------
    OutputError
        If the resolved path (symlinks followed) leaves ``folder``.
    """
    base = Path(folder).resolve()
    path = (base / name).resolve()
    if path.parent != base and base not in path.parents:
        raise OutputError(base / name, f"refusing to write outside the output folder {base}")
    return path


def output_path(folder: str | Path, stem: str, suffix: str) -> Path:
    """The file ``safe_name(stem) + suffix`` in ``folder``, verified to be inside it.

    ``stem`` may contain user text (scene and load-case names); ``suffix``
    is the program's own (``.png``, ``.json``).
    """
    return inside(folder, safe_name(stem) + suffix)


def json_safe(value):
    """``value`` with every non-finite float replaced by None (numpy scalars made plain).

    Strict JSON has no NaN or Infinity; ``null`` marks a value that is
    undefined (each field's documentation says when that happens).
    """
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def write_text(path: str | Path, text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically (raises OutputError on failure)."""
    return write_bytes(path, text.encode("utf-8"))


def write_json(path: str | Path, data) -> Path:
    """Write ``data`` as strict JSON (non-finite floats as null), atomically."""
    return write_text(path, json.dumps(json_safe(data), indent=1, allow_nan=False) + "\n")


def save_figure(fig, path: str | Path, **savefig_options) -> Path:
    """Save a Matplotlib figure to ``path`` atomically (format from the suffix, default PNG)."""
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, **savefig_options)
    return path


def write_figure(fig, path: str | Path, dpi: int = 110) -> Path:
    """Lay out a finished Matplotlib figure, save it atomically (:func:`save_figure`) and
    close it, whatever happens (an open figure holds its memory until the process ends)."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    try:
        return save_figure(fig, path, dpi=dpi)
    finally:
        plt.close(fig)
