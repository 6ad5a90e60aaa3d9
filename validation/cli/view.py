"""``flexval view``: its arguments and what it does."""

from __future__ import annotations

import argparse

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_file,
)
from .common import (
    EXIT_OK,
    ParserContext,
)


def run(args: argparse.Namespace) -> int:
    """``flexval view``: show a time series of run --vtu (or a .vtu) in a PyVista
    window, or render one level to a PNG.

    Returns the exit code.
    """
    from ..view import check_level, has_display, read_levels, screenshot, show

    png = None
    if args.screenshot is not None:
        png = check_file(args.screenshot, "--screenshot")
        if png.suffix.lower() != ".png":
            raise SceneError(COMMAND_LINE, "--screenshot", args.screenshot, "must end in .png")
    elif not has_display():
        raise SceneError(
            COMMAND_LINE,
            "--screenshot",
            None,
            "no display here (DISPLAY and WAYLAND_DISPLAY unset): give --screenshot "
            "FILE.png to render off-screen, or open the result in ParaView",
        )
    levels = read_levels(args.result)
    level = check_level(levels, args.level)
    if png is None:
        show(levels, level, args.field)
    else:
        print(f"wrote {screenshot(levels, level, args.field, png)}")
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval view``, its arguments and options."""
    from ..view import FIELDS as VIEW_FIELDS

    q = sub.add_parser(
        "view",
        help="show a time series of run --vtu (or a .vtu) in a PyVista window, or render "
        "one level to a PNG",
    )
    q.add_argument("result", metavar="RESULT", help="a .pvd series of run --vtu, or a .vtu file")
    q.add_argument(
        "--level", type=int, default=-1, metavar="K", help="level to show (default -1: the last)"
    )
    q.add_argument(
        "--field",
        choices=VIEW_FIELDS,
        default="fibre_stress",
        help="colour by this point data (default fibre_stress, MPa)",
    )
    q.add_argument(
        "--screenshot",
        metavar="FILE.png",
        help="render off-screen to this PNG instead of opening a window (no display needed)",
    )
    q.set_defaults(func=run)
