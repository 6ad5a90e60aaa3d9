"""How many threads the BLAS/LAPACK (and OpenMP) pools of this process may use.

flexval's linear systems are small or narrow-banded: a multithreaded BLAS
gains nothing on them, while OpenBLAS' default (one busy-waiting thread per
core) makes every LAPACK call stall as soon as another numerical process
shares the cores -- two continuum runs side by side took 5 s each instead of
1 s, and one next to a threaded-BLAS job 100 times longer. So flexval caps
the pools at ``DEFAULT_THREADS`` the first time it builds a system, unless
told otherwise:

* ``FLEXVAL_BLAS_THREADS=N`` (environment) or ``flexval --blas-threads N``
  (command line, which wins): cap at N threads;
* ``0`` leaves the pools as the BLAS libraries set them up (for example
  from ``OPENBLAS_NUM_THREADS``).

The cap is applied with threadpoolctl, which finds the BLAS and OpenMP
libraries actually loaded (numpy's and scipy's own OpenBLAS included).
"""

from __future__ import annotations

import os

ENV_VARIABLE = "FLEXVAL_BLAS_THREADS"
DEFAULT_THREADS = 1
MAX_THREADS = os.cpu_count() or 1
"""Most threads a cap may ask for: the logical CPUs (more only busy-wait against each other)."""
RULE = (
    f"must be a whole number of threads from 0 to {MAX_THREADS}, the logical CPUs "
    "(0: leave the BLAS pools alone)"
)

_requested: int | None = None  # the command line's cap, when it gave one
_applied: int | None = None  # the cap in force (0: pools left alone), None: not yet applied


def requested_threads(value: str | int | None = None) -> int:
    """The thread cap asked for: ``value``, else ``$FLEXVAL_BLAS_THREADS``, else the default.

    Raises ``ValueError`` naming the source and the value when it is not a
    whole number from 0 to ``MAX_THREADS``.
    """
    source = "--blas-threads"
    if value is None:
        source, value = ENV_VARIABLE, os.environ.get(ENV_VARIABLE, "").strip() or DEFAULT_THREADS
    text = str(value).strip()
    if not (text.isascii() and text.isdigit()) or int(text) > MAX_THREADS:
        raise ValueError(f"{source} {RULE}, got {value!r}")
    return int(text)


def request_threads(value: str | int | None = None) -> int:
    """Set the cap the next :func:`limit_threads` applies (the command line's entry point).

    The cap itself is applied when the first system is built, once numpy's
    and scipy's BLAS libraries are loaded: threadpoolctl only reaches the
    libraries loaded when it is called. Returns the cap; ``ValueError`` as
    :func:`requested_threads`.
    """
    global _requested, _applied
    _requested, _applied = requested_threads(value), None
    return _requested


def limit_threads() -> int:
    """Cap the BLAS/OpenMP pools of this process (see the module text); returns the cap.

    Decided once per process: the first system built pays for it (a few
    milliseconds), later calls cost a comparison.
    """
    global _applied
    if _applied is None:
        threads = _requested if _requested is not None else requested_threads()
        if threads:
            from threadpoolctl import threadpool_limits

            threadpool_limits(limits=threads)
        _applied = threads
    return _applied
