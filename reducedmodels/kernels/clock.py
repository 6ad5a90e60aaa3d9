"""The clock that load paths are timed on: wall time, less the time spent getting kernels.

A compiled kernel (:mod:`.jit`) is compiled on its first call with new argument
types, or its machine code is loaded from numba's on-disk cache: once per process
and signature, a cost of the process (seconds on a cold cache, milliseconds on a
warm one), not of the path that happened to call it first. Kernels are therefore
loaded where they are first called, and a path's ``seconds`` are read on
:func:`path_clock`: ``time.perf_counter()`` less the seconds this thread has spent
holding or waiting for numba's compiler lock (numba's documented event API, event
``numba:compiler_lock``, which covers compiling and loading from the cache). A
process that never imports numba (the continuum's) reads plain wall time.

Signals wait for kernel work too: meanwhile this thread blocks SIGINT and SIGTERM
(the operating system hands them to another thread, or holds them until the work
ends), and the command line's handler raises nothing while :func:`kernels_busy`
(:mod:`flexval.validation.interrupt`).

Units: s.
"""

from __future__ import annotations

import signal
import threading
import time


class _Held(threading.local):
    """This thread's seconds spent under numba's compiler lock, the nesting depth, and its
    signal mask from before."""

    seconds = 0.0
    depth = 0
    since = 0.0
    mask: set | None = None


_held = _Held()


def path_clock() -> float:
    """Seconds (an arbitrary origin) that stand still while this thread compiles or loads
    kernels: differences of two readings time a load path."""
    return time.perf_counter() - _held.seconds


def kernel_seconds() -> float:
    """Seconds this thread has spent compiling or loading kernels so far, s."""
    return _held.seconds


def kernels_busy() -> bool:
    """Whether this thread is compiling or loading a kernel now (inside numba's compiler
    lock, or waiting for it)."""
    return _held.depth > 0


_WAITING = (signal.SIGINT, signal.SIGTERM)
"""The signals held back from a thread while it compiles or loads a kernel."""


def _block_signals() -> set | None:
    """Block :data:`_WAITING` in this thread; the mask before (None where the platform has
    no thread signal masks)."""
    if not hasattr(signal, "pthread_sigmask"):
        return None
    return signal.pthread_sigmask(signal.SIG_BLOCK, _WAITING)


def _restore_signals(mask: set | None) -> None:
    """This thread's signal mask as :func:`_block_signals` found it."""
    if mask is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def count_kernel_time() -> None:
    """Start counting the time under numba's compiler lock (:mod:`.jit` calls this once,
    when it imports numba)."""
    from numba.core import event

    class CompilerLock(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            if _held.depth == 0:
                _held.since = time.perf_counter()
                _held.mask = _block_signals()
            _held.depth += 1

        def on_end(self, ev: event.Event) -> None:
            _held.depth -= 1
            if _held.depth == 0:
                _held.seconds += time.perf_counter() - _held.since
                _restore_signals(_held.mask)

    event.register("numba:compiler_lock", CompilerLock())
