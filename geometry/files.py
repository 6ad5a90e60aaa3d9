"""Writing files safely, and where flexval keeps its caches.

Every file flexval writes (reports, figures, JSON, VTU, cache entries) goes
through :func:`atomic_path`: the content is written to a temporary file with
a unique name in the target's own folder, flushed to disk (fsync) and then
renamed over the target (``os.replace``, atomic on POSIX). A reader never
sees a half-written file, two processes writing the same target never
collide on a temporary name, and a failed write leaves the target as it was
and no temporary file behind; it raises :class:`OutputError`. The
temporary files being written are also listed (:func:`remove_temporaries`),
so that a process stopped by a signal can remove them before it ends.

This module sits in ``geometry`` because it is the lowest layer: the mesh
cache here and every writer in ``validation`` share it.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

CACHE_ENV = "FLEXVAL_CACHE"
"""Environment variable that moves the cache root (default ``~/.cache/flexval``)."""


class OutputError(OSError):
    """A file could not be written (full device, I/O error, removed folder, ...).

    Parameters
    ----------
    path : Path
        The file that was to be written.
    reason : str
        What went wrong, in plain words (the operating system's message).
    """

    def __init__(self, path: Path, reason: str):
        self.path, self.reason = Path(path), reason
        super().__init__(f"could not write {self.path}: {reason}")


class CacheWarning(UserWarning):
    """A cache entry or the cache folder is unusable; the result is recomputed."""


_LIVE: dict[Path, int] = {}
"""The temporary files :func:`atomic_path` is writing, with the id of the process writing each
(a forked child inherits its parent's entries; it removes only its own)."""


def remove_temporaries() -> list[Path]:
    """Remove the temporary files this process's :func:`atomic_path` calls are writing.

    For a process that ends on a signal (:mod:`flexval.validation.interrupt`): the
    targets stay as they were. Returns the removed paths.
    """
    pid = os.getpid()
    removed = []
    for tmp, owner in list(_LIVE.items()):
        if owner == pid:
            _LIVE.pop(tmp, None)
            try:
                tmp.unlink()
            except OSError:
                continue
            removed.append(tmp)
    return removed


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _fsync_folder(folder: Path) -> None:
    """Persist a rename in ``folder`` (best effort: not every file system allows it)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a unique temporary path next to ``target``; on success it replaces ``target``.

    The temporary name ends with the target's suffix, so writers that infer
    the format from the extension (Matplotlib, meshio, PyVista) still work.
    The finished file gets the usual permissions (0666 minus the umask).

    Raises
    ------
    OutputError
        If the temporary file cannot be created, written, synced or renamed
        (the target is left untouched and the temporary file removed).
    """
    target = Path(target)
    try:
        fd, name = tempfile.mkstemp(
            dir=target.parent, prefix=f".{target.name}.", suffix=f".tmp{target.suffix}"
        )
        os.close(fd)
    except OSError as exc:
        raise OutputError(target, exc.strerror or str(exc)) from exc
    tmp = Path(name)
    _LIVE[tmp] = os.getpid()
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OutputError):
            raise
        raise OutputError(target, exc.strerror or str(exc)) from exc
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        _LIVE.pop(tmp, None)
    _fsync_folder(target.parent)


def write_bytes(target: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``target`` atomically; returns the target path.

    Raises
    ------
    OutputError
        If the file cannot be written.
    """
    target = Path(target)
    with atomic_path(target) as tmp:
        tmp.write_bytes(data)
    return target


def cache_dir() -> Path | None:
    """Root of flexval's caches: ``$FLEXVAL_CACHE`` or ``~/.cache/flexval`` (created).

    Returns None, after a :class:`CacheWarning`, when the folder cannot be
    used (it is a regular file, or cannot be created or written): caching is
    an optimisation, so flexval then computes everything without it rather
    than fail.
    """
    root = Path(os.environ.get(CACHE_ENV) or Path.home() / ".cache" / "flexval")
    try:
        root.mkdir(parents=True, exist_ok=True)
        if not os.access(root, os.W_OK | os.X_OK):
            raise PermissionError("not writable")
    except OSError as exc:
        reason = (
            "it is not a folder"
            if root.exists() and not root.is_dir()
            else (exc.strerror or str(exc))
        )
        warnings.warn(
            f"cache folder {root} ({CACHE_ENV}) cannot be used: {reason}; "
            "computing without a cache",
            CacheWarning,
            stacklevel=2,
        )
        return None
    return root
