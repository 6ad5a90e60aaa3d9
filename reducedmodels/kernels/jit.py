"""How flexval compiles its kernels: the one numba decorator of every compiled module.

:data:`kernel` is ``numba.njit`` with the project's policy, so that the
beam, band, DCMM and PRBM kernels (:mod:`flexval.reducedmodels.kernels.beamkernel`,
:mod:`~flexval.reducedmodels.kernels.bandkernel`, :mod:`~flexval.reducedmodels.kernels.dcmmkernel`,
:mod:`~flexval.reducedmodels.kernels.prbmkernel`) cannot drift apart:

* ``cache=True``: compiled on first use and cached on disk next to the
  module (``__pycache__``); later processes load the machine code
  (benchmarks/README.md, "Compiled kernels", gives both costs);
* ``error_model="numpy"``: numpy's floating-point semantics (a zero-length
  chord gives inf or nan, which the Newton iteration reports as a
  non-finite residual, instead of raising inside compiled code);
* no ``fastmath``: no reassociation, so the numbers are those of the
  formulas in the order written, the same in every run;
* ``nogil=True``: a kernel releases the interpreter lock while it runs.

A kernel is compiled, or loaded from the cache, where it is first called: a run
gets only the kernels it uses, and the time this takes is left out of path times
(:mod:`.clock`, which starts counting it here).
"""

from __future__ import annotations

import numba
import numpy as np

from .clock import count_kernel_time

count_kernel_time()

kernel = numba.njit(cache=True, error_model="numpy", nogil=True)


@kernel
def _first(values: np.ndarray) -> float:
    """The first entry of ``values``: a kernel that does nothing, for :func:`initialise`."""
    return values[0]


def initialise() -> None:
    """Set up numba's compiler in this process (its registries and type inference, some
    0.3 s), by loading or compiling a trivial kernel: a process's runners call it before
    their clock starts, so that the first real kernel costs only its own machine code."""
    _first(np.zeros(1))
