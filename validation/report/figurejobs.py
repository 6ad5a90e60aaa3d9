"""Draw the report's figures on worker processes while its text is written.

Every figure function the report calls (:mod:`flexval.validation.report.figures`, the stress
profiles, the mechanism drawing, the runtime-versus-error plot) writes the
file it is given and nothing the text depends on: the text links to the path
it chose. :class:`Figures` runs them on ``workers`` processes, or at once in
this process with one worker; :meth:`Figures.wait` (also on leaving the
``with`` block) waits for every figure and raises the first failure, e.g. an
:class:`~flexval.validation.outputs.OutputError`, as the serial run would. An
exception in the block (SIGINT or SIGTERM among them) stops the workers at
once: a figure being drawn is not written, and its temporary file is removed.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor

from ..interrupt import stop_pool, worker_signals


def draw_now(fn: Callable, *args, **kwargs) -> None:
    """Draw a figure in this process (the serial ``draw``)."""
    fn(*args, **kwargs)


class Figures:
    """Figure jobs of one report: ``draw(fn, *args)`` runs ``fn(*args)`` on a worker.

    Parameters
    ----------
    workers : int
        Processes drawing; 1 draws each figure at once in this process.
    """

    def __init__(self, workers: int = 1):
        self.pool = (
            ProcessPoolExecutor(max_workers=workers, initializer=worker_signals)
            if workers > 1
            else None
        )
        self.pending: list[Future] = []

    def draw(self, fn: Callable, *args, **kwargs) -> None:
        """Draw ``fn(*args, **kwargs)`` (on a worker when there are several)."""
        if self.pool is None:
            fn(*args, **kwargs)
        else:
            self.pending.append(self.pool.submit(fn, *args, **kwargs))

    def wait(self) -> None:
        """Wait for every figure drawn so far; raise the first failure."""
        pending, self.pending = self.pending, []
        for fut in pending:
            fut.result()

    def __enter__(self) -> Figures:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc_type is None:
                self.wait()
        except BaseException:
            if self.pool is not None:
                stop_pool(self.pool)
            raise
        if self.pool is None:
            return
        if exc_type is None:
            self.pool.shutdown(wait=True)
        else:  # e.g. SIGINT or SIGTERM (flexval.validation.interrupt): no figure is waited for
            stop_pool(self.pool)
