"""Stopping a ``flexval`` command on SIGINT (Ctrl-C) or SIGTERM.

:func:`install` (the console script calls it) makes either signal raise
:class:`Interrupted` in the main thread, a ``KeyboardInterrupt``: every ``with``
and ``finally`` on the way out runs, so a file being written through
:func:`flexval.geometry.files.atomic_path` is removed and its target left as
it was, a process pool is stopped (:func:`stop_pool`) and a Dask cluster
closed. The command line then removes what is left of its temporary files,
ends its child processes, prints one line saying what was kept (:func:`keep`
sets it) and exits with 128 + the signal number: 130 for SIGINT, 143 for SIGTERM.

A Python signal handler runs only between byte codes of the main thread, so a
long computation in compiled code would delay it. A watcher thread therefore
receives every signal as well (Python's wakeup file descriptor, written by the
C-level handler at once): when the orderly stop has not ended the process
:data:`GRACE_S` seconds after the first signal, or on a second signal, it
stops the process itself: it kills the child processes, removes this
process's temporary files, prints the line and ends the process. The handler
raises nothing while numba compiles or loads a kernel
(:mod:`flexval.reducedmodels.kernels.clock`) or runs its own code on a kernel's
first call (it unpickles the constants that build the results): an exception
there can leave a result tuple half-built, a segmentation fault when it is read.
The watcher ends such a process after :data:`GRACE_S`, or the command line does
at its end, whichever comes first, as if the signal had been raised.

Worker processes (:func:`worker_signals`, the initializer of every process
pool) end at once on either signal, after removing their own temporary files:
a terminal's Ctrl-C reaches them too, and :func:`stop_pool` sends them SIGTERM.

What is kept is whole: finished Parquet parts of a sweep, result-cache entries,
output files written before the signal. Running the same command again resumes
where the stores allow it (a sweep skips the stored rows, a report reads the
cached load paths).
"""

from __future__ import annotations

import atexit
import logging
import os
import select
import signal
import sys
import threading
import time
from collections.abc import Callable
from typing import NoReturn

from flexval.geometry.files import remove_temporaries
from flexval.reducedmodels.kernels.clock import kernels_busy

GRACE_S = 1.5
"""Seconds the orderly stop may take after the first signal before the watcher thread ends
the process (the command must be gone within 2 s)."""
CHILD_WAIT_S = 0.3
"""Seconds a child process has to end after SIGTERM before it is killed (SIGKILL)."""
SIGNALS = (signal.SIGINT, signal.SIGTERM)
_STOP_WATCHER = b"\xff"


class Interrupted(KeyboardInterrupt):
    """A SIGINT or SIGTERM received by a command (:func:`install`).

    Parameters
    ----------
    signum : int
        The signal number; :attr:`status` is the exit status, 128 + ``signum``.
    """

    def __init__(self, signum: int):
        self.signum = signum
        self.status = 128 + signum
        super().__init__(signal.Signals(signum).name)


class _State:
    def __init__(self) -> None:
        self.signum: int | None = None
        self.kept: Callable[[], str] | str = "nothing (the same command starts again)"
        self.watcher: threading.Thread | None = None
        self.wake: tuple[int, int] | None = None
        self.done = threading.Event()
        self.exiting = threading.Lock()


_state = _State()


def received() -> int | None:
    """The signal number that interrupted this command, or None."""
    return _state.signum


def keep(description: Callable[[], str] | str) -> None:
    """Say what an interruption from now on keeps: a text, or a function giving it then
    (e.g. counting the finished parts)."""
    _state.kept = description


def _kept() -> str:
    try:
        return _state.kept() if callable(_state.kept) else _state.kept
    except Exception:  # the message must not fail the exit
        return "what was finished before the signal"


def message(signum: int) -> str:
    """The line printed when ``signum`` stopped the command."""
    return f"flexval: interrupted by {signal.Signals(signum).name}; kept: {_kept()}"


