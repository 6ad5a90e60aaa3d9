"""flexval.validation: the continuum reference and everything that compares models.

Units: mm, N, N mm, MPa, rad (degrees only at the edges: files, CLI, reports).
"""
