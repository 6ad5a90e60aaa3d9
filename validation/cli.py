"""The ``flexval`` command line.

Exit codes: 0 success, 1 a gate of ``flexval gate`` does not hold, 2 bad input
(message on stderr, no traceback),
3 solver failure (message with the last converged load level), 4 an output
file could not be written although it was checked before the work (device
full, I/O error, folder removed meanwhile; the message names the file).

Every argument is checked before any work: numeric options against their
ranges, and every output path (``--json``, ``-o``, ``--out``, ``--out-dir``)
for writability (:mod:`flexval.validation.outputs`); such errors exit with 2.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import warnings
from pathlib import Path

from flexval.geometry import BUILTIN_SCENES, SceneError, load_scene
from flexval.geometry.errors import COMMAND_LINE

from .outputs import (
    OutputError,
    check_figure_file,
    check_file,
    check_folder,
    distinct_files,
    output_path,
    safe_name,
    write_json,
)
from .tables import GAP, SIG_WIDTH, Column, header, sig, text_row, text_table

EXIT_OK, EXIT_INPUT, EXIT_SOLVER, EXIT_OUTPUT = 0, 2, 3, 4
MAX_REPEATS = 1000
"""Most timing repeats per load path (a median of more adds nothing but time)."""
MAX_LOCAL_WORKERS = os.cpu_count() or 1
"""Most worker processes of a local sweep cluster: each runs one single-threaded task, so more
than the logical CPUs only multiplies memory (about 100 MB a process)."""


def _int_in(low: int, high: int):
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


def _check_load_levels(levels: int | None) -> None:
    """``--levels`` of ``run``: 2 .. the solver's sub-step cap (one sub-step per increment)."""
    from flexval.reducedmodels.core import SolverSettings

    cap = SolverSettings().max_substeps
    if levels is not None and not 2 <= levels <= cap:
        raise SceneError(
            COMMAND_LINE,
            "--levels",
            levels,
            f"must be from 2 to {cap} (each of the levels - 1 load increments "
            f"takes at least one of the solver's {cap} sub-steps)",
        )


def _parse_models(texts, source: str, field: str) -> list:
    """Model ids -> checked ModelSpecs of the catalogue (SceneError naming source and field)."""
    from flexval.reducedmodels.catalogue import parse_model

    return [parse_model(m, source, field) for m in texts]


def _cmd_info(args: argparse.Namespace) -> int:
    from .info import format_info, scene_info

    json_path = check_file(args.json, "--json") if args.json is not None else None
    info = scene_info(load_scene(args.scene))
    print(format_info(info))
    if json_path:
        write_json(json_path, info)
    return EXIT_OK


def _cmd_models(args: argparse.Namespace) -> int:
    from flexval.reducedmodels.catalogue import load_plugins

    from .modelinfo import catalogue_record, format_models

    json_path = check_file(args.json, "--json") if args.json is not None else None
    load_plugins()
    print(format_models())
    if json_path:
        write_json(json_path, catalogue_record())
    return EXIT_OK


def _cmd_plot(args: argparse.Namespace) -> int:
    from .drawing import plot_mechanism

    output = check_figure_file(args.output, "--output")
    scene = load_scene(args.scene)
    plot_mechanism(scene, output)
    print(f"wrote {output}")
    return EXIT_OK


def _run_request(args: argparse.Namespace, scene) -> tuple[list, list, frozenset]:
    """The models, load cases and stress-field outputs ``flexval run`` is asked for, checked."""
    from flexval.reducedmodels.catalogue import FIELDS, families

    specs = _parse_models(args.model or [], COMMAND_LINE, "--model")
    if not specs:
        specs = _parse_models(scene.models, scene.source, "request.models")
    if not specs:
        raise SceneError(
            scene.source,
            "--model",
            None,
            "no model requested (give --model or request.models in the scene)",
        )
    cases = [scene.load_case(n) for n in args.load_case] if args.load_case else scene.load_cases
    if args.max_load_factor is not None and not args.arclength:
        raise SceneError(
            COMMAND_LINE,
            "--max-load-factor",
            args.max_load_factor,
            "applies to --arclength traces only",
        )
    if args.branch_switch and not args.arclength:
        raise SceneError(
            COMMAND_LINE, "--branch-switch", True, "applies to --arclength traces only"
        )
    _check_dynamic_options(args)
    if args.arclength:
        from .limits import check_arclength

        for spec in specs:
            check_arclength(spec)
    fields = scene.outputs & {"vtu", "png"}
    if fields and not any(sp.model_family.has(FIELDS) for sp in specs):
        with_fields = [f.name for f in families() if f.has(FIELDS)]
        raise SceneError(
            scene.source,
            "request.outputs",
            sorted(fields),
            f"VTU and PNG stress fields come from these models only: {with_fields}",
        )
    return specs, list(cases), frozenset(fields)


DYNAMIC_OPTIONS = {
    "duration": ("--duration", None),
    "damping_ratio": ("--damping-ratio", None),
    "rayleigh": ("--rayleigh", None),
    "rho_inf": ("--rho-inf", 0.9),
    "error_tol": ("--error-tol", 1e-5),
}
"""``flexval run``'s options that only a ``--dynamic`` run reads: the argument, its default."""


def _check_dynamic_options(args: argparse.Namespace) -> None:
    """Refuse option combinations of which one would be silently dropped (exit 2): a dynamic
    option without ``--dynamic``, ``--arclength`` with ``--dynamic``, both damping options."""
    if args.dynamic and args.arclength:
        raise SceneError(
            COMMAND_LINE,
            "--arclength",
            True,
            "traces the static path: it does not go with --dynamic",
        )
    if not args.dynamic:
        for name, (flag, default) in DYNAMIC_OPTIONS.items():
            value = getattr(args, name)
            if value is not None and value != default:
                raise SceneError(COMMAND_LINE, flag, value, "applies to --dynamic runs only")
    if args.rayleigh is not None and args.damping_ratio is not None:
        raise SceneError(
            COMMAND_LINE,
            "--damping-ratio",
            args.damping_ratio,
            "give either --damping-ratio or --rayleigh ALPHA BETA, not both",
        )


def _run_each(specs, cases, run_one, row, scene, json_path) -> int:
    """Run every (model, load case), print one row each, write the JSON; the exit code.

    A solver failure is reported on stderr with the load reached, its partial
    path is kept in the JSON, and the other runs go on (exit code 3 at the end).
    """
    from flexval.reducedmodels import SolverError

    results, status = [], EXIT_OK
    for spec in specs:
        for case in cases:
            try:
                lp = run_one(spec, case)
            except SolverError as exc:
                print(f"flexval: solver failure: {exc}", file=sys.stderr)
                if exc.path is not None:
                    results.append(exc.path)
                    if exc.path.load:  # its last converged level, marked as stopped
                        row(exc.path)
                status = EXIT_SOLVER
                continue
            results.append(lp)
            row(lp)
    if json_path:
        write_json(
            json_path, {"scene": scene.name, "results": [_result(scene, p) for p in results]}
        )
    return status


