"""The fields of a scene file, declared once: the parser and the reference read them.

Each table of a scene is a :class:`flexval.geometry.fields.Table`;
:data:`SCENE_TABLES` lists them in the order of the reference.
:func:`flexval.geometry.scene.parse_scene` takes its known fields, defaults
and range checks from these declarations, and :func:`field_reference`
renders them as the scene file reference, so every field the parser accepts
is documented. Mass and gravity fields are declared in
:mod:`flexval.geometry.inertia`, time-law fields in
:mod:`flexval.geometry.timelaw`, load fields in :mod:`flexval.geometry.loads`.

Units of the file: mm, MPa, N, N mm, s, t, degrees.
"""

from __future__ import annotations

import dataclasses

from .fields import ABSENT, Field, Table, markdown_table, number_text
from .inertia import DENSITY_FIELD, GRAVITY, MASS_FIELDS
from .loads import LEVELS_FIELD, LOAD_FIELDS
from .profiles import NOTCH_CONTOURS
from .timelaw import TIME_LAW_FIELDS

NUMBER_LIMIT = 1e12
"""Largest magnitude of a number in a scene (unless its field sets a smaller one)."""
COORDINATE_LIMIT = 1e9
"""Largest magnitude of a point's coordinate, mm."""
OUTPUTS = ("png", "poses", "shape", "vtu")
"""What ``request.outputs`` may ask for."""
MAX_NAME_LENGTH = 200
"""Longest scene name (characters): it must fit a file name (255 bytes) with a suffix."""

SCENE = Table(
    "",
    "The scene's name and description, and its tables.",
    (
        Field(
            "name",
            "text",
            "the scene's name; other commands use it as a file-name stem, so it must be "
            f"safe as one (no path separators or control characters, at most "
            f"{MAX_NAME_LENGTH} characters)",
            default=ABSENT,
            default_text="the file's stem",
        ),
        Field("description", "text", "one line for reports", default=""),
        Field("material", "table", "the flexures' material"),
        Field("section", "table", "the default cross-section of every flexure"),
        Field("ground", "table", "the fixed body"),
        Field("target", "table", "the body and point whose motion every model reports"),
        Field("flexures", "tables", "the flexures (at least one)"),
        Field("bodies", "tables", "known points and mass data of links", default=ABSENT),
        Field("pins", "tables", "revolute joints between bodies", default=ABSENT),
        Field("gravity", "table", "a uniform gravity field", default=ABSENT),
        Field("load_cases", "tables", "the load cases (at least one)"),
        Field("request", "table", "the models and outputs to run", default=ABSENT),
        Field(
            "measurements",
            "tables",
            "measured load–displacement files to compare the models with",
            default=ABSENT,
        ),
    ),
)
"""The top level of a scene file."""

MATERIAL = Table(
    "material",
    "The flexures' material: linear elastic (the continuum reference also offers a "
    "neo-Hookean law with the same moduli).",
    (
        Field("youngs_modulus", "number", "Young's modulus E", unit="MPa", positive=True),
        Field(
            "poisson_ratio",
            "number",
            "Poisson's ratio ν (used by the continuum and the shear corrections)",
            default=0.3,
            interval=(-1.0, 0.5),
        ),
        Field(
            "yield_strength",
            "number",
            "yield strength σ_y: the run reports the load at first yield and the safety "
            "factor at full load of every model (decides no load path)",
            unit="MPa",
            default=ABSENT,
            positive=True,
        ),
        Field(
            "fatigue_strength",
            "number",
            "fatigue (endurance) strength σ_f, below `yield_strength` (which it needs): "
            "the run reports the safety factor against it too",
            unit="MPa",
            default=ABSENT,
            positive=True,
        ),
        DENSITY_FIELD,
    ),
)

SECTION = Table(
    "section",
    "The rectangular cross-section of every flexure; a flexure may override either field.",
    (
        Field("depth", "number", "out-of-plane depth b", unit="mm", positive=True),
        Field("thickness", "number", "in-plane thickness h", unit="mm", positive=True),
    ),
)

GROUND = Table(
    "ground",
    "The fixed body. Every ground point must hold a flexure end or a pin.",
    (
        Field("name", "name", "the ground's body name (flexures and pins refer to it)"),
        Field(
            "points",
            "points",
            "where the ground holds flexures or pins (at least one point)",
            unit="mm",
        ),
    ),
)

TARGET = Table(
    "target",
    "The body and the point whose displacement and rotation every model reports.",
    (
        Field("body", "name", "the target body"),
        Field("point", "point", "the traced point, in the undeformed configuration", unit="mm"),
    ),
)

FLEXURE_SHAPES = ("arc", "segment", "notch", "spline")
"""The flexure shapes a scene may name (``shape = ...``)."""

