"""``flexval buckle``: its arguments and what it does."""

from __future__ import annotations

import argparse
import sys

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
    """``flexval buckle``: linearised buckling: critical loads and modes of a load case,
    beside its path.

    Returns the exit code.
    """
    from flexval.reducedmodels import SolverError

    from ..studies.buckle import buckle_record, linearisation_holds, path_stop, run_buckle
    from ..studies.modes import plot_modes

    scene, spec, json_path, plot_path = analysis_inputs(args)
    case = scene.load_case(args.load_case) if args.load_case else scene.load_cases[0]
    try:
        system, found = run_buckle(scene, spec, case, args.at, args.count)
    except SolverError as exc:
        print(f"flexval: solver failure: {exc}", file=sys.stderr)
        return EXIT_SOLVER
    where = "at rest" if args.at == 0.0 else f"about {args.at:g} of the load"
    print(f"{spec.id}, load case {case.name}: linearised buckling {where}")
    rows = [
        [str(k), sig(f, 6), sig(f * case.magnitude, 6)]
        for k, f in enumerate(found.factors.tolist(), 1)
    ]
    columns = [Column("mode"), Column("factor"), Column(f"load {case.unit}")]
    for line in text_table(columns, rows, "  "):
        print(line)
    if not rows:
        print("no critical load: the load case does not destabilise this model")
    stop = path_stop(scene, spec, case)
    if stop["kind"] == "bifurcation":
        print(f"load control: bifurcation at {sig(stop['load'], 6)} {case.unit}")
    elif stop["kind"] == "failure":
        print(f"load control: stops at {sig(stop['load'], 6)} {case.unit} ({stop['reason']})")
    else:
        print(f"load control: stable up to the full load {sig(case.magnitude, 6)} {case.unit}")
    if rows and not linearisation_holds(found, stop, case):
        print(
            "note: load control passes the lowest critical load without a bifurcation: the "
            "deformation before it is too large for the linearisation about this state; "
            "trust the path"
        )
    if json_path:
        write_json(json_path, buckle_record(scene, spec, case, system, found, stop))
    if plot_path and rows:
        from flexval.reducedmodels.analyses.modes import Modes

        shapes = Modes(found.factors, found.shapes, found.state)
        labels = [
            f"mode {k}: {sig(f * case.magnitude, 4)} {case.unit}"
            for k, f in enumerate(found.factors.tolist(), 1)
        ]
        plot_modes(system, shapes, plot_path, f"{scene.name} {spec.id} {where}", labels)
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval buckle``, its arguments and options."""
    ids = context.ids
    scene_help = context.scene_help
    q = sub.add_parser(
        "buckle",
        help="linearised buckling: critical loads and modes of a load case, beside its path",
    )
    scene_and_model(q, scene_help, ids)
    q.add_argument("--load-case", metavar="NAME", help="load case (default: the scene's first)")
    q.add_argument(
        "--count", type=int, default=3, metavar="K", help="critical loads, lowest first (default 3)"
    )
    q.add_argument(
        "--at",
        type=float,
        default=0.0,
        metavar="FRACTION",
        help="linearise about the equilibrium at this fraction of the load case (a preload), "
        "0 (at rest, the classical linear buckling analysis) up to 1 (default 0)",
    )
    q.add_argument(
        "--json",
        metavar="PATH",
        help="write the critical loads and factors, the mode shapes and where load control "
        "stops as JSON",
    )
    q.add_argument("--plot", metavar="FILE.png", help="draw the buckling modes")
    q.set_defaults(func=run)