def _result(scene, lp) -> dict:
    """A path as the run JSON holds it: its fields and, where the scene's material has a
    yield strength, ``first_yield``, ``safety_factor`` and ``yield_note``
    (:func:`flexval.validation.yieldpoint.path_yield`)."""
    from .yieldpoint import scene_yield

    return {**lp.to_dict(), **(scene_yield(scene, lp) or {})}


def _yield_line(scene, lp) -> str | None:
    """The run table's line on first yield and safety factor (None without a yield strength)."""
    from .yieldpoint import scene_yield

    found = scene_yield(scene, lp)
    if found is None:
        return None
    fy, factors, note = found["first_yield"], found["safety_factor"], found["yield_note"]
    parts = [
        f"first yield: load {fy['load']:.6g} {lp.load_unit} ({100 * fy['fraction']:.4g} % of "
        f"full load) on {fy['flexure']} at s = {fy['at']:.4g} mm"
        if fy
        else "first yield: none"
    ]
    if factors["yield"] is not None:
        parts.append(f"safety factor {factors['yield']:.4g}")
    if factors["fatigue"] is not None:
        parts.append(f"against fatigue {factors['fatigue']:.4g}")
    return "; ".join(parts) + (f" ({note})" if note else "")


def _check_memory(paths, source: str, field: str, parallel: int = 1, quiet: bool = False) -> float:
    """Refuse (exit 2) a model whose load path would not fit in memory, before any work; print
    the time estimate of long work (:func:`flexval.validation.resources.check_models`); the
    estimated time, s."""
    from .resources import check_models

    return check_models(paths, source, field, parallel, quiet)


def _keep_on_interrupt(description) -> None:
    """What SIGINT or SIGTERM keeps from now on (:func:`flexval.validation.interrupt.keep`)."""
    from .interrupt import keep

    keep(description)


def _keep_cached(enabled: bool, more: str = "") -> None:
    """An interruption keeps the load paths finished so far in the result cache, if it is
    used (the same command then reads them), and nothing otherwise."""

    def description() -> str:
        from .cache import ResultCache

        cache = ResultCache(enabled=enabled)
        if not cache.enabled:
            return "no load path (the result cache is not used)" + more
        return (
            f"the load paths finished so far, in the result cache {cache.root}; "
            "the same command reuses them" + more
        )

    _keep_on_interrupt(description)


def _cmd_view(args: argparse.Namespace) -> int:
    from .view import check_level, has_display, read_levels, screenshot, show

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


def _uncalibrated_notes(scene, specs) -> list[str]:
    """A note per notch hinge outside the calibrated range of the reduced models' correction
    (:mod:`flexval.reducedmodels.notchcorrection`), where a reduced model without ``eb``
    runs: its factors are the nearest calibrated hinge's, not its own."""
    from flexval.reducedmodels.notchcorrection import factors_of, takes_correction

    if not any(takes_correction(s) for s in specs):
        return []

    notes = []
    for flexure in scene.mechanism.flexures:
        found = factors_of(flexure, scene.mechanism.material.poisson_ratio)
        if found is not None and not found.inside:
            notes.append(
                f"note: notch hinge {flexure.name} ({found.where}) lies outside the range the "
                "reduced models' 2D correction is calibrated on: they take the nearest "
                "calibrated hinge's factors (compare with the continuum, or [eb])"
            )
    return notes


def _cmd_run(args: argparse.Namespace) -> int:
    from flexval.reducedmodels.catalogue import FIELDS

    from .cache import ResultCache, result_key
    from .run import run_model

    _check_load_levels(args.levels)
    json_path = check_file(args.json, "--json") if args.json is not None else None
    scene = load_scene(args.scene)
    specs, cases, fields = _run_request(args, scene)
    max_factor = 1.0 if args.max_load_factor is None else args.max_load_factor
    if not (math.isfinite(max_factor) and 0.0 < max_factor <= 1e6):
        raise SceneError(
            COMMAND_LINE, "--max-load-factor", max_factor, "must be a positive number up to 1e6"
        )
    if args.density is not None and not args.dynamic:
        raise SceneError(
            COMMAND_LINE,
            "--density",
            args.density,
            "applies to --dynamic only (a static run takes its weights from the scene)",
        )
    estimate = _check_memory(  # a dynamic run's memory too; its time is estimated apart
        [(scene.mechanism, spec, args.levels) for spec in specs for _ in cases],
        *((COMMAND_LINE, "--model") if args.model else (scene.source, "request.models")),
        quiet=args.dynamic,
    )
    if args.dynamic:
        if args.vtu is not None:
            raise SceneError(
                COMMAND_LINE,
                "--vtu",
                args.vtu,
                "applies to static runs (load control or --arclength), not --dynamic",
            )
        return _run_dynamic(args, scene, specs, cases, json_path)
    out_dir = check_folder(args.out_dir, "--out-dir") if fields else None
    vtu_dir = check_folder(args.vtu, "--vtu") if args.vtu is not None else None
    cache = ResultCache(enabled=args.cache)
    _keep_cached(cache.enabled and not args.arclength)
    inertia = scene.mechanism.inertia
    massless = inertia.massless_bodies(scene.mechanism.moving_bodies)
    if inertia.gravity is not None and massless:
        print(f"note: bodies without mass data are massless (no weight): {', '.join(massless)}")
    for line in _uncalibrated_notes(scene, specs):
        print(line)
    record = {
        "record_poses": "poses" in scene.outputs or vtu_dir is not None,
        "record_shapes": "shape" in scene.outputs or vtu_dir is not None,
    }
    written: list = []

    def run_one(spec, case):
        """One path, its time series written where ``--vtu`` asks (the levels reached, also
        when the solver stops early)."""
        from flexval.reducedmodels import SolverError

        if vtu_dir is None:
            return trace_one(spec, case)
        from .series import write_series

        try:
            lp = trace_one(spec, case)
        except SolverError as exc:
            if exc.path is not None and exc.path.load and exc.path.shapes is not None:
                written.append(write_series(vtu_dir, scene, exc.path))
            raise
        written.append(write_series(vtu_dir, scene, lp))
        return lp

    def trace_one(spec, case):
        extra = {}
        if spec.model_family.has(FIELDS) and fields:
            extra["vtu_dir"] = out_dir
            if "png" in fields:
                stem = f"{scene.name}_{case.name}_{spec.id.replace(':', '')}"
                extra["png"] = output_path(out_dir, stem, ".png")
        if args.arclength:  # arc-length traces are not cached
            from .limits import DEFAULT_STEPS, trace_arclength

            return trace_arclength(
                scene,
                spec,
                case,
                max_factor,
                args.levels - 1 if args.levels else DEFAULT_STEPS,
                record_poses=record["record_poses"],
                record_shapes=record["record_shapes"],
                branch_switch=args.branch_switch,
            )
        # field outputs need the solve
        key = (
            result_key(scene, spec.id, case.name, args.levels, record)
            if cache.enabled and not extra
            else None
        )
        lp = cache.get(key) if key else None
        if lp is not None:
            lp.stats["cached"] = True
            return lp
        lp = run_model(scene, spec, case, args.levels, **record, **extra)
        if key:
            cache.put(key, lp)
        return lp

    flexures = scene.mechanism.flexures
    columns = [
        _model_column(specs, ":arclength" if args.arclength else ""),
        _case_column(cases),
        Column("load", width=SIG_WIDTH),
        Column("unit", "<", width=4),
        Column("dx mm", width=9),
        Column("dy mm", width=9),
        Column("|d| mm", width=9),
        Column("rot deg", width=8),
        Column("peak MPa", width=SIG_WIDTH),
        Column("at", "<", width=max((len(f.name) for f in flexures), default=0) + 5),
        Column("iters", width=5),
        Column("seconds", width=8),
        Column("valid", width=2 * len(str(_most_levels(args, cases))) + 1),
    ]

    def row(lp) -> None:
        print(
            text_row(
                columns,
                [
                    lp.model,
                    lp.load_case,
                    sig(lp.load[-1]),
                    lp.load_unit,
                    f"{lp.dx[-1]:.4f}",
                    f"{lp.dy[-1]:.4f}",
                    f"{lp.displacement[-1]:.4f}",
                    f"{math.degrees(lp.rotation[-1]):.3f}",
                    *_peak_cells(lp, scene),
                    str(lp.stats.get("newton_iterations", 0)),
                    sig(lp.seconds, 3),
                    _valid_cell(lp),
                ],
            )
        )
        note = _validity_note(lp)
        if note:
            print(note)
        if lp.drive_reactions:
            drive = scene.load_case(lp.load_case).drive
            print(f"{'':<{columns[0].size}}{GAP}{_drive_line(lp, drive)}")
        if _peak_cells(lp, scene)[0].endswith(FIBRE_MARK):
            print(f"{'':<{columns[0].size}}{GAP}{FIBRE_MARK} peak: {_fibre_note(lp)}")
        strength = _yield_line(scene, lp)
        if strength:
            print(f"{'':<{columns[0].size}}{GAP}{strength}")
        for point in lp.limit_points or []:
            print(
                f"{'':<{columns[0].size}}{GAP}limit point: load {point['load']:.6g} "
                f"{lp.load_unit}, dx {point['dx']:.6g} mm, dy {point['dy']:.6g} mm, "
                f"rot {math.degrees(point['rotation']):.6g} deg"
            )
        for point in lp.bifurcations or []:
            print(
                f"{'':<{columns[0].size}}{GAP}bifurcation: load {point['load']:.6g} "
                f"{lp.load_unit} (fraction {point['fraction']:.6g})"
            )
        if "stability" in lp.stats:
            print(f"{'':<{columns[0].size}}{GAP}stability {lp.stats['stability']}")

    print(header(columns))
    from .campaign import level_progress
    from .resources import long_seconds

    long = not args.arclength and estimate > long_seconds()  # progress: see --help
    with level_progress(specs, cases, args.levels, enabled=long):
        status = _run_each(specs, cases, run_one, row, scene, json_path)
    if written:
        print(
            f"VTK time series: {len(written)} .pvd in {vtu_dir} "
            f"(ParaView, or: flexval view {written[0]})"
        )
    return status


