"""The multibody core every reduced model and the continuum run on.

The System of rigid bodies and connectors, the connector and connector-group
contracts, the one Newton solve, the one path tracer and its arc-length
continuation, the stability rule, the recorder of load paths, a batch of copies,
the linear response at rest, pins and prescribed motions, section forces and the
validity monitor. Units: mm, N, N mm, rad.
"""

__all__ = [
    "allocator",
    "batch",
    "batchsystem",
    "bifurcation",
    "blocktangent",
    "chains",
    "connector",
    "continuation",
    "drives",
    "extrapolation",
    "geometrycache",
    "inertia",
    "joints",
    "linearbatch",
    "loadpath",
    "loads",
    "newton",
    "peaks",
    "recorder",
    "restnumbering",
    "roundoff",
    "sections",
    "settings",
    "stability",
    "system",
    "tangent",
    "threads",
    "tracer",
    "validity",
]
"""The modules of this package (import the names from them)."""