def _on_signal(signum: int, frame) -> None:
    if _state.signum is not None:
        return  # already stopping; a second signal makes the watcher stop at once
    _state.signum = signum
    if kernels_busy() or _inside_numba(frame):
        return  # raised there, it could crash the process: the watcher ends it instead
    raise Interrupted(signum)


def _inside_numba(frame) -> bool:
    """Whether ``frame`` runs numba's or llvmlite's own code (a kernel compiled or loaded,
    or its first call building its results)."""
    name = frame.f_code.co_filename if frame is not None else ""
    return any(f"{os.sep}{package}{os.sep}" in name for package in ("numba", "llvmlite"))


class AbandonedDaskCall(logging.Filter):
    """Drops the event loop's report of Dask's ``sync`` cancelling a call that had not
    started when the interrupt arrived.

    ``distributed.utils.sync`` answers a ``KeyboardInterrupt`` in its wait by scheduling
    a ``cancel`` of the call's future on the event loop; when the interrupt comes before
    the loop started the call, the future was never assigned and ``cancel`` raises
    ``NameError`` (distributed 2026.8), which the loop logs with its traceback. The call
    is abandoned either way (the command is stopping), so the record says nothing: every
    other record passes.
    """

    def filter(self, record: logging.LogRecord) -> bool:
        error = record.exc_info[1] if record.exc_info else None
        if not isinstance(error, NameError) or received() is None:
            return True
        frame = error.__traceback__
        while frame is not None and frame.tb_next is not None:
            frame = frame.tb_next
        code = frame.tb_frame.f_code if frame is not None else None
        return not (
            code is not None
            and code.co_name == "cancel"
            and code.co_filename.replace(os.sep, "/").endswith("distributed/utils.py")
        )


_ABANDONED_DASK_CALL = AbandonedDaskCall()


def install() -> None:
    """Handle SIGINT and SIGTERM in this process (main thread; a signal the parent set
    to be ignored stays ignored) and start the watcher thread."""
    for name in ("tornado.application", "asyncio"):  # the event loop's callback errors
        logging.getLogger(name).addFilter(_ABANDONED_DASK_CALL)
    handled = False
    for sig in SIGNALS:
        if signal.getsignal(sig) is signal.SIG_IGN:
            continue
        signal.signal(sig, _on_signal)
        handled = True
    if not handled or _state.watcher is not None:
        return
    read, write = os.pipe()
    os.set_blocking(write, False)
    try:
        signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    except ValueError:  # not the main thread
        os.close(read)
        os.close(write)
        return
    _state.wake = (read, write)
    _state.watcher = threading.Thread(target=_watch, args=(read,), name="flexval-interrupt")
    _state.watcher.daemon = True
    _state.watcher.start()


def uninstall() -> None:
    """Stop the watcher thread (the command is ending on its own) and restore the default
    handlers."""
    _state.done.set()
    if _state.watcher is None:
        return
    signal.set_wakeup_fd(-1)
    read, write = _state.wake
    try:
        os.write(write, _STOP_WATCHER)
    except OSError:
        pass
    _state.watcher.join(timeout=1.0)
    os.close(read)
    os.close(write)
    _state.watcher = _state.wake = None
    for sig in SIGNALS:
        if signal.getsignal(sig) is _on_signal:
            signal.signal(
                sig, signal.SIG_DFL if sig == signal.SIGTERM else signal.default_int_handler
            )


def _watch(read: int) -> None:
    """The watcher thread: after the first SIGINT/SIGTERM, end the process if the orderly
    stop takes longer than :data:`GRACE_S`, or at once on a second one."""
    first: int | None = None
    deadline = None
    while True:
        wait = None if deadline is None else max(deadline - time.monotonic(), 0.0)
        try:
            ready, _, _ = select.select([read], [], [], wait)
            data = os.read(read, 64) if ready else b""
        except (OSError, ValueError):
            return
        if _STOP_WATCHER in data or _state.done.is_set():
            return
        signums = [b for b in data if b in SIGNALS]
        if first is None and signums:
            first = signums[0]
            deadline = time.monotonic() + GRACE_S
            signums = signums[1:]
        if first is not None and (signums or time.monotonic() >= deadline):
            hard_stop(first)
            return


