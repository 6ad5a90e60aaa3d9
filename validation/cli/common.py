"""What the ``flexval`` commands share: exit codes, argument checks, option groups and table
columns.
"""

from __future__ import annotations

import argparse
import os
from typing import NamedTuple

from flexval.geometry import load_scene
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_figure_file,
    check_file,
    distinct_files,
)


class ParserContext(NamedTuple):
    """What every command's parser block reads of the catalogue and the scenes (text)."""

    ids: str
    """The accepted model-id forms."""
    refine: str
    """Each family's resolution and its meaning."""
    defaults: str
    """Each family's default study ladder."""
    scene_help: str
    """The help text of a scene argument."""


EXIT_OK, EXIT_INPUT, EXIT_SOLVER, EXIT_OUTPUT = 0, 2, 3, 4
"""Exit codes: success, bad input, solver failure, an output not written."""


MAX_REPEATS = 1000
"""Most timing repeats per load path (a median of more adds nothing but time)."""


MAX_LOCAL_WORKERS = os.cpu_count() or 1
"""Most worker processes of a local sweep cluster: each runs one single-threaded task, so more
than the logical CPUs only multiplies memory (about 100 MB a process)."""


def int_in(low: int, high: int):
    """argparse type: an integer from ``low`` to ``high`` (checked while parsing, exit 2)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be from {low} to {high}, got {value}")
        return value

    return parse


def parse_models(texts, source: str, field: str) -> list:
    """Model ids -> checked ModelSpecs of the catalogue (SceneError naming source and field)."""
    from flexval.reducedmodels.catalogue import parse_model

    return [parse_model(m, source, field) for m in texts]


def check_memory(paths, source: str, field: str, parallel: int = 1, quiet: bool = False) -> float:
    """Refuse (exit 2) a model whose load path would not fit in memory, before any work; print
    the time estimate of long work (:func:`flexval.validation.resources.check_models`); the
    estimated time, s."""
    from ..resources import check_models

    return check_models(paths, source, field, parallel, quiet)


def keep_on_interrupt(description) -> None:
    """What SIGINT or SIGTERM keeps from now on (:func:`flexval.validation.interrupt.keep`)."""
    from ..interrupt import keep

    keep(description)


def keep_cached(enabled: bool, more: str = "") -> None:
    """An interruption keeps the load paths finished so far in the result cache, if it is
    used (the same command then reads them), and nothing otherwise."""
    from ..cache import ResultCache  # here: the watcher thread may call description()

    def description() -> str:
        cache = ResultCache(enabled=enabled)
        if not cache.enabled:
            return "no load path (the result cache is not used)" + more
        return (
            f"the load paths finished so far, in the result cache {cache.root}; "
            "the same command reuses them" + more
        )

    keep_on_interrupt(description)


def analysis_inputs(args: argparse.Namespace):
    """What an analysis of one model about an equilibrium (``modes``, ``buckle``) reads
    first: the scene, the model (its memory estimated), and its ``--json`` and ``--plot``
    paths (checked, distinct; None where not given)."""
    from flexval.reducedmodels import parse_model

    scene = load_scene(args.scene)
    spec = parse_model(args.model, COMMAND_LINE, "--model")
    check_memory([(scene.mechanism, spec, None)], COMMAND_LINE, "--model")
    json_path = check_file(args.json, "--json") if args.json is not None else None
    plot_path = check_figure_file(args.plot, "--plot") if args.plot is not None else None
    distinct_files(("--json", json_path), ("--plot", plot_path))
    return scene, spec, json_path, plot_path


def load_case_option(parser: argparse.ArgumentParser) -> None:
    """``--load-case NAME`` (repeatable): only these load cases of each scene."""
    parser.add_argument(
        "--load-case",
        action="append",
        metavar="NAME",
        help="only this load case of each scene (repeatable; default: all)",
    )


def chosen_cases(scene, args: argparse.Namespace):
    """``scene`` with only its load cases named by ``--load-case`` (all without it)."""
    return scene.with_load_cases(args.load_case) if args.load_case else scene


NO_BATCH_HELP = (
    "skip the batched cost per path (each path also timed as a batch of identical copies, "
    "with the speed-ups against beam:100)"
)


def campaign_options(q: argparse.ArgumentParser) -> None:
    """Options shared by the commands that run many models: timing, cache, progress."""
    q.add_argument(
        "--repeats",
        type=int_in(1, MAX_REPEATS),
        default=3,
        help=f"timing repeats, 1 to {MAX_REPEATS} (median; default 3)",
    )
    q.add_argument("--no-cache", action="store_true", help="recompute everything")
    q.add_argument("--quiet", action="store_true", help="no progress bar")


def scene_and_model(q: argparse.ArgumentParser, scene_help: str, ids: str) -> None:
    """The scene and the one ``--model`` of an analysis about an equilibrium (``modes``,
    ``buckle``, ``stiffness``)."""
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--model", required=True, metavar="MODEL", help=f"model id: {ids} (see flexval models)"
    )
