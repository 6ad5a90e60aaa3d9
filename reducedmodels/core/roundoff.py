"""The round-off of double-precision sums: the yardstick of the stability rule.

A leaf module, so that the rule (:mod:`flexval.reducedmodels.core.stability`) and
its compiled kernels (:mod:`flexval.reducedmodels.kernels.stabilitykernel`,
:mod:`flexval.reducedmodels.kernels.ldlkernel`) read the same constant without
importing each other. Dimensionless.
"""

from __future__ import annotations

import numpy as np

UNIT_ROUNDOFF = float(np.finfo(float).eps) / 2.0
"""u, half the spacing of doubles at 1 (2^-53)."""


def tolerance(terms: int) -> float:
    """gamma_w = w u / (1 - w u): the relative round-off of a sum of ``terms`` products."""
    w = max(int(terms), 1) * UNIT_ROUNDOFF
    return w / (1.0 - w)