def hard_stop(signum: int) -> NoReturn:
    """End the process now (any thread): unless :func:`finish` has done it, kill the child
    processes, remove this process's temporary files and print the line; exit with
    128 + ``signum``."""
    if _state.exiting.acquire(blocking=False):
        stop_children()
        remove_temporaries()
        _write_line(message(signum))
    os._exit(128 + signum)


def finish(signum: int) -> NoReturn:
    """The orderly end of an interrupted command (main thread): child processes ended,
    temporary files removed, the line printed, the exit handlers run (the watcher thread
    still ends the process :data:`GRACE_S` s after the signal if they take longer), and the
    process ended with 128 + ``signum``."""
    if not _state.exiting.acquire(blocking=False):
        time.sleep(GRACE_S)  # the watcher thread is ending the process
        os._exit(128 + signum)
    stop_children()
    remove_temporaries()
    _write_line(message(signum))
    # the exit handlers (Dask's among them) would report on the work cut short: not wanted
    sys.stderr = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115
    atexit._run_exitfuncs()  # noqa: SLF001  (as flexval.validation.process.end_process)
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(128 + signum)


def _write_line(text: str) -> None:
    """Write a line to stderr's file descriptor (no Python buffer lock: another thread may
    hold it), after a line end: the signal may have cut a line, or a progress bar holds it."""
    data = ("\n" + text + "\n").encode("utf-8", "replace")
    try:
        os.write(sys.stderr.fileno() if sys.stderr is not None else 2, data)
    except (OSError, ValueError):
        pass


def stop_children(wait: float = CHILD_WAIT_S) -> None:
    """End every descendant process of this one: SIGTERM, then SIGKILL after ``wait`` s."""
    try:
        import psutil
    except ImportError:  # psutil comes with distributed; without it, no children to find
        return
    try:
        children = psutil.Process().children(recursive=True)
    except psutil.Error:
        return
    # multiprocessing's resource tracker ends by itself with this process, after it has
    # removed what the workers left (shared-memory semaphores)
    tracker = sys.modules.get("multiprocessing.resource_tracker")
    spared = getattr(getattr(tracker, "_resource_tracker", None), "_pid", None)
    children = [c for c in children if c.pid != spared]
    for child in children:
        try:
            child.terminate()
        except psutil.Error:
            pass
    _, alive = psutil.wait_procs(children, timeout=wait)
    for child in alive:
        try:
            child.kill()
        except psutil.Error:
            pass
    psutil.wait_procs(alive, timeout=wait)


def _worker_signal(signum: int, frame) -> None:
    remove_temporaries()
    os._exit(128 + signum)


def worker_signals() -> None:
    """Initializer of a worker process: end at once on SIGINT or SIGTERM, after removing its
    own temporary files (no traceback, no half-written file)."""
    try:
        signal.set_wakeup_fd(-1)  # a forked worker must not wake its parent's watcher
    except ValueError:
        pass
    for sig in SIGNALS:
        signal.signal(sig, _worker_signal)


def stop_pool(pool) -> None:
    """Stop a ``concurrent.futures.ProcessPoolExecutor`` now: queued work cancelled, its
    worker processes sent SIGTERM (killed after :data:`CHILD_WAIT_S` s)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    end = time.monotonic() + CHILD_WAIT_S
    for proc in processes:
        proc.join(timeout=max(end - time.monotonic(), 0.0))
        if proc.is_alive():
            proc.kill()
            proc.join(timeout=CHILD_WAIT_S)
