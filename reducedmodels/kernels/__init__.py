"""The compiled kernels (numba) under the core and the families.

One decorator (:mod:`.jit`) for all of them; each module holds the kernels of
one concern (band factorisation, beam elements, node chains, DCMM sub-arcs, the
dense LDL^T, the tangent's ordering, PRBM chains, the stability rule's pivots,
stacked stresses). Units: those of the arrays they are given.
"""

__all__ = [
    "bandkernel",
    "beamkernel",
    "chainkernel",
    "clock",
    "dcmmkernel",
    "jit",
    "ldlkernel",
    "orderkernel",
    "prbmkernel",
    "stabilitykernel",
    "stresskernel",
]
"""The modules of this package (import the names from them)."""
