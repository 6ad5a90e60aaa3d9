"""flexval.geometry: what a planar compliant mechanism is (no solver knowledge).

Units everywhere: mm, N, MPa, N mm, rad (degrees only in scene files).
"""

from .errors import SceneError
from .inertia import MassData, RigidMass
from .kinematics import rotation
from .loads import Displacement, Force, LoadCase, Moment
from .mechanism import Body, Flexure, FlexureSpec, Material, Mechanism, PinSpec, Section
from .scene import BUILTIN_SCENES, MECHANISM_SCENES, Scene, load_scene
from .shapes import Arc, Ellipse, Segment, Spline

__all__ = [
    "Arc",
    "Body",
    "BUILTIN_SCENES",
    "MECHANISM_SCENES",
    "Ellipse",
    "Flexure",
    "FlexureSpec",
    "Displacement",
    "Force",
    "LoadCase",
    "MassData",
    "Material",
    "Mechanism",
    "Moment",
    "PinSpec",
    "RigidMass",
    "Scene",
    "SceneError",
    "Section",
    "Segment",
    "Spline",
    "load_scene",
    "rotation",
]
