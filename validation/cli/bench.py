"""``flexval bench``: its arguments and what it does."""

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
    EXIT_SOLVER,
    NO_BATCH_HELP,
    ParserContext,
    campaign_options,
    chosen_cases,
    keep_cached,
    load_case_option,
    parse_models,
)


def run(args: argparse.Namespace) -> int:
    """``flexval bench``: runtime-versus-error study of every model on a scene.

    Returns the exit code.
    """
    from ..cache import ResultCache
    from ..studies.batchtiming import BatchMemo
    from ..studies.bench import runtime_vs_error, sweep_specs, write_bench

    scene = chosen_cases(load_scene(args.scene), args)
    (ref,) = parse_models([args.reference], COMMAND_LINE, "--reference")
    out = check_folder(args.out, "--out")
    keep_cached(not args.no_cache)
    cache = ResultCache(enabled=not args.no_cache)
    rows, failures = runtime_vs_error(
        scene,
        ref,
        sweep_specs(ref),
        args.repeats,
        cache,
        not args.quiet,
        batches=BatchMemo(args.repeats, cache, enabled=not args.no_batch),
    )
    for f in failures:
        print(f"flexval: {f.model} on {f.load_case} {f.summary()}: {f.message}", file=sys.stderr)
    md = write_bench(scene, rows, ref.id, out, failures)
    print(md.read_text(encoding="utf-8"))
    stopped = sorted({f.load_case for f in failures if f.model == ref.id})
    for case in stopped:  # every file is written; nothing to compare on these cases
        print(
            f"flexval: solver failure: the reference {ref.id} stopped before the full load on "
            f"load case {case}",
            file=sys.stderr,
        )
    return EXIT_SOLVER if stopped else EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval bench``, its arguments and options."""
    scene_help = context.scene_help
    q = sub.add_parser("bench", help="runtime-versus-error study of every model on a scene")
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--reference",
        default="continuum",
        metavar="MODEL",
        help="reference model (default: continuum at its default level)",
    )
    q.add_argument("--out", default="reports/bench", metavar="DIR", help="output folder")
    campaign_options(q)
    load_case_option(q)
    q.add_argument("--no-batch", action="store_true", help=NO_BATCH_HELP)
    q.set_defaults(func=run)
