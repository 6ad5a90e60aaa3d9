"""The fields of a sweep file: its top-level table and its ``[[axes]]``, with their limits.

Declared once (:class:`flexval.geometry.fields.Table`): :mod:`.spec` reads and
checks a file against them, and the documentation's field reference is
generated from them (:func:`field_reference`).
"""

from __future__ import annotations

from flexval.geometry.fields import ABSENT, Field, Table, markdown_table

from ..studies.compare import METRICS

COMBINE = ("grid", "zip")
SAMPLES = {"uniform": ("low", "high"), "normal": ("mean", "std"), "lognormal": ("median", "sigma")}
SUMMARY_METRICS = ("worst",) + METRICS
"""``worst`` is max(end_disp_vec, end_rot): a model is as good as its worse end error."""
ALWAYS_OUTPUTS = ("errors", "times")
"""Outputs of every row: the error metrics against the reference and the run time."""
OPTIONAL_OUTPUTS = ("peak_stress", "limit_load", "first_yield")
"""``peak_stress``: the largest outer-fibre stress at full load and its error against the
reference's (free: every model records it); ``limit_load``: the first limit point of a run
that stops below full load, found by arc length (costly: only on request); ``first_yield``:
the load at first yield and the safety factors at full load against the scene's
``material.yield_strength`` (free; null without one)."""
DEFAULT_OUTPUTS = ("peak_stress",)
MAX_COUNT = 1_000_000
"""Most values of one axis, and most points of one task (``batch``)."""
MAX_POINTS = 1_000_000
"""Default bound on a sweep's points (``flexval sweep --max-points``): the point count is
computed from the axes before any point is built, and a sweep with more is refused."""
BYTES_PER_POINT = 10e3
"""Memory a sweep's driver holds per point, bytes: the points themselves are not held (a
:class:`PointRecord` each, and the scenes of the blocks in flight), but the keys of their
stored rows and the rows the summary reads are, 3.8 kB a row measured (open_chain, 20,000
points, two rows each: 160 MB); a sweep whose points would not fit is refused."""
RECORD_BLOCK = 4096
"""Points whose parameters a lazy :class:`PointSet` computes at a time for its records."""
CHECK_BLOCK = 512
"""Points whose values the checking pass of :func:`parse_sweep` proves valid together
(:meth:`PointBuilder.build_block`; it builds them one at a time)."""
SECONDS_PER_POINT = 6e-3
"""Time to build one point (parse and check its scene), s, for the duration a long check
announces: about what a point of the slowest built-in scene, notch_fourbar, takes."""

SWEEP = Table(
    "",
    "What is swept, with which models, against which reference.",
    (
        Field("name", "text", "the sweep's name", default=ABSENT, default_text="the file's stem"),
        Field("description", "text", "one line for the summary", default=""),
        Field(
            "base",
            "any",
            "the base scene: a built-in scene name, a scene file path (relative to the "
            "sweep file) or an inline table of scene fields",
        ),
        Field("models", "texts", "model ids to compare with the reference (each once)"),
        Field(
            "reference",
            "text",
            "model id every error is measured against (not one of models)",
            default="beam:100",
        ),
        Field(
            "reference_sample",
            "integer",
            "run the reference on this many of the valid points only (a tolerance study "
            "needs the models' outputs at every point but their errors on a subsample): "
            "error columns exist only on the rows of those points",
            default=ABSENT,
            default_text="every point",
            minimum=1,
            maximum=MAX_COUNT,
        ),
        Field(
            "load_cases",
            "texts",
            "load cases of the base scene to run",
            default=ABSENT,
            default_text="all of the base scene's",
        ),
        Field(
            "combine",
            "choice",
            "grid: every combination of the axes' values; zip: the i-th value of each axis "
            "together (axes of equal length)",
            default=COMBINE[0],
            choices=COMBINE,
        ),
        Field(
            "metric",
            "choice",
            "the summary's metric: worst = max(end_disp_vec, end_rot), or one error metric",
            default=SUMMARY_METRICS[0],
            choices=SUMMARY_METRICS,
        ),
        Field(
            "linear_rotation",
            "number",
            "scale each load case at every point so that the linear (ee) end rotation is this",
            unit="rad",
            default=ABSENT,
            positive=True,
        ),
        Field(
            "batch",
            "integer",
            "points per task of a reduced model",
            default=ABSENT,
            default_text="automatic: the first tasks points / (4 workers), 1 to 25; then about "
            "1 s of measured work each",
            minimum=1,
            maximum=MAX_COUNT,
        ),
        Field(
            "outputs",
            "choices",
            "what each row holds besides errors and times (always there): peak_stress "
            "(free), limit_load (an arc-length search on each run that stops early) and "
            "first_yield (free; against the scene's material.yield_strength)",
            default=ABSENT,
            default_text="`" + str(list(DEFAULT_OUTPUTS)).replace("'", '"') + "`",
            choices=ALWAYS_OUTPUTS + OPTIONAL_OUTPUTS,
        ),
        Field("axes", "tables", "the swept parameters", default=ABSENT, default_text="none"),
    ),
)
"""The top level of a sweep file."""

