"""The ``flexval`` command line.

Exit codes: 0 success, 1 a gate of ``flexval gate`` does not hold, 2 bad input
(message on stderr, no traceback),
3 solver failure (message with the last converged load level), 4 an output
file could not be written although it was checked before the work (device
full, I/O error, folder removed meanwhile; the message names the file).

Every argument is checked before any work: numeric options against their
ranges, and every output path (``--json``, ``-o``, ``--out``, ``--out-dir``)
for writability (:mod:`flexval.validation.outputs`); such errors exit with 2.

Each command is one module of this package: its parser block (``add_parser``) beside
what it does (``run``); :func:`build_parser` declares them in :data:`COMMANDS` order.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from flexval.geometry import BUILTIN_SCENES, SceneError
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import OutputError
from . import (
    bench,
    buckle,
    compare,
    converge,
    gate,
    info,
    models,
    modes,
    plot,
    report,
    run,
    stiffness,
    stress,
    sweep,
    view,
)
from .common import (
    EXIT_INPUT,
    EXIT_OK,
    EXIT_OUTPUT,
    EXIT_SOLVER,
    MAX_LOCAL_WORKERS,
    MAX_REPEATS,
    ParserContext,
)

__all__ = [
    "EXIT_INPUT",
    "EXIT_OK",
    "EXIT_OUTPUT",
    "EXIT_SOLVER",
    "MAX_LOCAL_WORKERS",
    "MAX_REPEATS",
    "build_parser",
    "main",
]

COMMANDS = (
    info,
    models,
    plot,
    view,
    run,
    compare,
    modes,
    buckle,
    stiffness,
    converge,
    report,
    bench,
    stress,
    sweep,
    gate,
)
"""The commands, in the order ``flexval --help`` lists them."""


def build_parser() -> argparse.ArgumentParser:
    """The argparse parser of ``flexval`` (all sub-commands)."""
    p = argparse.ArgumentParser(
        prog="flexval",
        description="Validate flexibility models of planar compliant mechanisms "
        "(units: mm, N, N mm; angles in degrees on the command line and in files).",
    )
    from flexval import __version__

    p.add_argument("--version", action="version", version=f"flexval {__version__}")
    p.add_argument(
        "--blas-threads",
        metavar="N",
        help="threads of the BLAS/LAPACK pools (default: $FLEXVAL_BLAS_THREADS, else 1, "
        "which suits flexval's small banded systems; 0: leave them as the "
        "libraries set them up)",
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    from flexval.reducedmodels.catalogue import expected_ids, families

    ids = expected_ids()
    refine = ", ".join(
        f"{f.name}:{f.resolution.name} ({f.resolution.meaning})" for f in families() if f.resolution
    )
    defaults = ", ".join(
        "{} {}:{}".format(f.name, *f.resolution.study) for f in families() if f.resolution
    )
    scene_help = f"built-in scene name ({', '.join(BUILTIN_SCENES)}) or path to a scene TOML file"
    context = ParserContext(ids, refine, defaults, scene_help)
    for command in COMMANDS:
        command.add_parser(sub, context)
    return p


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one plain line on stderr (no source location): they are for the user."""
    print(f"flexval: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``flexval`` console script; returns the exit code.

    ``argv`` None (the console script, ``python -m flexval.validation.cli``): the
    arguments are the process's own, and so is the process: once the command
    is done, :func:`flexval.validation.process.end_process` ends it without the
    interpreter's teardown (a fifth of a small model's whole run), and a
    reader that closes the output pipe early only discards the rest of the
    output. Called from Python with a list of arguments, ``main`` returns.
    The console script also stops in order on SIGINT and SIGTERM
    (:mod:`flexval.validation.interrupt`): exit status 130 or 143.
    """
    if argv is None:
        from ..interrupt import install
        from ..process import discard_output_when_reader_leaves

        install()  # SIGINT/SIGTERM: orderly stop, exit 130/143 (flexval.validation.interrupt)
        discard_output_when_reader_leaves()
    try:
        args = build_parser().parse_args(argv)
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            status = _dispatch(args)
    except BaseException:
        from ..interrupt import finish, received

        if received() is None:
            raise
        finish(received())  # ends the process: 128 + the signal number
    if argv is None:
        from ..interrupt import finish, received, uninstall
        from ..process import end_process

        if received() is not None:  # a signal the handler held back (inside numba): it ends
            finish(received())
        uninstall()
        end_process(status)
    return status


def _dispatch(args: argparse.Namespace) -> int:
    """Run the chosen command; bad input, solver and output failures become exit codes."""
    from flexval.reducedmodels.core.threads import ENV_VARIABLE, RULE, request_threads

    try:
        try:
            request_threads(args.blas_threads)
        except ValueError:
            if args.blas_threads is not None:
                raise SceneError(COMMAND_LINE, "--blas-threads", args.blas_threads, RULE) from None
            raise SceneError(
                "<environment>", ENV_VARIABLE, os.environ[ENV_VARIABLE], RULE
            ) from None
        return args.func(args)
    except SceneError as exc:
        print(f"flexval: bad input: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except OutputError as exc:
        print(f"flexval: output not written: {exc}", file=sys.stderr)
        return EXIT_OUTPUT
