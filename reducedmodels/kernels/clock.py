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

Units: s.
"""

from __future__ import annotations

import threading
import time


class _Held(threading.local):
    """This thread's seconds spent under numba's compiler lock, and the nesting depth."""

    seconds = 0.0
    depth = 0
    since = 0.0


_held = _Held()


def path_clock() -> float:
    """Seconds (an arbitrary origin) that stand still while this thread compiles or loads
    kernels: differences of two readings time a load path."""
    return time.perf_counter() - _held.seconds


def kernel_seconds() -> float:
    """Seconds this thread has spent compiling or loading kernels so far, s."""
    return _held.seconds


def count_kernel_time() -> None:
    """Start counting the time under numba's compiler lock (:mod:`.jit` calls this once,
    when it imports numba)."""
    from numba.core import event

    class CompilerLock(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            if _held.depth == 0:
                _held.since = time.perf_counter()
            _held.depth += 1

        def on_end(self, ev: event.Event) -> None:
            _held.depth -= 1
            if _held.depth == 0:
                _held.seconds += time.perf_counter() - _held.since

    event.register("numba:compiler_lock", CompilerLock())