FLEXURES = Table(
    "flexures",
    "One entry per flexure: the two bodies it joins and its centre line. An arc is "
    "given by its centre, radius, the direction of its axis of symmetry and its "
    "angular width (it spans axis ± width/2); a segment by its two ends; a notch "
    "hinge by the two ends of its straight axis and its thickness contour, "
    "symmetric about the axis and the middle, thinnest (`thickness` = t) at the "
    "middle and `height` = H at both ends; a spline by the points its centre line "
    "passes through (the C² cubic spline by chord length, not-a-knot ends). An arc, "
    "a segment or a spline may taper: `thickness = [h_start, h_end]` varies linearly "
    "in arc length from the centre line's first end. A field of another shape is "
    "refused by name; without `shape` the flexure is an arc, so `start` and `end` or "
    "`points` there name the missing `shape`.",
    (
        Field("name", "name", "the flexure's name (unique)"),
        Field(
            "bodies",
            "names",
            "the two different bodies it joins, e.g. [1, 2]; either may be the ground",
        ),
        Field(
            "shape",
            "choice",
            "shape of the centre line",
            default="arc",
            choices=FLEXURE_SHAPES,
        ),
        Field("center", "point", "centre of the arc", unit="mm", variants=("arc",)),
        Field(
            "radius", "number", "radius r of the arc", unit="mm", positive=True, variants=("arc",)
        ),
        Field(
            "axis_deg",
            "number",
            "direction of the arc's axis of symmetry, from the x axis, counterclockwise",
            unit="deg",
            variants=("arc",),
        ),
        Field(
            "width_deg",
            "number",
            "angular width of the arc",
            unit="deg",
            interval=(0.0, 360.0),
            variants=("arc",),
        ),
        Field(
            "start",
            "point",
            "first end of the segment or of the notch's axis",
            unit="mm",
            variants=("segment", "notch"),
        ),
        Field(
            "end",
            "point",
            "second end of the segment or of the notch's axis (not equal to start)",
            unit="mm",
            variants=("segment", "notch"),
        ),
        Field(
            "contour",
            "choice",
            "the notch's thickness contour: circular cut-outs through the ends and the "
            "middle, elliptical (semi-axes L/2 and (H - t)/2), quarter-circle fillets of "
            "radius r at a flat of thickness t, or t + (H - t) |2 s / L - 1|^n",
            choices=NOTCH_CONTOURS,
            variants=("notch",),
        ),
        Field(
            "height",
            "number",
            "the notch's thickness H at both ends (H > t)",
            unit="mm",
            default=ABSENT,
            default_text="t + 2 fillet_radius (corner-filleted); required otherwise",
            positive=True,
            variants=("notch",),
        ),
        Field(
            "fillet_radius",
            "number",
            "radius r of a corner-filleted notch's fillets (r <= L/2)",
            unit="mm",
            default=ABSENT,
            default_text="required for corner-filleted",
            positive=True,
            variants=("notch",),
        ),
        Field(
            "exponent",
            "number",
            "exponent n of a power-law notch",
            default=ABSENT,
            default_text="required for power",
            positive=True,
            variants=("notch",),
        ),
        Field(
            "points",
            "points",
            "the points the spline passes through, in order (at least 3, all different, "
            "the curve not crossing itself)",
            unit="mm",
            variants=("spline",),
        ),
        Field(
            "crosses",
            "texts",
            "names of flexures whose centre lines this one crosses out of plane: a "
            "cross-axis pivot's leaves lie in layers of their own, side by side in depth, "
            "and cross in the plane's projection (otherwise flexures that cross or whose "
            "outlines overlap are refused)",
            default=ABSENT,
            default_text="none",
        ),
        Field(
            "start_body",
            "name",
            "the body at the centre line's first end (arcs: the end at axis - width/2); "
            "by default it is found from the ground points and the chain",
            default=ABSENT,
        ),
        Field(
            "depth",
            "number",
            "out-of-plane depth b of this flexure",
            unit="mm",
            default=ABSENT,
            default_text="[section] depth",
            positive=True,
        ),
        Field(
            "thickness",
            "number | pair",
            "in-plane thickness h of this flexure, or [h_start, h_end] for a linear taper "
            "(arc, segment, spline); a notch's smallest thickness t (a number). Smaller "
            "than twice the radius of curvature everywhere (arcs: h < 2 r)",
            unit="mm",
            default=ABSENT,
            default_text="[section] thickness",
            positive=True,
        ),
    ),
    array=True,
    selector="shape",
)

BODIES = Table(
    "bodies",
    "Optional, one entry per link: points known on it (checked against the flexures "
    "and pins that hold it) and its mass, either explicit (mass, inertia and "
    "center_of_mass together) or from an outline polygon of the material's density. "
    "A body without mass data is massless: static runs do not need it, dynamic runs "
    "and modal analyses refuse it by name.",
    (
        Field("name", "name", "the body's name (as flexures, pins and loads name it)"),
        Field("points", "points", "known points of the link", unit="mm", default=ABSENT),
        *MASS_FIELDS,
    ),
    array=True,
)

