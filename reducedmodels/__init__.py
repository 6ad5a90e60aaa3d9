"""flexval.reducedmodels: the paper's reduced flexibility models on one multibody core.

Units: mm, N, N mm, rad.
"""

from .core import Connector, SolverError, SolverSettings, System, solve_path
from .loadpath import LoadPath, write_results
from .models import REDUCED_FAMILIES, build_system, run_reduced

__all__ = ["Connector", "LoadPath", "REDUCED_FAMILIES", "SolverError", "SolverSettings", "System",
           "build_system", "run_reduced", "solve_path", "write_results"]
