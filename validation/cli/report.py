"""``flexval report``: its arguments and what it does."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from flexval.geometry import load_scene
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_folder,
)
from .common import (
    EXIT_OK,
    EXIT_SOLVER,
    MAX_LOCAL_WORKERS,
    NO_BATCH_HELP,
    ParserContext,
    campaign_options,
    check_memory,
    chosen_cases,
    int_in,
    keep_cached,
    load_case_option,
    parse_models,
)


def _check_report_memory(scenes: list[str], specs: list, args: argparse.Namespace) -> None:
    """:func:`check_memory` of every path the report traces: each model on each scene and
    load case, and the convergence study of its reference family (the resolutions up to one
    above the reference's; :data:`flexval.validation.report.data.DEFAULT_MODELS`)."""
    from flexval.reducedmodels.catalogue import REFERENCE

    from ..report.data import convergence_specs

    paths = []
    for name in scenes:
        scene = load_scene(name)
        reference = next((s for s in specs if s.model_family.has(REFERENCE)), None)
        if not args.no_converge and reference is not None and reference.resolution is not None:
            paths += [(scene.mechanism, s, None) for s in convergence_specs(reference)]
        paths += [(scene.mechanism, s, None) for s in specs for _ in scene.load_cases]
    check_memory(paths, COMMAND_LINE, "--model", parallel=args.jobs or 1, quiet=args.quiet)


def run(args: argparse.Namespace) -> int:
    """``flexval report``: build the validation report (Markdown, PNG, JSON).

    Returns the exit code.
    """
    from flexval.geometry.scene import PAPER_SCENES

    from ..report.data import compute_report
    from ..report.folder import default_report_folder, other_report
    from ..report.writer import DEFAULT_MODELS, write_report

    scenes = args.scene or list(PAPER_SCENES)
    names = []
    for name in scenes:
        scene = load_scene(name)
        chosen_cases(scene, args)  # bad input fails before any work
        names.append(scene.name)
    models = args.model or list(DEFAULT_MODELS)
    specs = parse_models(models, COMMAND_LINE, "--model")
    _check_report_memory(scenes, specs, args)
    out_arg = args.out if args.out is not None else default_report_folder(names)
    other_report(out_arg, names, args.force)
    out = check_folder(out_arg, "--out")  # created only once the rest is known good
    timings = check_folder(args.timings, "--timings") if args.timings is not None else None
    keep_cached(not args.no_cache, f"; the files written in {out} are whole")
    data = compute_report(
        scenes,
        models,
        args.repeats,
        not args.no_cache,
        not args.quiet,
        not args.no_bench,
        not args.no_converge,
        args.jobs,
        args.peers,
        not args.no_batch,
        load_cases=args.load_case,
    )
    path = write_report(
        data,
        out,
        Path(args.protocol) if args.protocol else None,
        Path(args.threed) if args.threed else None,
        timings,
    )
    print(f"wrote {path}" + (f" (run times in {timings})" if timings is not None else ""))
    unfinished = _unfinished_cases(data)
    for line in unfinished:
        print(f"flexval: solver failure: {line}", file=sys.stderr)
    return EXIT_SOLVER if unfinished else EXIT_OK


def _unfinished_cases(data) -> list[str]:
    """The report's (scene, load case) pairs with nothing to compare: the reference stopped
    before the full load, or every model did. Every file is written all the same; the
    command then exits 3."""
    lines = []
    for r in data.scenes:
        for case in r.cases:
            finished = [m for m in r.models if r.converged(m, case) is not None]
            if not finished:
                lines.append(f"{r.scene.name}, load case {case}: no model reached the full load")
            elif r.reference and r.reference not in finished:
                lines.append(
                    f"{r.scene.name}, load case {case}: the reference {r.reference} stopped "
                    "before the full load (the report says where and why)"
                )
    return lines


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval report``, its arguments and options."""
    scene_help = context.scene_help
    q = sub.add_parser("report", help="build the validation report (Markdown, PNG, JSON)")
    q.add_argument("scene", nargs="*", help=f"{scene_help} (default: both built-in scenes)")
    q.add_argument(
        "--out",
        metavar="DIR",
        help="output folder (default: SCENE_report in the current folder, the scenes' "
        "names joined by '+', paper_report for the paper's scenes); a folder holding "
        "another scene's report is refused without --force",
    )
    q.add_argument(
        "--force",
        action="store_true",
        help="write into --out even where it holds the report of other scenes",
    )
    q.add_argument(
        "--timings",
        metavar="DIR",
        help="write the run times (timings.md, timings.json, bench_SCENE.*) into DIR "
        "instead of beside report.md, whose results are the same from run to run while "
        "its run times are not (a repository that commits its report keeps them apart)",
    )
    q.add_argument(
        "--model",
        action="append",
        metavar="MODEL",
        help="models to compare (repeatable; default: continuum, beam:100, beam:20, "
        "prbm, dcmm:1, dcmm:2, dcmm:3, ee)",
    )
    campaign_options(q)
    load_case_option(q)
    q.add_argument("--no-bench", action="store_true", help="skip the runtime-vs-error study")
    q.add_argument("--no-converge", action="store_true", help="skip the mesh convergence study")
    q.add_argument("--no-batch", action="store_true", help=NO_BATCH_HELP)
    q.add_argument(
        "--peers",
        action="store_true",
        help="also time beam:100 against OpenSeesPy on every load case, in the run "
        "times (optional extra [peers]; without it they say it is missing)",
    )
    q.add_argument(
        "--protocol",
        metavar="PATH",
        help="protocol.json of benchmarks/paper_protocol.py, summarised in the "
        "report's dynamics section (default: none; a missing or stale file is "
        "said so in the report, never an error)",
    )
    q.add_argument(
        "--threed",
        metavar="PATH",
        help="threed.json of benchmarks/threed_study.py, each paper scene's section "
        '"2D idealisation against 3D" (default: none; a missing or stale file is said '
        "so in the report, never an error)",
    )
    q.add_argument(
        "--jobs",
        type=int_in(1, MAX_LOCAL_WORKERS),
        default=MAX_LOCAL_WORKERS,
        metavar="N",
        help="processes computing the load paths and drawing the scenes, 1 to "
        f"{MAX_LOCAL_WORKERS} (default: one per core; results are the same, "
        "run times are measured N at a time)",
    )
    q.set_defaults(func=run)
