"""Large temporaries reused, not mapped afresh: glibc's malloc thresholds in a batch's process.

glibc's malloc hands out every block of at least ``M_MMAP_THRESHOLD``
(128 kB until a larger mapped block is freed) as fresh pages from the
kernel and unmaps it on free, and returns the top of its heap to the kernel
once more than ``M_TRIM_THRESHOLD`` of it is free. A batch of copies works
on arrays of that size at every Newton iteration (a 1000-copy ``prbm``
batch: vectors of 21,000 unknowns, 168 kB; its factorised blocks, 3.5 MB),
so each of them was page-faulted in again at every iteration, and the
heap's top, returned to the kernel when a batch's arrays were freed, at the
next batch: the median batch of 1000 identical copies (open chain f+, six
batches after one) costs 5 % more CPU time with glibc's thresholds for
``prbm``, 4 % for ``dcmm:1``, 1–2 % for ``beam:20``, and a batch that
follows the freeing of a larger one up to 20 % more (80 MB faulted in).
:func:`keep_freed_memory` raises both thresholds once per process (the
first batch, as :func:`flexval.reducedmodels.core.threads.limit_threads` caps the
BLAS pools at the first system), so that freed blocks up to
:data:`MMAP_THRESHOLD` are reused from the heap and up to
:data:`TRIM_THRESHOLD` of free heap is kept for them (the process's
resident memory then stays near its peak).

``FLEXVAL_MALLOC=system`` (environment) leaves glibc's own thresholds; on a
C library without ``mallopt`` (macOS, Windows, musl) nothing is changed.
Results do not depend on it: only where memory comes from.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os

ENV_VARIABLE = "FLEXVAL_MALLOC"
"""``system``: leave the C library's malloc thresholds as they are."""
MMAP_THRESHOLD = 32 * 1024 * 1024
"""Smallest block (bytes) glibc maps afresh instead of taking from its heap: its own largest
dynamic threshold on 64-bit Linux (32 MiB), beyond a batch's largest temporaries."""
TRIM_THRESHOLD = 512 * 1024 * 1024
"""Free heap (bytes) glibc keeps before returning it to the kernel: more than a batch frees at
once. A 1000-copy ``prbm`` batch's process peaks near 270 MB, and when a batch's arrays are
freed (the garbage collector frees those of a batch's cycles) more than 64 MB (twice the
mapping threshold, glibc's own rule) left the heap's top at a time, so that every second
or third batch page-faulted 80 MB in again: 20 % of its time."""

_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # <malloc.h>'s parameter numbers
_applied: bool | None = None  # None: not decided yet in this process


def keep_freed_memory() -> bool:
    """Raise glibc's mapping and trimming thresholds once per process (see the module text).

    Returns whether the thresholds are raised in this process (False: told
    to leave them, or a C library without ``mallopt``).
    """
    global _applied
    if _applied is None:
        _applied = False
        if os.environ.get(ENV_VARIABLE, "").strip().lower() != "system":
            try:
                mallopt = ctypes.CDLL(ctypes.util.find_library("c") or None).mallopt
            except (OSError, AttributeError, TypeError):
                return _applied
            mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
            _applied = bool(
                mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)
                and mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD)
            )
    return _applied
