"""``flexval stress``: its arguments and what it does."""

from __future__ import annotations

import argparse
import sys

from flexval.geometry import load_scene
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_folder,
)
from .common import (
    EXIT_OK,
    ParserContext,
    check_memory,
    chosen_cases,
    load_case_option,
    parse_models,
)


def run(args: argparse.Namespace) -> int:
    """``flexval stress``: stress tests: load amplification, step count, invariance.

    Returns the exit code.
    """
    from ..studies.stress import stress_report, write_stress

    scene = chosen_cases(load_scene(args.scene), args)
    models = args.model or ["ee", "dcmm:1", "dcmm:2", "prbm", "beam:20"]
    specs = parse_models(models, COMMAND_LINE, "--model")
    from ..studies.stress import AMPLIFICATIONS, STEP_COUNTS

    counts = [n for n in STEP_COUNTS if not args.quick or n < 1001]
    check_memory(  # every case: each amplification at 11 levels, then each step count
        [
            (scene.mechanism, spec, n)
            for spec in specs
            for _ in scene.load_cases
            for n in [11] * len(AMPLIFICATIONS) + counts
        ],
        COMMAND_LINE,
        "--model",
    )
    out = check_folder(args.out, "--out")

    def progress(line: str) -> None:
        if not args.quiet:
            print(line, file=sys.stderr, flush=True)

    report = stress_report(scene, specs, quick=args.quick, progress=progress)
    md, _ = write_stress(report, out)
    print(md.read_text(encoding="utf-8"))
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval stress``, its arguments and options."""
    scene_help = context.scene_help
    q = sub.add_parser("stress", help="stress tests: load amplification, step count, invariance")
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--model",
        action="append",
        metavar="MODEL",
        help="models to stress (repeatable; default: ee, dcmm:1, dcmm:2, prbm, beam:20)",
    )
    q.add_argument(
        "--quick",
        action="store_true",
        help="small study: loads up to x100, beam:40 reference, no 1001-level run",
    )
    q.add_argument("--out", default="reports/stress", metavar="DIR", help="output folder")
    q.add_argument("--quiet", action="store_true", help="no progress lines")
    load_case_option(q)
    q.set_defaults(func=run)
