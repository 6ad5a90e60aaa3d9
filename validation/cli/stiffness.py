"""``flexval stiffness``: its arguments and what it does."""

from __future__ import annotations

import argparse
import sys

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    write_json,
)
from ..report.tables import Column, sig, text_table
from .common import (
    EXIT_OK,
    EXIT_SOLVER,
    ParserContext,
    analysis_inputs,
    scene_and_model,
)


def run(args: argparse.Namespace) -> int:
    """``flexval stiffness``: the 3 x 3 stiffness and compliance at the target, at rest
    or under a load.

    Returns the exit code.
    """
    from flexval.reducedmodels import SolverError

    from ..studies.stiffness import MOTIONS, run_stiffness, stiffness_record

    scene, spec, json_path, _ = analysis_inputs(args)
    if args.at is not None and args.load_case is None:
        raise SceneError(COMMAND_LINE, "--at", args.at, "needs --load-case (the preload)")
    case = scene.load_case(args.load_case) if args.load_case else None
    fraction = 0.0 if case is None else (1.0 if args.at is None else args.at)
    try:
        _, found, linear = run_stiffness(scene, spec, case, fraction)
    except SolverError as exc:
        print(f"flexval: solver failure: {exc}", file=sys.stderr)
        return EXIT_SOLVER
    where = "at rest" if case is None or fraction == 0.0 else f"at {fraction:g} of {case.name}"
    if linear and case is not None and fraction > 0.0:
        where = f"at rest ({spec.id} is linear: the same at every load)"
    body = scene.mechanism.target_body
    x, y = found.point.tolist()
    print(f"{spec.id}: stiffness of body {body} at its target point ({x:.4f}, {y:.4f}) mm, {where}")
    labels = ("Fx N", "Fy N", "M N mm")
    if found.stiffness is not None:
        columns = [Column("", "<")] + [Column(f"{m}") for m in ("dx mm", "dy mm", "rot rad")]
        rows = [[label, *(sig(v, 6) for v in row)] for label, row in zip(labels, found.stiffness)]
        for line in text_table(columns, rows, "  "):
            print(line)
    else:
        directions = "; ".join(
            "(" + ", ".join(f"{m} {sig(v, 4)}" for m, v in zip(MOTIONS, row)) + ")"
            for row in found.rigid
        )
        print(
            f"no finite stiffness: {spec.id} is rigid at the target along {directions} "
            "(its compliance has zero directions there)"
        )
    print("compliance")
    columns = [Column("", "<")] + [Column(f"{m}") for m in ("Fx N", "Fy N", "M N mm")]
    rows = [
        [f"{m} {u}", *(sig(v, 6) for v in row)]
        for m, u, row in zip(MOTIONS, ("mm", "mm", "rad"), found.compliance)
    ]
    for line in text_table(columns, rows, "  "):
        print(line)
    if found.stable is False:
        print("note: the state is unstable (the tangent has a negative eigenvalue)")
    if json_path:
        write_json(json_path, stiffness_record(scene, spec, case, fraction, found))
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval stiffness``, its arguments and options."""
    ids = context.ids
    scene_help = context.scene_help
    q = sub.add_parser(
        "stiffness",
        help="the 3 x 3 stiffness and compliance at the target, at rest or under a load",
    )
    scene_and_model(q, scene_help, ids)
    q.add_argument(
        "--load-case", metavar="NAME", help="load case of the preload (default: none, at rest)"
    )
    q.add_argument(
        "--at",
        type=float,
        default=None,
        metavar="FRACTION",
        help="about the equilibrium at this fraction of the load case, 0 (at rest) to 1 "
        "(default: 1 with --load-case)",
    )
    q.add_argument("--json", metavar="PATH", help="write the matrices, their units and where")
    q.set_defaults(func=run, plot=None)
