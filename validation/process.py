"""Ending a ``flexval`` process without the interpreter's teardown.

When a command is done, a normal exit tears the interpreter down: it clears
every imported module (500-700 of them for a ``flexval run``: numpy, scipy,
scikit-fem...), frees their objects one by one and runs a final garbage
collection. Nothing of that is observable from outside, and it is not cheap:
a sizeable share of a short command's CPU time (``benchmarks/bench_process.py``
times whole commands). :func:`end_process` does what a
normal exit does that can be observed -- the exit handlers run (coverage
data, temporary folders' finalizers), Python's and the C library's output
buffers are flushed -- and then ends the process at once with the status.
(mypy's command line ends the same way, for the same reason.)

A reader that stops early (``flexval run ... | head -1``) closes the pipe
under the process's standard output. :func:`discard_output_when_reader_leaves`
makes the rest of the output go nowhere instead of raising
``BrokenPipeError`` in the middle of a command: the command still finishes
its work (its files are written) and exits with its own status.
"""

from __future__ import annotations

import atexit
import os
import sys
import threading


class _PipeSafeStream:
    """A text stream that sends its output to the null device once its pipe is broken."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._discard()
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._discard()

    def _discard(self) -> None:
        """Point the stream's file descriptor at the null device; buffered text goes there too."""
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, self._stream.fileno())
        os.close(null)
        self._stream.flush()

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def discard_output_when_reader_leaves() -> None:
    """Make ``sys.stdout`` go to the null device, not raise, when its reader closes the pipe."""
    if sys.stdout is not None and not isinstance(sys.stdout, _PipeSafeStream):
        sys.stdout = _PipeSafeStream(sys.stdout)


def end_process(status: int) -> None:
    """End this process with exit status ``status``, skipping the interpreter's teardown.

    Returns, leaving the caller to exit normally, when that is not safe: on
    a system other than POSIX, while another thread runs (a normal exit waits
    for it), under a profiler, tracer or debugger (``python -m cProfile``,
    coverage: they write their results after the program returns), with
    ``python -i`` (the prompt comes after the program), or when the output
    cannot be flushed (e.g. a closed pipe: the normal exit reports that).
    """
    if (
        os.name != "posix"
        or threading.active_count() > 1
        or sys.flags.inspect
        or sys.gettrace() is not None
        or sys.getprofile() is not None
        or not _flushed()
    ):
        return
    atexit._run_exitfuncs()  # noqa: SLF001  (CPython's exit handlers; no public runner)
    _flushed()
    import ctypes  # numpy has imported it already; C stdio buffers (printf)

    ctypes.CDLL(None).fflush(None)
    os._exit(status)


def _flushed() -> bool:
    """Flush ``sys.stdout`` and ``sys.stderr``; whether both succeeded."""
    try:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
    except (OSError, ValueError):
        return False
    return True
