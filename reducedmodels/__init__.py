"""flexval.reducedmodels: the paper's reduced flexibility models on one multibody core.

Units: mm, N, N mm, rad.
"""

from .connector import Connector
from .core import SolverError, SolverSettings, System
from .loadpath import LoadPath, write_results
from .loads import Loads
from .models import REDUCED_FAMILIES, build_system, run_reduced
from .recorder import PathRecorder, solve_path
from .tracer import LoadControl, PathPoint, trace

__all__ = ["Connector", "LoadControl", "LoadPath", "Loads", "PathPoint", "PathRecorder",
           "REDUCED_FAMILIES", "SolverError", "SolverSettings", "System", "build_system",
           "run_reduced", "solve_path", "trace", "write_results"]
