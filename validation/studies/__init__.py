"""The studies flexval runs on models: what each compares and measures.

Comparisons with the reference and with measurements, convergence, run time
against error, stress tests, limit loads, modes, buckling and stiffness about
an equilibrium, first yield, parasitic motion, the accuracy gate and its file,
the peers' benchmarks. Units: mm, N, N mm, MPa, rad, s.
"""

__all__ = [
    "batchtiming",
    "bench",
    "buckle",
    "campaign",
    "compare",
    "convergence",
    "dynamic",
    "gate",
    "gatefile",
    "gatemetrics",
    "junit",
    "limits",
    "measuredcompare",
    "modes",
    "parasitic",
    "peers",
    "stiffness",
    "stress",
    "studyfile",
    "yieldpoint",
]
"""The modules of this package (import the names from them)."""