def _drive_line(lp, drive) -> str:
    """What holds a prescribed motion (``drive``, a Displacement): the force (N) and moment
    (N mm) at the path's last point, the range of the reaction along the drive's axis (its
    first moving component) and where it is zero (the unloaded equilibria a bistable
    mechanism passes; :mod:`.drivereaction`)."""
    from .drivereaction import along_drive, zero_crossings

    fx, fy, moment = lp.drive_reactions[-1]
    component, _ = drive.axis
    along = along_drive(lp, drive)[:, component]
    unit = "N mm" if component == 2 else "N"
    text = (
        f"drive reaction: Fx {fx:.6g} N, Fy {fy:.6g} N, M {moment:.6g} N mm at load "
        f"{lp.load[-1]:.6g} {lp.load_unit}; along the drive from {along.min():.6g} to "
        f"{along.max():.6g} {unit}"
    )
    zeros = zero_crossings(lp, along)
    if zeros:
        listed = ", ".join(f"{z:.4g}" for z in zeros)
        text += f"; zero at {listed} {lp.load_unit} (unloaded equilibria)"
    return text


def _run_dynamic(args: argparse.Namespace, scene, specs, cases, json_path) -> int:
    """``run --dynamic``: one time history per model and load case (final values printed)."""
    from .dynamic import run_dynamic
    from .modes import choose_density

    scene, density = choose_density(scene, args.density, what="a dynamic run")
    massless = scene.mechanism.inertia.massless_bodies(scene.mechanism.moving_bodies)
    if massless:
        print(f"note: bodies without mass data (massless): {', '.join(massless)}")
    print(f"note: {density.describe()}")

    def run_one(spec, case):
        return run_dynamic(
            scene,
            spec,
            case,
            args.duration,
            args.damping_ratio,
            args.rayleigh,
            args.rho_inf,
            "poses" in scene.outputs,
            args.error_tol,
        )

    columns = [
        _model_column(specs),
        _case_column(cases),
        Column("t s", width=SIG_WIDTH),
        Column("load", width=SIG_WIDTH),
        Column("unit", "<", width=4),
        Column("dx mm", width=9),
        Column("dy mm", width=9),
        Column("rot deg", width=8),
        Column("steps", width=5),
        Column("rejected", width=8),
        Column("seconds", width=8),
    ]

    def row(lp) -> None:
        print(
            text_row(
                columns,
                [
                    lp.model,
                    lp.load_case,
                    sig(lp.time[-1]),
                    sig(lp.load[-1]),
                    lp.load_unit,
                    f"{lp.dx[-1]:.4f}",
                    f"{lp.dy[-1]:.4f}",
                    f"{math.degrees(lp.rotation[-1]):.3f}",
                    str(lp.stats["steps"]),
                    str(lp.stats["rejected_steps"]),
                    sig(lp.seconds, 3),
                ],
            )
        )

    from .dynamic import describe, estimate_dynamic, time_progress
    from .resources import long_seconds

    estimates = [
        (spec.id, case.name, e)
        for spec in specs
        for case in cases
        if (e := estimate_dynamic(scene, spec, case, args.duration, args.error_tol, args.rho_inf))
    ]
    long = bool(estimates) and sum(e.seconds for *_, e in estimates) > long_seconds()
    if long:  # the estimate, then a progress line per 1/20 of each run's duration
        print(describe(estimates), file=sys.stderr, flush=True)
    print(header(columns))
    with time_progress(len(specs) * len(cases), enabled=long):
        return _run_each(specs, cases, run_one, row, scene, json_path)


def _model_column(specs, suffix: str = "") -> Column:
    """The ``model`` column of a run table: as wide as the longest canonical id (and the
    ``suffix`` its results carry, e.g. ``:arclength``)."""
    return Column("model", "<", width=max((len(sp.id + suffix) for sp in specs), default=0))


def _case_column(cases) -> Column:
    """The ``case`` column of a run table: as wide as the longest load case name."""
    return Column("case", "<", width=max((len(c.name) for c in cases), default=0))


