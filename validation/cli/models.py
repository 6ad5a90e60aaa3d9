"""``flexval models``: its arguments and what it does."""

from __future__ import annotations

import argparse

from ..outputs import (
    check_file,
    write_json,
)
from .common import (
    EXIT_OK,
    ParserContext,
)


def run(args: argparse.Namespace) -> int:
    """``flexval models``: list the model families: id syntax, resolutions, options, capabilities.

    Returns the exit code.
    """
    from flexval.reducedmodels.catalogue import load_plugins

    from .modelinfo import catalogue_record, format_models

    json_path = check_file(args.json, "--json") if args.json is not None else None
    load_plugins()
    print(format_models())
    if json_path:
        write_json(json_path, catalogue_record())
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval models``, its arguments and options."""
    q = sub.add_parser(
        "models",
        help="list the model families: id syntax, resolutions, options, capabilities",
    )
    q.add_argument("--json", metavar="PATH", help="also write the listing as JSON")
    q.set_defaults(func=run)
