"""``flexval compare``: its arguments and what it does."""

from __future__ import annotations

import argparse
import sys

from flexval.geometry import SceneError, load_scene
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_figure_file,
    check_file,
    write_json,
)
from .common import (
    EXIT_OK,
    EXIT_SOLVER,
    ParserContext,
    check_memory,
    keep_cached,
    parse_models,
)


def run(args: argparse.Namespace) -> int:
    """``flexval compare``: models against a measured load-displacement file
    (:mod:`flexval.validation.studies.measuredcompare`); exit 3 when a model's path stops before
    the largest measured load (the JSON and the plot are written all the same)."""
    from flexval.geometry.measured import read_measurement

    from ..cache import ResultCache
    from ..report.measured import plot, text_lines
    from ..studies.measuredcompare import compare_measurement, traced_case

    json_path = check_file(args.json, "--json") if args.json is not None else None
    plot_path = check_figure_file(args.plot, "--plot") if args.plot is not None else None
    scene = load_scene(args.scene)
    case = scene.load_case(args.load_case)
    measurement = read_measurement(args.measured, case)
    specs = parse_models(args.model or [], COMMAND_LINE, "--model")
    if not specs:
        specs = parse_models(scene.models, scene.source, "request.models")
    if not specs:
        raise SceneError(
            scene.source, "--model", None, "no model requested (give --model or request.models)"
        )
    levels = len(traced_case(case, measurement)[0].at)
    check_memory(
        [(scene.mechanism, spec, levels) for spec in specs],
        *((COMMAND_LINE, "--model") if args.model else (scene.source, "request.models")),
    )
    cache = ResultCache(enabled=not args.no_cache)
    keep_cached(cache.enabled)
    comparison = compare_measurement(scene, measurement, specs, cache if cache.enabled else None)
    print("\n".join(text_lines(comparison)))
    if json_path:
        write_json(json_path, comparison.record())
    if plot_path:
        plot(comparison, plot_path)
        print(f"wrote {plot_path}")
    for s in comparison.stopped():
        print(f"flexval: solver failure: {s.model}: {comparison.beyond_text(s)}", file=sys.stderr)
    return EXIT_SOLVER if comparison.stopped() else EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval compare``, its arguments and options."""
    ids = context.ids
    scene_help = context.scene_help
    q = sub.add_parser(
        "compare",
        help="compare models with a measured load-displacement file (a test rig's CSV)",
        description="Trace each model through the measured loads of a CSV file (columns "
        "load, in the load case's unit N or N mm; dx, dy in mm and rotation in deg, any of "
        "them; optional <column>_std standard uncertainties) and score it: RMS and largest "
        "difference in percent of the measured range, and the share of points within twice "
        "the standard uncertainty. Measured loads beyond a model's path (a limit point) are "
        "reported, not scored; exit 3 then.",
    )
    q.add_argument("scene", help=scene_help)
    q.add_argument("--measured", required=True, metavar="FILE", help="the measured CSV file")
    q.add_argument(
        "--load-case", required=True, metavar="NAME", help="the load case the file measures"
    )
    q.add_argument(
        "--model",
        action="append",
        metavar="MODEL",
        help=f"model id: {ids} (repeatable; default: the scene's request.models)",
    )
    q.add_argument(
        "--json", metavar="PATH", help="write the scores, the values and the paths as JSON"
    )
    q.add_argument("--plot", metavar="FILE.png", help="draw the measurement against every model")
    q.add_argument(
        "--no-cache",
        action="store_true",
        help="recompute every path (default: reuse and store them in the result cache)",
    )
    q.set_defaults(func=run)