def _most_levels(args: argparse.Namespace, cases) -> int:
    """The most load levels a run line can count in its ``valid`` cell."""
    if args.arclength:
        from .limits import DEFAULT_STEPS

        return max(1000, args.levels or DEFAULT_STEPS)
    return args.levels or max((c.levels for c in cases), default=0)


def _valid_cell(lp) -> str:
    """``valid/levels`` of the validity monitor, ``-`` for a model it does not judge;
    ``stopped`` after it for a path that did not reach the full load."""
    cell = "-" if lp.valid is None else f"{sum(lp.valid)}/{len(lp.valid)}"
    return cell if lp.converged is not False else f"{cell} stopped"


def _validity_note(lp) -> str:
    """A marked line naming the first level outside the model's range and why ('' if none)."""
    if lp.valid is None or all(lp.valid):
        return ""
    k = lp.valid.index(False)
    return (
        f"  ! {lp.model} {lp.load_case}: outside the model's range from level {k + 1} "
        f"({lp.load[k]:.4g} {lp.load_unit}): {lp.validity[k]}"
    )


def _cmd_compare(args: argparse.Namespace) -> int:
    """``flexval compare``: models against a measured load-displacement file
    (:mod:`flexval.validation.measuredcompare`); exit 3 when a model's path stops before
    the largest measured load (the JSON and the plot are written all the same)."""
    from flexval.geometry.measured import read_measurement

    from .cache import ResultCache
    from .measuredcompare import compare_measurement, traced_case
    from .measuredreport import plot, text_lines

    json_path = check_file(args.json, "--json") if args.json is not None else None
    plot_path = check_figure_file(args.plot, "--plot") if args.plot is not None else None
    scene = load_scene(args.scene)
    case = scene.load_case(args.load_case)
    measurement = read_measurement(args.measured, case)
    specs = _parse_models(args.model or [], COMMAND_LINE, "--model")
    if not specs:
        specs = _parse_models(scene.models, scene.source, "request.models")
    if not specs:
        raise SceneError(
            scene.source, "--model", None, "no model requested (give --model or request.models)"
        )
    levels = len(traced_case(case, measurement)[0].at)
    _check_memory(
        [(scene.mechanism, spec, levels) for spec in specs],
        *((COMMAND_LINE, "--model") if args.model else (scene.source, "request.models")),
    )
    cache = ResultCache(enabled=not args.no_cache)
    _keep_cached(cache.enabled)
    comparison = compare_measurement(scene, measurement, specs, cache if cache.enabled else None)
    print("\n".join(text_lines(comparison)))
    if json_path:
        write_json(json_path, comparison.record())
    if plot_path:
        plot(comparison, plot_path)
        print(f"wrote {plot_path}")
    for s in comparison.stopped():
        print(f"flexval: solver failure: {s.model}: {comparison.beyond_text(s)}", file=sys.stderr)
    return EXIT_SOLVER if comparison.stopped() else EXIT_OK


def _analysis_inputs(args: argparse.Namespace):
    """What an analysis of one model about an equilibrium (``modes``, ``buckle``) reads
    first: the scene, the model (its memory estimated), and its ``--json`` and ``--plot``
    paths (checked, distinct; None where not given)."""
    from flexval.reducedmodels import parse_model

    scene = load_scene(args.scene)
    spec = parse_model(args.model, COMMAND_LINE, "--model")
    _check_memory([(scene.mechanism, spec, None)], COMMAND_LINE, "--model")
    json_path = check_file(args.json, "--json") if args.json is not None else None
    plot_path = check_figure_file(args.plot, "--plot") if args.plot is not None else None
    distinct_files(("--json", json_path), ("--plot", plot_path))
    return scene, spec, json_path, plot_path


def _cmd_modes(args: argparse.Namespace) -> int:
    from flexval.reducedmodels import SolverError

    from .modes import choose_density, modes_record, plot_modes, run_modes

    scene, spec, json_path, plot_path = _analysis_inputs(args)
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


def _cmd_stiffness(args: argparse.Namespace) -> int:
    from flexval.reducedmodels import SolverError

    from .stiffness import MOTIONS, run_stiffness, stiffness_record

    scene, spec, json_path, _ = _analysis_inputs(args)
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


def _cmd_buckle(args: argparse.Namespace) -> int:
    from flexval.reducedmodels import SolverError

    from .buckle import buckle_record, linearisation_holds, path_stop, run_buckle
    from .modes import plot_modes

    scene, spec, json_path, plot_path = _analysis_inputs(args)
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
        from flexval.reducedmodels.modes import Modes

        shapes = Modes(found.factors, found.shapes, found.state)
        labels = [
            f"mode {k}: {sig(f * case.magnitude, 4)} {case.unit}"
            for k, f in enumerate(found.factors.tolist(), 1)
        ]
        plot_modes(system, shapes, plot_path, f"{scene.name} {spec.id} {where}", labels)
    return EXIT_OK


FIBRE_MARK = "*"
"""Marks a run line's peak stress that is a notch's surface fibre stress (the continuum's,
or a reduced model's beam formula times the calibrated stress concentration)."""


def _fibre_note(lp) -> str:
    """What a run line's :data:`FIBRE_MARK` means for ``lp``'s model."""
    if lp.model.startswith("continuum"):
        return (
            "the continuum's surface fibre stress at the notch, stress concentration "
            "included (elsewhere the beam formula of its section forces)"
        )
    return (
        "the notch's surface fibre stress: the beam formula at its waist times the "
        "notch's stress concentration, calibrated against the continuum"
    )


def _peak_cells(lp, scene) -> tuple[str, str]:
    """``peak MPa`` and ``at`` of a run line: the largest peak stress over the flexures at the
    last level (:func:`flexval.validation.yieldpoint.flexure_peaks`, marked with
    :data:`FIBRE_MARK` where it is a notch's surface fibre stress) and where
    (``flexure@fraction`` of its length from its first end)."""
    from .yieldpoint import flexure_peaks, notch_concentrations

    peaks = flexure_peaks(lp, notch_concentrations(scene, lp))
    if not peaks:
        return "-", ""
    name = max(peaks, key=lambda f: peaks[f][0][-1])
    values, places, fibre = peaks[name]
    return sig(values[-1]) + (FIBRE_MARK if fibre else ""), f"{name}@{places[-1]:.2f}"


def _parse_levels(text: str, spec) -> list[int]:
    """The resolutions of a study of ``spec``'s family: ``LO:HI`` is the family's series
    (``0:4`` -> 0, 1, 2, 3, 4 for mesh levels; ``20:320`` -> 20, 40, ..., 320 for doubling
    N); a comma list is taken as is."""
    res = spec.model_family.resolution
    try:
        vals = [int(x) for x in text.split(":" if ":" in text else ",")]
    except ValueError:
        raise SceneError(
            COMMAND_LINE, "--levels", text, "expected LO:HI or a comma-separated list of integers"
        ) from None
    if ":" in text and len(vals) != 2:
        raise SceneError(COMMAND_LINE, "--levels", text, "expected LO:HI")
    # range first: the series is built only from checked ends (a doubling from 0 never ends)
    if not vals or vals != sorted(set(vals)) or not res.low <= min(vals) <= max(vals) <= res.high:
        raise SceneError(
            COMMAND_LINE,
            "--levels",
            text,
            f"resolutions must increase, within {res.low}..{res.high} for the "
            f"{res.name} of '{spec.family}' ({res.meaning})",
        )
    series = res.series(*vals) if ":" in text else vals
    if len(series) < 2:
        raise SceneError(
            COMMAND_LINE,
            "--levels",
            text,
            f"gives the single resolution {series[0]}: a study compares at least "
            f"two (three for the order and the Richardson value)",
        )
    return series


