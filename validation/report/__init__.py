"""The validation report: one module per section, and what they draw.

:mod:`.data` computes every run a report needs, :mod:`.writer` writes the
Markdown, figures and JSON from it; the other modules are its sections and
tables. Units: mm, N, N mm, MPa, rad (degrees in the text).
"""

__all__ = [
    "data",
    "discussion",
    "drawing",
    "drivereaction",
    "figurejobs",
    "figures",
    "folder",
    "frequencies",
    "measured",
    "protocol",
    "stiffnesstable",
    "strength",
    "tables",
    "threed",
    "timings",
    "writer",
    "yieldtable",
]
"""The modules of this package (import the names from them)."""
