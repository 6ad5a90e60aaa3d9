"""``flexval plot``: its arguments and what it does."""

from __future__ import annotations

import argparse

from flexval.geometry import load_scene

from ..outputs import (
    check_figure_file,
)
from .common import (
    EXIT_OK,
    ParserContext,
)


def run(args: argparse.Namespace) -> int:
    """``flexval plot``: draw the undeformed mechanism to a PNG; returns the exit code."""
    from ..report.drawing import plot_mechanism

    output = check_figure_file(args.output, "--output")
    scene = load_scene(args.scene)
    plot_mechanism(scene, output)
    print(f"wrote {output}")
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval plot``, its arguments and options."""
    scene_help = context.scene_help
    q = sub.add_parser("plot", help="draw the undeformed mechanism to a PNG")
    q.add_argument("scene", help=scene_help)
    q.add_argument("-o", "--output", required=True, metavar="FILE.png", help="output PNG")
    q.set_defaults(func=run)