def _cmd_converge(args: argparse.Namespace) -> int:
    from flexval.reducedmodels.catalogue import families

    from .convergence import format_study, study

    (spec,) = _parse_models([args.model], COMMAND_LINE, "--model")
    res = spec.model_family.resolution
    if res is None:
        refinable = [f.name for f in families() if f.resolution is not None]
        raise SceneError(
            COMMAND_LINE,
            "--model",
            args.model,
            f"convergence studies need a model with a resolution: {refinable}",
        )
    resolutions = _parse_levels(args.levels or "{}:{}".format(*res.study), spec)
    json_path = check_file(args.json, "--json") if args.json is not None else None
    scene = load_scene(args.scene)
    cases = [scene.load_case(n) for n in args.load_case] if args.load_case else scene.load_cases
    _check_memory(
        [(scene.mechanism, spec.with_resolution(r), None) for r in resolutions for _ in cases],
        COMMAND_LINE,
        "--levels" if args.levels else "--model",
    )
    out, status = [], EXIT_OK
    for case in cases:
        st = study(scene, spec, resolutions, case)
        for f in st.failures:
            print(f"flexval: solver failure: {f.message}", file=sys.stderr)
            status = EXIT_SOLVER
        print(format_study(st) + "\n")
        out.append(
            {
                "family": st.family,
                "load_case": st.load_case,
                "ratio": st.ratio,
                "rows": st.rows,
                "summary": st.summary,
                "failures": [f.to_dict() for f in st.failures],
            }
        )
    if json_path:
        write_json(json_path, {"scene": scene.name, "studies": out})
    return status


def _check_report_memory(scenes: list[str], specs: list, args: argparse.Namespace) -> None:
    """:func:`_check_memory` of every path the report traces: each model on each scene and
    load case, and the convergence study of its reference family (the resolutions up to one
    above the reference's; :data:`flexval.validation.reportdata.DEFAULT_MODELS`)."""
    from flexval.reducedmodels.catalogue import REFERENCE

    from .reportdata import convergence_specs

    paths = []
    for name in scenes:
        scene = load_scene(name)
        reference = next((s for s in specs if s.model_family.has(REFERENCE)), None)
        if not args.no_converge and reference is not None and reference.resolution is not None:
            paths += [(scene.mechanism, s, None) for s in convergence_specs(reference)]
        paths += [(scene.mechanism, s, None) for s in specs for _ in scene.load_cases]
    _check_memory(paths, COMMAND_LINE, "--model", parallel=args.jobs or 1, quiet=args.quiet)


def _load_case_option(parser: argparse.ArgumentParser) -> None:
    """``--load-case NAME`` (repeatable): only these load cases of each scene."""
    parser.add_argument(
        "--load-case",
        action="append",
        metavar="NAME",
        help="only this load case of each scene (repeatable; default: all)",
    )


def _chosen_cases(scene, args: argparse.Namespace):
    """``scene`` with only its load cases named by ``--load-case`` (all without it)."""
    return scene.with_load_cases(args.load_case) if args.load_case else scene


def _cmd_report(args: argparse.Namespace) -> int:
    from flexval.geometry.scene import PAPER_SCENES

    from .report import DEFAULT_MODELS, write_report
    from .reportdata import compute_report
    from .reportfolder import default_report_folder, other_report

    scenes = args.scene or list(PAPER_SCENES)
    names = []
    for name in scenes:
        scene = load_scene(name)
        _chosen_cases(scene, args)  # bad input fails before any work
        names.append(scene.name)
    models = args.model or list(DEFAULT_MODELS)
    specs = _parse_models(models, COMMAND_LINE, "--model")
    _check_report_memory(scenes, specs, args)
    out_arg = args.out if args.out is not None else default_report_folder(names)
    other_report(out_arg, names, args.force)
    out = check_folder(out_arg, "--out")  # created only once the rest is known good
    timings = check_folder(args.timings, "--timings") if args.timings is not None else None
    _keep_cached(not args.no_cache, f"; the files written in {out} are whole")
    data = compute_report(
        scenes,
        models,
        args.repeats,
        not args.no_cache,
        not args.quiet,
        not args.no_bench,
        not args.no_converge,
        args.jobs,
        args.peers,
        not args.no_batch,
        load_cases=args.load_case,
    )
    path = write_report(
        data,
        out,
        Path(args.protocol) if args.protocol else None,
        Path(args.threed) if args.threed else None,
        timings,
    )
    print(f"wrote {path}" + (f" (run times in {timings})" if timings is not None else ""))
    unfinished = _unfinished_cases(data)
    for line in unfinished:
        print(f"flexval: solver failure: {line}", file=sys.stderr)
    return EXIT_SOLVER if unfinished else EXIT_OK


def _unfinished_cases(data) -> list[str]:
    """The report's (scene, load case) pairs with nothing to compare: the reference stopped
    before the full load, or every model did. Every file is written all the same; the
    command then exits 3."""
    lines = []
    for r in data.scenes:
        for case in r.cases:
            finished = [m for m in r.models if r.converged(m, case) is not None]
            if not finished:
                lines.append(f"{r.scene.name}, load case {case}: no model reached the full load")
            elif r.reference and r.reference not in finished:
                lines.append(
                    f"{r.scene.name}, load case {case}: the reference {r.reference} stopped "
                    "before the full load (the report says where and why)"
                )
    return lines


def _cmd_bench(args: argparse.Namespace) -> int:
    from .batchtiming import BatchMemo
    from .bench import runtime_vs_error, sweep_specs, write_bench
    from .cache import ResultCache

    scene = _chosen_cases(load_scene(args.scene), args)
    (ref,) = _parse_models([args.reference], COMMAND_LINE, "--reference")
    out = check_folder(args.out, "--out")
    _keep_cached(not args.no_cache)
    cache = ResultCache(enabled=not args.no_cache)
    rows, failures = runtime_vs_error(
        scene,
        ref,
        sweep_specs(ref),
        args.repeats,
        cache,
        not args.quiet,
        batches=BatchMemo(args.repeats, cache, enabled=not args.no_batch),
    )
    for f in failures:
        print(f"flexval: {f.model} on {f.load_case} {f.summary()}: {f.message}", file=sys.stderr)
    md = write_bench(scene, rows, ref.id, out, failures)
    print(md.read_text(encoding="utf-8"))
    stopped = sorted({f.load_case for f in failures if f.model == ref.id})
    for case in stopped:  # every file is written; nothing to compare on these cases
        print(
            f"flexval: solver failure: the reference {ref.id} stopped before the full load on "
            f"load case {case}",
            file=sys.stderr,
        )
    return EXIT_SOLVER if stopped else EXIT_OK


