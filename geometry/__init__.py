"""flexval.geometry: what a planar compliant mechanism is (no solver knowledge).

Units everywhere: mm, N, MPa, N mm, rad (degrees only in scene files).
"""

from .errors import SceneError
from .kinematics import rotation
from .loads import Force, LoadCase, Moment
from .mechanism import Body, Flexure, Material, Mechanism, Section
from .scene import BUILTIN_SCENES, ModelSpec, Scene, load_scene, parse_model
from .shapes import Arc, Ellipse, Segment

__all__ = [
    "Arc", "Body", "BUILTIN_SCENES", "Ellipse", "Flexure", "Force", "LoadCase", "Material",
    "Mechanism", "ModelSpec", "Moment", "Scene", "SceneError", "Section", "Segment",
    "load_scene", "parse_model", "rotation",
]
