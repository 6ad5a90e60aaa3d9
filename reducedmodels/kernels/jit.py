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
"""

from __future__ import annotations

import numba

kernel = numba.njit(cache=True, error_model="numpy", nogil=True)