def _cmd_stress(args: argparse.Namespace) -> int:
    from .stress import stress_report, write_stress

    scene = _chosen_cases(load_scene(args.scene), args)
    models = args.model or ["ee", "dcmm:1", "dcmm:2", "prbm", "beam:20"]
    specs = _parse_models(models, COMMAND_LINE, "--model")
    from .stress import AMPLIFICATIONS, STEP_COUNTS

    counts = [n for n in STEP_COUNTS if not args.quick or n < 1001]
    _check_memory(  # every case: each amplification at 11 levels, then each step count
        [
            (scene.mechanism, spec, n)
            for spec in specs
            for _ in scene.load_cases
            for n in [11] * len(AMPLIFICATIONS) + counts
        ],
        COMMAND_LINE,
        "--model",
    )
    out = check_folder(args.out, "--out")

    def progress(line: str) -> None:
        if not args.quiet:
            print(line, file=sys.stderr, flush=True)

    report = stress_report(scene, specs, quick=args.quick, progress=progress)
    md, _ = write_stress(report, out)
    print(md.read_text(encoding="utf-8"))
    return EXIT_OK


def _close_cluster(cluster) -> None:
    """Close the local Dask cluster (None: none was made, or its start was interrupted).

    After SIGINT or SIGTERM (:mod:`flexval.validation.interrupt`) its worker processes are
    ended first, and the close waits for nothing: Dask's own closing at exit, which waits
    for the workers it lost, is dropped."""
    from .interrupt import received, stop_children

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


