"""flexval.reducedmodels: the paper's reduced flexibility models on one multibody core.

Units: mm, N, N mm, rad.
"""

from . import families as _families  # noqa: F401  (registers beam, prbm, dcmm, ee)
from .catalogue import Family, ModelSpec, Option, Resolution, family, parse_model, register
from .connector import Connector
from .core import SolverError, SolverSettings, System
from .loadpath import LoadPath
from .loads import Loads
from .models import build_system, run_reduced
from .recorder import PathRecorder, solve_path
from .tracer import LoadControl, PathPoint, trace

__all__ = ["Connector", "Family", "LoadControl", "LoadPath", "Loads", "ModelSpec", "Option",
           "PathPoint", "PathRecorder", "Resolution", "SolverError", "SolverSettings", "System",
           "build_system", "family", "parse_model", "register", "run_reduced", "solve_path",
           "trace"]
