"""``flexval info``: its arguments and what it does."""

from __future__ import annotations

import argparse

from flexval.geometry import load_scene

from ..outputs import (
    check_file,
    write_json,
)
from .common import (
    EXIT_OK,
    ParserContext,
)


def run(args: argparse.Namespace) -> int:
    """``flexval info``: describe a scene: bodies, flexures, ellipse data, loads.

    Returns the exit code.
    """
    from .sceneinfo import format_info, scene_info

    json_path = check_file(args.json, "--json") if args.json is not None else None
    info = scene_info(load_scene(args.scene))
    print(format_info(info))
    if json_path:
        write_json(json_path, info)
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval info``, its arguments and options."""
    scene_help = context.scene_help
    q = sub.add_parser("info", help="describe a scene: bodies, flexures, ellipse data, loads")
    q.add_argument("scene", help=scene_help)
    q.add_argument("--json", metavar="PATH", help="also write the description as JSON")
    q.set_defaults(func=run)