PINS = Table(
    "pins",
    "Optional revolute joints. A pin joins two different bodies at a point; either "
    "may be the ground. Pins that leave the mechanism mobile, or are redundant, are "
    "refused by name.",
    (
        Field("name", "name", "the pin's name (unique)"),
        Field("bodies", "names", "the two different bodies it joins"),
        Field("point", "point", "the pin's position", unit="mm"),
    ),
    array=True,
)

LOAD_CASES = Table(
    "load_cases",
    "One entry per load case: either a single load (its fields in the entry) or "
    "several loads scaled together (`loads = [{...}, ...]`, each with the fields of "
    "[`[[load_cases.loads]]`](#scene-load_cases-loads)). Every load is scaled by one load "
    "factor from 0 to 1; the time-law fields say how it grows in a dynamic run.",
    (
        Field("name", "name", "the load case's name (unique)"),
        LEVELS_FIELD,
        *(dataclasses.replace(f, variants=("single",)) for f in LOAD_FIELDS),
        Field(
            "loads",
            "tables",
            "the loads of a combined case (at least one), each a table of the "
            "[[load_cases.loads]] fields",
            default=ABSENT,
            variants=("combined",),
        ),
        *TIME_LAW_FIELDS,
    ),
    array=True,
    selector="form",
)

LOAD_COMPONENTS = Table(
    "load_cases.loads",
    "One load of a combined load case (inline tables in `loads`). A moment has no "
    "point or direction; a force needs `angle_deg`.",
    LOAD_FIELDS,
    array=True,
)

REQUEST = Table(
    "request",
    "Optional: what `flexval run` runs when no model is named on the command line.",
    (
        Field(
            "models",
            "texts",
            'model ids, e.g. "beam:100", "prbm", "dcmm:2[frame=follower]" (see the '
            "model catalogue)",
            default=ABSENT,
            default_text="none",
        ),
        Field(
            "outputs",
            "choices",
            "extra outputs: poses (body poses), shape (deformed centre lines), vtu and "
            "png (continuum fields)",
            default=ABSENT,
            default_text="none",
            choices=OUTPUTS,
        ),
    ),
)

MEASUREMENTS = Table(
    "measurements",
    "Optional: measured load–displacement files of the mechanism (from a test rig), one "
    "entry per file. `flexval report` adds a section *Against measurements* that scores "
    "every model against each, as `flexval compare` does on the command line; the file "
    "format and the scores are described on the page "
    "[Comparing with measurements](../measurements.md). A missing or bad file is refused "
    "naming the entry, the line and the column.",
    (
        Field("load_case", "name", "the load case the file measures"),
        Field("file", "text", "the CSV file, relative to the scene file's folder"),
    ),
    array=True,
)

SCENE_TABLES = (
    SCENE,
    MATERIAL,
    SECTION,
    GROUND,
    TARGET,
    FLEXURES,
    BODIES,
    PINS,
    GRAVITY,
    LOAD_CASES,
    LOAD_COMPONENTS,
    REQUEST,
    MEASUREMENTS,
)
"""Every table of a scene file, in reference order."""


def scene_table(path: str) -> Table:
    """The declared table at ``path`` (``""`` for the top level)."""
    for table in SCENE_TABLES:
        if table.path == path:
            return table
    raise KeyError(f"no scene table {path!r}; tables are {[t.path for t in SCENE_TABLES]}")


_RULES = f"""\
Rules for every field:

- Units: lengths mm, moduli MPa, forces N, moments N mm, times s, masses t
  (1 t = 1000 kg), angles degrees in the file (radians inside flexval).
- A number must be finite, of magnitude at most {number_text(NUMBER_LIMIT)} (point
  coordinates {number_text(COORDINATE_LIMIT)}), and not subnormal.
- A *name* is a non-empty string or an integer (`bodies = [1, 2]` and
  `bodies = ["1", "2"]` are the same).
- A field no table declares is refused, naming it and the fields expected.
- Every error names the file, the field (e.g. `flexures.e12.radius`) and the value.
"""


def field_reference(level: int = 2) -> str:
    """The scene file reference: every table and field, as Markdown.

    Parameters
    ----------
    level : int
        Heading level of each table's section.

    Returns
    -------
    str
        One section per table of :data:`SCENE_TABLES`: its header, what it
        holds and a table of its fields (kind, unit, default, allowed values,
        description).
    """
    parts = [_RULES]
    for table in SCENE_TABLES:
        anchor = "scene-" + (table.path.replace(".", "-") or "top")
        title = f"`{table.heading}`" if table.path else "Top level"
        parts.append(f"{'#' * level} {title} {{#{anchor}}}")
        parts.append(table.description)
        parts.append(markdown_table(table))
    return "\n\n".join(parts)
