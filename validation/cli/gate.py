"""``flexval gate``: its arguments and what it does."""

from __future__ import annotations

import argparse
import sys

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_file,
    check_folder,
    distinct_files,
    write_json,
)
from ..report.tables import Column, sig, text_table
from .common import (
    EXIT_OK,
    EXIT_SOLVER,
    MAX_LOCAL_WORKERS,
    ParserContext,
    check_memory,
    int_in,
    keep_cached,
)

EXIT_GATE_FAILED = 1
"""``flexval gate``: a gate does not hold."""


def run(args: argparse.Namespace) -> int:
    """``flexval gate``: accuracy gates for CI: exit 1 when a model's error exceeds its threshold.

    Returns the exit code.
    """
    from flexval.reducedmodels import PluginFailure

    from ..cache import ResultCache
    from ..studies.campaign import available_cores
    from ..studies.gate import ReferenceFailure, evaluate, prepare, summary_record
    from ..studies.gatefile import load_gates

    json_path = check_file(args.json, "--json") if args.json is not None else None
    junit_path = check_file(args.junit, "--junit") if args.junit is not None else None
    distinct_files(("--json", json_path), ("--junit", junit_path))
    if args.prepare and (json_path or junit_path):
        option = "--json" if json_path else "--junit"
        raise SceneError(
            COMMAND_LINE, option, args.json or args.junit, "--prepare writes no verdict"
        )
    root = check_folder(args.cache, "--cache") if args.cache is not None else None
    gates = load_gates(args.gates)
    specs = [gates.reference] + [g.model for g in gates.gates]
    workers = args.workers or available_cores()
    check_memory(
        [(s.mechanism, spec, None) for spec in specs for s in gates.scenes],
        gates.source,
        "gates",
        parallel=workers,
        quiet=args.quiet,
    )
    cache = ResultCache(root=root)
    keep_cached(cache.enabled)
    if args.prepare:
        done, failed = prepare(gates, cache, workers, not args.quiet)
        print(f"{done} results in the result cache {cache.root}")
        for line in failed:
            print(f"flexval: solver failure: {line}", file=sys.stderr)
        return EXIT_SOLVER if failed else EXIT_OK
    try:
        checks = evaluate(gates, cache, workers, not args.quiet)
    except (ReferenceFailure, PluginFailure) as exc:
        print(f"flexval: solver failure: {exc}", file=sys.stderr)
        return EXIT_SOLVER
    rows = [
        [
            c.model,
            c.scene,
            c.case,
            c.metric,
            sig(c.value),
            sig(c.threshold),
            "pass" if c.passed else "FAIL",
        ]
        for c in checks
    ]
    columns = [
        Column("model", "<"),
        Column("scene", "<"),
        Column("case", "<"),
        Column("metric", "<"),
        Column("error %"),
        Column("threshold %"),
        Column("verdict", "<"),
    ]
    print(f"errors against {gates.reference.id} (percent)")
    print("\n".join(text_table(columns, rows)))
    failed = [c for c in checks if not c.passed]
    for c in checks:
        if c.detail:
            print(f"{c.model} {c.scene} {c.case} {c.metric}: {c.detail}")
        if c.reason and not c.passed and c.reason != c.detail:
            print(f"{c.model} {c.scene} {c.case}: {c.reason}")
    print(f"{len(checks)} checks: {len(checks) - len(failed)} passed, {len(failed)} failed")
    if json_path:
        write_json(json_path, summary_record(gates, checks))
    if junit_path:
        from ..studies.junit import write_junit

        write_junit(junit_path, checks, gates.reference.id)
    return EXIT_GATE_FAILED if failed else EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval gate``, its arguments and options."""
    q = sub.add_parser(
        "gate",
        help="accuracy gates for CI: exit 1 when a model's error exceeds its threshold",
    )
    q.add_argument("gates", metavar="GATES.toml", help="gates file (see the gates file reference)")
    q.add_argument("--junit", metavar="PATH", help="also write the checks as JUnit XML")
    q.add_argument("--json", metavar="PATH", help="also write the checks as JSON")
    q.add_argument(
        "--cache",
        metavar="DIR",
        help="result cache folder kept between CI runs (default: $FLEXVAL_CACHE, else "
        "~/.cache/flexval)",
    )
    q.add_argument(
        "--prepare",
        action="store_true",
        help="only compute the results into the cache (paths, critical loads, natural "
        "frequencies; the reference's and the built-in models'); no verdict",
    )
    q.add_argument(
        "--workers",
        type=int_in(1, MAX_LOCAL_WORKERS),
        metavar="N",
        help=f"processes computing paths, 1 to {MAX_LOCAL_WORKERS} (default: one per core)",
    )
    q.add_argument("--quiet", action="store_true", help="no progress bar")
    q.set_defaults(func=run)
