"""``flexval sweep``: its arguments and what it does."""

from __future__ import annotations

import argparse
import os
import sys

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_folder,
    safe_name,
)
from .common import (
    EXIT_OK,
    MAX_LOCAL_WORKERS,
    ParserContext,
    check_memory,
    int_in,
    keep_on_interrupt,
)


def _close_cluster(cluster) -> None:
    """Close the local Dask cluster (None: none was made, or its start was interrupted).

    After SIGINT or SIGTERM (:mod:`flexval.validation.interrupt`) its worker processes are
    ended first, and the close waits for nothing: Dask's own closing at exit, which waits
    for the workers it lost, is dropped."""
    from ..interrupt import received, stop_children

    if received() is None:
        if cluster is not None:
            cluster.close()
        return
    import atexit
    import logging

    from distributed.deploy.spec import close_clusters

    logging.disable(logging.CRITICAL)  # Dask's complaints about the workers it lost
    atexit.unregister(close_clusters)
    stop_children()
    if cluster is not None:
        try:
            cluster.close(timeout=0.5)
        except Exception:  # the workers are gone; the scheduler ends with this process
            pass


def run(args: argparse.Namespace) -> int:
    """``flexval sweep``: parameter sweep of a scene on Dask (Parquet results,
    resumable, error maps).

    Returns the exit code.
    """
    import dataclasses

    from ..sweep import (
        load_sweep,
        local_cluster,
        results_store,
        run_sweep,
        sweep_models,
        sweep_rows,
        write_outputs,
    )
    from ..sweep.engine import stop_workers_on_signals
    from ..sweep.identity import check_identity, keep_identity

    if args.scheduler and args.workers is not None:
        raise SceneError(
            COMMAND_LINE,
            "--workers",
            args.workers,
            "sizes the local cluster; an existing one (--scheduler) has its own",
        )
    from ..sweep.fields import MAX_POINTS

    def building(line: str) -> None:
        if not args.quiet:
            print(f"sweep: {line}", file=sys.stderr, flush=True)

    # the point count is checked from the axes before any point is built, then every point
    sweep = load_sweep(args.sweep, args.max_points or MAX_POINTS, building)
    workers = args.workers or (1 if args.scheduler else MAX_LOCAL_WORKERS)
    check_memory(  # one point built at a time, for the costly families only
        (
            (point.scene.mechanism, spec, None)
            for spec in (sweep.reference, *sweep.models)
            if spec.model_family.cost is not None
            for point in sweep.valid_points
            for _ in sweep.load_cases
        ),
        sweep.source,
        "reference" if sweep.reference.model_family.cost is not None else "models",
        parallel=workers,
        quiet=args.quiet,
    )
    if args.batch is not None:
        sweep = dataclasses.replace(sweep, batch=args.batch)
    out = check_folder(
        args.out if args.out is not None else os.path.join("sweeps", safe_name(sweep.name)), "--out"
    )
    results_store(sweep, out).check()  # a dataset of another format: refused up front
    check_identity(sweep, out)  # and another sweep's rows

    def kept() -> str:
        """What an interruption keeps, once the workers are ended: the published parts;
        the staged ones (a worker's part, or its temporary file, cut short) are removed."""
        store = results_store(sweep, out)
        store.clear_staged()
        return (
            f"{len(store.parts())} finished Parquet parts in "
            f"{out / 'results'}; the same command resumes from them"
        )

    keep_on_interrupt(kept)
    invalid = (
        f"{len(sweep.points) - len(sweep.valid_points)} invalid"
        if sweep.points.checked
        else "random draws: the invalid ones are found as they run"
    )
    print(
        f"sweep {sweep.name}: {len(sweep.points)} points ({invalid}), "
        f"{len(sweep.models)} models + reference {sweep.reference.id}, "
        f"{len(sweep.load_cases)} load cases -> {out}",
        file=sys.stderr,
    )

    def progress(line: str) -> None:
        if not args.quiet:
            print(line, file=sys.stderr, flush=True)

    from distributed import Client

    cluster = None
    try:
        if args.scheduler:
            try:
                client = Client(args.scheduler, timeout="20s")
            except (OSError, TimeoutError) as exc:
                raise SceneError(
                    COMMAND_LINE,
                    "--scheduler",
                    args.scheduler,
                    f"cannot reach the Dask scheduler: {exc}",
                ) from None
        else:
            cluster = local_cluster(args.workers, sweep_models(sweep))
            client = Client(cluster)
            stop_workers_on_signals(client)
        with client:
            stats = run_sweep(sweep, out, client, use_cache=not args.no_cache, progress=progress)
    finally:
        _close_cluster(cluster)
    keep_identity(sweep, out)
    rows = sweep_rows(sweep, out, stats)
    write_outputs(sweep, rows, out, stats.seconds)
    stale = results_store(sweep, out).key_array().size - len(rows)
    print(
        f"{stats.tasks} tasks, {stats.rows_written} rows written ({stats.rows_failed} failed), "
        f"{stats.rows_skipped} already present; {stats.seconds:.1f} s"
        + (
            f"; {stale} stored rows left out of the summary (of an earlier code version, or "
            "of points this sweep no longer has)"
            if stale
            else ""
        ),
        file=sys.stderr,
    )
    print((out / "summary.md").read_text(encoding="utf-8"))
    return EXIT_OK


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval sweep``, its arguments and options."""
    q = sub.add_parser(
        "sweep", help="parameter sweep of a scene on Dask (Parquet results, resumable, error maps)"
    )
    q.add_argument(
        "sweep",
        help="sweep file (TOML) or built-in sweep: open_chain_arcs, slenderness, arc_angle, "
        "notch_ratio, open_chain_tolerance",
    )
    q.add_argument(
        "--out",
        metavar="DIR",
        help="output folder: results/ (Parquet), summary.md, timings.md, figures "
        "(default: sweeps/NAME)",
    )
    q.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="address of an existing Dask scheduler, e.g. tcp://HOST:8786 "
        "(default: a local cluster)",
    )
    q.add_argument(
        "--workers",
        type=int_in(1, MAX_LOCAL_WORKERS),
        metavar="N",
        help=f"local cluster size, 1 to {MAX_LOCAL_WORKERS} (the logical CPUs; "
        "default: one single-threaded process per core)",
    )
    q.add_argument(
        "--max-points",
        type=int_in(1, 10**15),
        metavar="N",
        help="most points the sweep may have (default 1,000,000): the count is computed "
        "from the axes before any point is built, and a larger sweep is refused",
    )
    q.add_argument(
        "--batch",
        type=int_in(1, 100_000),
        metavar="N",
        help="points per task of a reduced model (default: the sweep's, or about "
        "4 tasks per worker and model, at most 25 points each)",
    )
    q.add_argument(
        "--no-cache", action="store_true", help="recompute reference paths even if cached"
    )
    q.add_argument("--quiet", action="store_true", help="no progress lines")
    q.set_defaults(func=run)
