"""``flexval converge``: its arguments and what it does."""

from __future__ import annotations

import argparse
import sys

from flexval.geometry import SceneError, load_scene
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_file,
    write_json,
)
from .common import (
    EXIT_OK,
    EXIT_SOLVER,
    ParserContext,
    check_memory,
    parse_models,
)


def _parse_levels(text: str, spec) -> list[int]:
    """The resolutions of a study of ``spec``'s family: ``LO:HI`` is the family's series
    (``0:4`` -> 0, 1, 2, 3, 4 for mesh levels; ``20:320`` -> 20, 40, ..., 320 for doubling
    N); a comma list is taken as is."""
    res = spec.model_family.resolution
    try:
        vals = [int(x) for x in text.split(":" if ":" in text else ",")]
    except ValueError:
        raise SceneError(
            COMMAND_LINE, "--levels", text, "expected LO:HI or a comma-separated list of integers"
        ) from None
    if ":" in text and len(vals) != 2:
        raise SceneError(COMMAND_LINE, "--levels", text, "expected LO:HI")
    # range first: the series is built only from checked ends (a doubling from 0 never ends)
    if not vals or vals != sorted(set(vals)) or not res.low <= min(vals) <= max(vals) <= res.high:
        raise SceneError(
            COMMAND_LINE,
            "--levels",
            text,
            f"resolutions must increase, within {res.low}..{res.high} for the "
            f"{res.name} of '{spec.family}' ({res.meaning})",
        )
    series = res.series(*vals) if ":" in text else vals
    if len(series) < 2:
        raise SceneError(
            COMMAND_LINE,
            "--levels",
            text,
            f"gives the single resolution {series[0]}: a study compares at least "
            f"two (three for the order and the Richardson value)",
        )
    return series


def run(args: argparse.Namespace) -> int:
    """``flexval converge``: resolution study: order, Richardson value, GCI.

    Returns the exit code.
    """
    from flexval.reducedmodels.catalogue import families

    from ..studies.convergence import format_study, study

    (spec,) = parse_models([args.model], COMMAND_LINE, "--model")
    res = spec.model_family.resolution
    if res is None:
        refinable = [f.name for f in families() if f.resolution is not None]
        raise SceneError(
            COMMAND_LINE,
            "--model",
            args.model,
            f"convergence studies need a model with a resolution: {refinable}",
        )
    resolutions = _parse_levels(args.levels or "{}:{}".format(*res.study), spec)
    json_path = check_file(args.json, "--json") if args.json is not None else None
    scene = load_scene(args.scene)
    cases = [scene.load_case(n) for n in args.load_case] if args.load_case else scene.load_cases
    check_memory(
        [(scene.mechanism, spec.with_resolution(r), None) for r in resolutions for _ in cases],
        COMMAND_LINE,
        "--levels" if args.levels else "--model",
    )
    out, status = [], EXIT_OK
    for case in cases:
        st = study(scene, spec, resolutions, case)
        for f in st.failures:
            print(f"flexval: solver failure: {f.message}", file=sys.stderr)
            status = EXIT_SOLVER
        print(format_study(st) + "\n")
        out.append(
            {
                "family": st.family,
                "load_case": st.load_case,
                "ratio": st.ratio,
                "rows": st.rows,
                "summary": st.summary,
                "failures": [f.to_dict() for f in st.failures],
            }
        )
    if json_path:
        write_json(json_path, {"scene": scene.name, "studies": out})
    return status


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval converge``, its arguments and options."""
    refine = context.refine
    defaults = context.defaults
    scene_help = context.scene_help
    q = sub.add_parser("converge", help="resolution study: order, Richardson value, GCI")
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--model",
        default="continuum",
        metavar="MODEL",
        help="model to refine, a family with a resolution and any options, e.g. "
        f"beam[shear] ({refine}; default: continuum)",
    )
    q.add_argument(
        "--levels",
        metavar="LO:HI",
        help="mesh levels LO..HI, or N from LO doubling up to HI; or a comma list "
        f"(defaults: {defaults})",
    )
    q.add_argument(
        "--load-case",
        action="append",
        metavar="NAME",
        help="load case name (repeatable; default: all)",
    )
    q.add_argument("--json", metavar="PATH", help="write the studies as JSON")
    q.set_defaults(func=run)