def _cmd_sweep(args: argparse.Namespace) -> int:
    import dataclasses

    from .sweep import (
        load_sweep,
        local_cluster,
        results_store,
        run_sweep,
        sweep_models,
        sweep_rows,
        write_outputs,
    )
    from .sweep.engine import stop_workers_on_signals
    from .sweep.identity import check_identity, keep_identity

    if args.scheduler and args.workers is not None:
        raise SceneError(
            COMMAND_LINE,
            "--workers",
            args.workers,
            "sizes the local cluster; an existing one (--scheduler) has its own",
        )
    from .sweep.spec import MAX_POINTS

    def building(line: str) -> None:
        if not args.quiet:
            print(f"sweep: {line}", file=sys.stderr, flush=True)

    # the point count is checked from the axes before any point is built, then every point
    sweep = load_sweep(args.sweep, args.max_points or MAX_POINTS, building)
    workers = args.workers or (1 if args.scheduler else MAX_LOCAL_WORKERS)
    _check_memory(  # one point built at a time, for the costly families only
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

    _keep_on_interrupt(kept)
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


EXIT_GATE_FAILED = 1
"""``flexval gate``: a gate does not hold."""


def _cmd_gate(args: argparse.Namespace) -> int:
    from flexval.reducedmodels import PluginFailure

    from .cache import ResultCache
    from .campaign import available_cores
    from .gate import ReferenceFailure, evaluate, prepare, summary_record
    from .gatefile import load_gates

    json_path = check_file(args.json, "--json") if args.json is not None else None
    junit_path = check_file(args.junit, "--junit") if args.junit is not None else None
    distinct_files(("--json", json_path), ("--junit", junit_path))
    if args.prepare and (json_path or junit_path):
        option = "--json" if json_path else "--junit"
        raise SceneError(
            COMMAND_LINE, option, args.json or args.junit, "--prepare writes no verdict"
        )
    root = check_folder(args.cache, "--cache") if args.cache is not None else None
    gates = load_gates(args.gates)
    specs = [gates.reference] + [g.model for g in gates.gates]
    workers = args.workers or available_cores()
    _check_memory(
        [(s.mechanism, spec, None) for spec in specs for s in gates.scenes],
        gates.source,
        "gates",
        parallel=workers,
        quiet=args.quiet,
    )
    cache = ResultCache(root=root)
    _keep_cached(cache.enabled)
    if args.prepare:
        done, failed = prepare(gates, cache, workers, not args.quiet)
        print(f"{done} results in the result cache {cache.root}")
        for line in failed:
            print(f"flexval: solver failure: {line}", file=sys.stderr)
        return EXIT_SOLVER if failed else EXIT_OK
    try:
        checks = evaluate(gates, cache, workers, not args.quiet)
    except (ReferenceFailure, PluginFailure) as exc:
        print(f"flexval: solver failure: {exc}", file=sys.stderr)
        return EXIT_SOLVER
    rows = [
        [
            c.model,
            c.scene,
            c.case,
            c.metric,
            sig(c.value),
            sig(c.threshold),
            "pass" if c.passed else "FAIL",
        ]
        for c in checks
    ]
    columns = [
        Column("model", "<"),
        Column("scene", "<"),
        Column("case", "<"),
        Column("metric", "<"),
        Column("error %"),
        Column("threshold %"),
        Column("verdict", "<"),
    ]
    print(f"errors against {gates.reference.id} (percent)")
    print("\n".join(text_table(columns, rows)))
    failed = [c for c in checks if not c.passed]
    for c in checks:
        if c.detail:
            print(f"{c.model} {c.scene} {c.case} {c.metric}: {c.detail}")
        if c.reason and not c.passed and c.reason != c.detail:
            print(f"{c.model} {c.scene} {c.case}: {c.reason}")
    print(f"{len(checks)} checks: {len(checks) - len(failed)} passed, {len(failed)} failed")
    if json_path:
        write_json(json_path, summary_record(gates, checks))
    if junit_path:
        from .junit import write_junit

        write_junit(junit_path, checks, gates.reference.id)
    return EXIT_GATE_FAILED if failed else EXIT_OK


NO_BATCH_HELP = (
    "skip the batched cost per path (each path also timed as a batch of identical copies, "
    "with the speed-ups against beam:100)"
)


def _campaign_options(q: argparse.ArgumentParser) -> None:
    """Options shared by the commands that run many models: timing, cache, progress."""
    q.add_argument(
        "--repeats",
        type=_int_in(1, MAX_REPEATS),
        default=3,
        help=f"timing repeats, 1 to {MAX_REPEATS} (median; default 3)",
    )
    q.add_argument("--no-cache", action="store_true", help="recompute everything")
    q.add_argument("--quiet", action="store_true", help="no progress bar")


def _scene_and_model(q: argparse.ArgumentParser, scene_help: str, ids: str) -> None:
    """The scene and the one ``--model`` of an analysis about an equilibrium (``modes``,
    ``buckle``, ``stiffness``)."""
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--model", required=True, metavar="MODEL", help=f"model id: {ids} (see flexval models)"
    )


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

    q = sub.add_parser("info", help="describe a scene: bodies, flexures, ellipse data, loads")
    q.add_argument("scene", help=scene_help)
    q.add_argument("--json", metavar="PATH", help="also write the description as JSON")
    q.set_defaults(func=_cmd_info)

    q = sub.add_parser(
        "models",
        help="list the model families: id syntax, resolutions, options, capabilities",
    )
    q.add_argument("--json", metavar="PATH", help="also write the listing as JSON")
    q.set_defaults(func=_cmd_models)

    q = sub.add_parser("plot", help="draw the undeformed mechanism to a PNG")
    q.add_argument("scene", help=scene_help)
    q.add_argument("-o", "--output", required=True, metavar="FILE.png", help="output PNG")
    q.set_defaults(func=_cmd_plot)

    from .view import FIELDS as VIEW_FIELDS

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
    q.set_defaults(func=_cmd_view)

    from .resources import LONG_ENV, LONG_SECONDS

    q = sub.add_parser(
        "run",
        help="trace load paths with one or more models",
        description="Trace load paths with one or more models. Work estimated to take "
        f"longer than {LONG_SECONDS:g} s (${LONG_ENV} sets another threshold) prints the "
        "estimate first and, on static load-control paths, one progress line per converged "
        "load level on stderr (level k/N, load, time so far, about how long the rest takes), "
        "and on --dynamic runs (time steps estimated from the duration, the lowest natural "
        "frequency at rest and --error-tol) one line per twentieth of the duration reached, "
        "whether or not stderr is a terminal; the results are the same.",
    )
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--model",
        action="append",
        metavar="MODEL",
        help=f"model id: {ids}; options in brackets, e.g. beam:100[shear], "
        "dcmm:2[frame=follower]; flexval models lists them (repeatable; default: the "
        "scene's request.models)",
    )
    q.add_argument(
        "--load-case",
        action="append",
        metavar="NAME",
        help="load case name (repeatable; default: all)",
    )
    q.add_argument(
        "--levels",
        type=int,
        metavar="N",
        help="number of equally spaced load levels from 0 (default: the scene's, 11)",
    )
    q.add_argument("--json", metavar="PATH", help="write all LoadPaths as JSON")
    q.add_argument(
        "--cache",
        action="store_true",
        help="reuse and store results in the result cache ($FLEXVAL_CACHE or "
        "~/.cache/flexval; default: always compute, so timings are fresh; "
        "runs that write VTU/PNG fields always compute)",
    )
    q.add_argument(
        "--arclength",
        action="store_true",
        help="trace by arc-length continuation, through limit points, up to the "
        "load case's full value (every converged point is reported; --levels N "
        "sets the initial arc length to reach it in N - 1 steps, default 20)",
    )
    q.add_argument(
        "--max-load-factor",
        type=float,
        metavar="X",
        help="with --arclength: trace up to X times the load case's value (default 1)",
    )
    q.add_argument(
        "--branch-switch",
        action="store_true",
        help="with --arclength: at the first bifurcation point, follow the crossing branch "
        "(a step along the critical mode) instead of the traced one",
    )
    q.add_argument(
        "--out-dir",
        default="flexval_out",
        metavar="DIR",
        help="folder for the continuum's VTU/PNG outputs when the scene requests "
        'them (request.outputs = ["vtu", "png"]; default flexval_out)',
    )
    q.add_argument(
        "--vtu",
        metavar="DIR",
        help="write each path as a VTK time series into DIR (any model): STEM.pvd and "
        "one .vtu per level with the flexures as solids of their thickness, the rigid "
        "bodies as polygons, point data displacement (mm) and signed fibre_stress (MPa); "
        "open it in ParaView or with flexval view",
    )
    q.add_argument(
        "--dynamic",
        action="store_true",
        help="integrate in time (generalised-alpha) instead of tracing the static "
        "path; the JSON adds 'time' (s) to each result",
    )
    q.add_argument(
        "--duration",
        type=float,
        metavar="T",
        help="--dynamic: end time in s (default: the load case's end_time, or 1.25 "
        "t1; a load case without a time law ramps by Eq. 15 from 0 to t1 = 1 s, a run "
        "of 1.25 s, or, given T, over 0.8 T)",
    )
    q.add_argument(
        "--damping-ratio",
        type=float,
        metavar="ZETA",
        help="--dynamic: Rayleigh damping giving this ratio at the two lowest "
        "natural frequencies at rest (default: no damping)",
    )
    q.add_argument(
        "--rayleigh",
        type=float,
        nargs=2,
        metavar=("ALPHA", "BETA"),
        help="--dynamic: Rayleigh damping D = ALPHA M + BETA K (1/s, s)",
    )
    q.add_argument(
        "--rho-inf",
        type=float,
        default=0.9,
        metavar="RHO",
        help="--dynamic: generalised-alpha spectral radius at infinite frequency, "
        "1 (no numerical dissipation) to 0 (default 0.9)",
    )
    q.add_argument(
        "--error-tol",
        type=float,
        default=1e-5,
        metavar="TOL",
        help="--dynamic: local error bound per time step (displacement over the "
        "mechanism size, rotation in rad; default 1e-5): the history's error "
        "falls about 3-5 times per decade of it",
    )
    q.add_argument(
        "--density",
        type=float,
        metavar="RHO",
        help="--dynamic: flexure density in t/mm^3 instead of the scene's material.density "
        "(PLA: 1.24e-9); a scene with neither and a body without mass data is refused",
    )
    q.set_defaults(func=_cmd_run)

    q = sub.add_parser(
        "compare",
        help="compare models with a measured load-displacement file (a test rig's CSV)",
        description="Trace each model through the measured loads of a CSV file (columns "
        "load, in the load case's unit N or N mm; dx, dy in mm and rotation in deg, any of "
        "them; optional <column>_std standard uncertainties) and score it: RMS and largest "
        "difference in percent of the measured range, and the share of points within twice "
        "the standard uncertainty. Measured loads beyond a model's path (a limit point) are "
        "reported, not scored; exit 3 then.",
    )
    q.add_argument("scene", help=scene_help)
    q.add_argument("--measured", required=True, metavar="FILE", help="the measured CSV file")
    q.add_argument(
        "--load-case", required=True, metavar="NAME", help="the load case the file measures"
    )
    q.add_argument(
        "--model",
        action="append",
        metavar="MODEL",
        help=f"model id: {ids} (repeatable; default: the scene's request.models)",
    )
    q.add_argument(
        "--json", metavar="PATH", help="write the scores, the values and the paths as JSON"
    )
    q.add_argument("--plot", metavar="FILE.png", help="draw the measurement against every model")
    q.add_argument(
        "--no-cache",
        action="store_true",
        help="recompute every path (default: reuse and store them in the result cache)",
    )
    q.set_defaults(func=_cmd_compare)

    q = sub.add_parser("modes", help="natural frequencies and mode shapes about an equilibrium")
    _scene_and_model(q, scene_help, ids)
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
    q.set_defaults(func=_cmd_modes)

    q = sub.add_parser(
        "buckle",
        help="linearised buckling: critical loads and modes of a load case, beside its path",
    )
    _scene_and_model(q, scene_help, ids)
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
    q.set_defaults(func=_cmd_buckle)

    q = sub.add_parser(
        "stiffness",
        help="the 3 x 3 stiffness and compliance at the target, at rest or under a load",
    )
    _scene_and_model(q, scene_help, ids)
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
    q.set_defaults(func=_cmd_stiffness, plot=None)

    q = sub.add_parser("converge", help="resolution study: order, Richardson value, GCI")
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--model",
        default="continuum",
        metavar="MODEL",
        help="model to refine, a family with a resolution and any options, e.g. "
        f"beam[shear] ({refine}; default: continuum)",
    )
    q.add_argument(
        "--levels",
        metavar="LO:HI",
        help="mesh levels LO..HI, or N from LO doubling up to HI; or a comma list "
        f"(defaults: {defaults})",
    )
    q.add_argument(
        "--load-case",
        action="append",
        metavar="NAME",
        help="load case name (repeatable; default: all)",
    )
    q.add_argument("--json", metavar="PATH", help="write the studies as JSON")
    q.set_defaults(func=_cmd_converge)

    q = sub.add_parser("report", help="build the validation report (Markdown, PNG, JSON)")
    q.add_argument("scene", nargs="*", help=f"{scene_help} (default: both built-in scenes)")
    q.add_argument(
        "--out",
        metavar="DIR",
        help="output folder (default: SCENE_report in the current folder, the scenes' "
        "names joined by '+', paper_report for the paper's scenes); a folder holding "
        "another scene's report is refused without --force",
    )
    q.add_argument(
        "--force",
        action="store_true",
        help="write into --out even where it holds the report of other scenes",
    )
    q.add_argument(
        "--timings",
        metavar="DIR",
        help="write the run times (timings.md, timings.json, bench_SCENE.*) into DIR "
        "instead of beside report.md, whose results are the same from run to run while "
        "its run times are not (a repository that commits its report keeps them apart)",
    )
    q.add_argument(
        "--model",
        action="append",
        metavar="MODEL",
        help="models to compare (repeatable; default: continuum, beam:100, beam:20, "
        "prbm, dcmm:1, dcmm:2, dcmm:3, ee)",
    )
    _campaign_options(q)
    _load_case_option(q)
    q.add_argument("--no-bench", action="store_true", help="skip the runtime-vs-error study")
    q.add_argument("--no-converge", action="store_true", help="skip the mesh convergence study")
    q.add_argument("--no-batch", action="store_true", help=NO_BATCH_HELP)
    q.add_argument(
        "--peers",
        action="store_true",
        help="also time beam:100 against OpenSeesPy on every load case, in the run "
        "times (optional extra [peers]; without it they say it is missing)",
    )
    q.add_argument(
        "--protocol",
        metavar="PATH",
        help="protocol.json of benchmarks/paper_protocol.py, summarised in the "
        "report's dynamics section (default: none; a missing or stale file is "
        "said so in the report, never an error)",
    )
    q.add_argument(
        "--threed",
        metavar="PATH",
        help="threed.json of benchmarks/threed_study.py, each paper scene's section "
        '"2D idealisation against 3D" (default: none; a missing or stale file is said '
        "so in the report, never an error)",
    )
    q.add_argument(
        "--jobs",
        type=_int_in(1, MAX_LOCAL_WORKERS),
        default=MAX_LOCAL_WORKERS,
        metavar="N",
        help="processes computing the load paths and drawing the scenes, 1 to "
        f"{MAX_LOCAL_WORKERS} (default: one per core; results are the same, "
        "run times are measured N at a time)",
    )
    q.set_defaults(func=_cmd_report)

    q = sub.add_parser("bench", help="runtime-versus-error study of every model on a scene")
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--reference",
        default="continuum",
        metavar="MODEL",
        help="reference model (default: continuum at its default level)",
    )
    q.add_argument("--out", default="reports/bench", metavar="DIR", help="output folder")
    _campaign_options(q)
    _load_case_option(q)
    q.add_argument("--no-batch", action="store_true", help=NO_BATCH_HELP)
    q.set_defaults(func=_cmd_bench)

    q = sub.add_parser("stress", help="stress tests: load amplification, step count, invariance")
    q.add_argument("scene", help=scene_help)
    q.add_argument(
        "--model",
        action="append",
        metavar="MODEL",
        help="models to stress (repeatable; default: ee, dcmm:1, dcmm:2, prbm, beam:20)",
    )
    q.add_argument(
        "--quick",
        action="store_true",
        help="small study: loads up to x100, beam:40 reference, no 1001-level run",
    )
    q.add_argument("--out", default="reports/stress", metavar="DIR", help="output folder")
    q.add_argument("--quiet", action="store_true", help="no progress lines")
    _load_case_option(q)
    q.set_defaults(func=_cmd_stress)

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
        type=_int_in(1, MAX_LOCAL_WORKERS),
        metavar="N",
        help=f"local cluster size, 1 to {MAX_LOCAL_WORKERS} (the logical CPUs; "
        "default: one single-threaded process per core)",
    )
    q.add_argument(
        "--max-points",
        type=_int_in(1, 10**15),
        metavar="N",
        help="most points the sweep may have (default 1,000,000): the count is computed "
        "from the axes before any point is built, and a larger sweep is refused",
    )
    q.add_argument(
        "--batch",
        type=_int_in(1, 100_000),
        metavar="N",
        help="points per task of a reduced model (default: the sweep's, or about "
        "4 tasks per worker and model, at most 25 points each)",
    )
    q.add_argument(
        "--no-cache", action="store_true", help="recompute reference paths even if cached"
    )
    q.add_argument("--quiet", action="store_true", help="no progress lines")
    q.set_defaults(func=_cmd_sweep)

    q = sub.add_parser(
        "gate",
        help="accuracy gates for CI: exit 1 when a model's error exceeds its threshold",
    )
    q.add_argument("gates", metavar="GATES.toml", help="gates file (see the gates file reference)")
    q.add_argument("--junit", metavar="PATH", help="also write the checks as JUnit XML")
    q.add_argument("--json", metavar="PATH", help="also write the checks as JSON")
    q.add_argument(
        "--cache",
        metavar="DIR",
        help="result cache folder kept between CI runs (default: $FLEXVAL_CACHE, else "
        "~/.cache/flexval)",
    )
    q.add_argument(
        "--prepare",
        action="store_true",
        help="only compute the results into the cache (paths, critical loads, natural "
        "frequencies; the reference's and the built-in models'); no verdict",
    )
    q.add_argument(
        "--workers",
        type=_int_in(1, MAX_LOCAL_WORKERS),
        metavar="N",
        help=f"processes computing paths, 1 to {MAX_LOCAL_WORKERS} (default: one per core)",
    )
    q.add_argument("--quiet", action="store_true", help="no progress bar")
    q.set_defaults(func=_cmd_gate)
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
        from .interrupt import install
        from .process import discard_output_when_reader_leaves

        install()  # SIGINT/SIGTERM: orderly stop, exit 130/143 (flexval.validation.interrupt)
        discard_output_when_reader_leaves()
    try:
        args = build_parser().parse_args(argv)
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            status = _dispatch(args)
    except BaseException:
        from .interrupt import finish, received

        if received() is None:
            raise
        finish(received())  # ends the process: 128 + the signal number
    if argv is None:
        from .interrupt import uninstall
        from .process import end_process

        uninstall()
        end_process(status)
    return status


def _dispatch(args: argparse.Namespace) -> int:
    """Run the chosen command; bad input, solver and output failures become exit codes."""
    from flexval.reducedmodels.threads import ENV_VARIABLE, RULE, request_threads

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


if __name__ == "__main__":
    sys.exit(main())