AXIS_KINDS = ("values", "linspace", "logspace", "sample")
"""How an axis gives its values: exactly one of these fields."""

AXES = Table(
    "axes",
    "One swept parameter: a scene field path and its values, given by exactly one of "
    "`values`, `linspace`, `logspace` or `sample` (random draws with `count` and "
    "`seed`, and the distribution's two parameters).",
    (
        Field(
            "path",
            "text",
            "the scene field, e.g. section.thickness, flexures.e12.thickness, "
            "load_cases.f+.value, ground.points.0.1 (arrays of tables by name, plain "
            "arrays by index)",
        ),
        Field(
            "values",
            "numbers",
            "the values, listed (numbers, in the field's unit)",
            default=ABSENT,
            variants=("values",),
        ),
        Field(
            "linspace",
            "numbers",
            "[first, last, count]: count evenly spaced values",
            default=ABSENT,
            variants=("linspace",),
        ),
        Field(
            "logspace",
            "numbers",
            "[first, last, count]: count values in geometric progression (first, last > 0)",
            default=ABSENT,
            variants=("logspace",),
        ),
        Field(
            "sample",
            "choice",
            "random draws: uniform (low, high), normal (mean, std), lognormal (median, sigma)",
            default=ABSENT,
            choices=tuple(SAMPLES),
            variants=("sample",),
        ),
        Field(
            "count",
            "integer",
            "number of draws",
            default=ABSENT,
            minimum=1,
            maximum=MAX_COUNT,
            variants=("sample",),
        ),
        Field(
            "seed",
            "integer",
            "seed of the draws (repeatable)",
            default=ABSENT,
            minimum=0,
            variants=("sample",),
        ),
        Field("low", "number", "lower end of a uniform draw", default=ABSENT, variants=("sample",)),
        Field(
            "high",
            "number",
            "upper end of a uniform draw (> low)",
            default=ABSENT,
            variants=("sample",),
        ),
        Field("mean", "number", "mean of a normal draw", default=ABSENT, variants=("sample",)),
        Field(
            "std",
            "number",
            "standard deviation of a normal draw",
            default=ABSENT,
            positive=True,
            variants=("sample",),
        ),
        Field(
            "median",
            "number",
            "median of a lognormal draw",
            default=ABSENT,
            positive=True,
            variants=("sample",),
        ),
        Field(
            "sigma",
            "number",
            "standard deviation of the logarithm of a lognormal draw",
            default=ABSENT,
            positive=True,
            variants=("sample",),
        ),
    ),
    array=True,
    selector="how",
)
"""One ``[[axes]]`` entry of a sweep file."""


_RULES = """\
Units are those of the scene fields an axis addresses (mm, MPa, N, N mm,
degrees). Every point is the base scene with the axes' values written in,
loaded through the scene loader, so every scene check applies: a listed value
that makes an invalid scene stops the sweep before anything runs (naming the
point and the field); a random draw that does is recorded as an invalid point.
A field no table declares is refused, naming it and the fields expected.
"""


def field_reference(level: int = 2) -> str:
    """The sweep file reference: every field of :data:`SWEEP` and :data:`AXES`, as Markdown.

    Parameters
    ----------
    level : int
        Heading level of each table's section.

    Returns
    -------
    str
        The rules, then one section per table with its fields (kind, unit,
        default, allowed values, description).
    """
    h = "#" * level
    return "\n\n".join(
        [
            _RULES,
            f"{h} Top level {{#sweep-top}}",
            SWEEP.description,
            markdown_table(SWEEP),
            f"{h} `[[axes]]` {{#sweep-axes}}",
            AXES.description,
            markdown_table(AXES),
        ]
    )
