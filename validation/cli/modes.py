"""``flexval modes``: its arguments and what it does."""

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
    """``flexval modes``: natural frequencies and mode shapes about an equilibrium.

    Returns the exit code.
    """
    from flexval.reducedmodels import SolverError

    from ..studies.modes import choose_density, modes_record, plot_modes, run_modes

    scene, spec, json_path, plot_path = analysis_inputs(args)
    scene, density = choose_density(scene, args.density, what="a modal analysis")
    case = (
        scene.load_case(args.load_case)
        if args.load_case
        else (scene.load_cases[0] if args.at > 0.0 else None)
    )
    massless = scene.mechanism.inertia.massless_bodies(scene.mechanism.moving_bodies)
    if massless:
        print(f"note: bodies without mass data (massless): {', '.join(massless)}")
    try:
        system, modes = run_modes(scene, spec, case, args.at, args.count)
    except SolverError as exc:
        print(f"flexval: solver failure: {exc}", file=sys.stderr)
        return EXIT_SOLVER
    where = "at rest" if case is None or args.at == 0.0 else f"at {args.at:g} of {case.name}"
    print(f"{spec.id}: natural frequencies {where}, with {density.describe()}")
    rows = [
        [str(k), sig(f, 6), "unstable" if f < 0.0 else ""]
        for k, f in enumerate(modes.frequencies_hz, 1)
    ]
    for line in text_table([Column("mode"), Column("f Hz"), Column("", "<")], rows, "  "):
        print(line)
    record = modes_record(scene, spec, case, args.at, system, modes, density)
    if json_path:
        write_json(json_path, record)
    if plot_path:
        plot_modes(system, modes, plot_path, f"{scene.name} {spec.id} {where}")
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval modes``, its arguments and options."""
    ids = context.ids
    scene_help = context.scene_help
    q = sub.add_parser("modes", help="natural frequencies and mode shapes about an equilibrium")
    scene_and_model(q, scene_help, ids)
    q.add_argument(
        "--at",
        type=float,
        default=0.0,
        metavar="FRACTION",
        help="load level as a fraction of the load case, 0 (unloaded; with gravity "
        "if the scene has it) to 1 (default 0)",
    )
    q.add_argument(
        "--load-case", metavar="NAME", help="load case for --at (default: the scene's first)"
    )
    q.add_argument(
        "--count",
        type=int,
        default=6,
        metavar="K",
        help="number of modes, lowest first (default 6)",
    )
    q.add_argument(
        "--json", metavar="PATH", help="write frequencies_hz, eigenvalues and mode shapes as JSON"
    )
    q.add_argument("--plot", metavar="FILE.png", help="draw the mode shapes")
    q.add_argument(
        "--density",
        type=float,
        metavar="RHO",
        help="flexure density in t/mm^3 instead of the scene's material.density "
        "(PLA: 1.24e-9), e.g. for the built-in scenes, whose links are then "
        "massless and carry the flexure pieces each model lumps on them",
    )
    q.set_defaults(func=run)
