"""``flexval run``: its arguments and what it does."""

from __future__ import annotations

import argparse
import math
import sys

from flexval.geometry import SceneError, load_scene
from flexval.geometry.errors import COMMAND_LINE

from ..outputs import (
    check_file,
    check_folder,
    output_path,
    write_json,
)
from ..report.tables import GAP, SIG_WIDTH, Column, header, sig, text_row
from .common import (
    EXIT_OK,
    EXIT_SOLVER,
    ParserContext,
    check_memory,
    keep_cached,
    parse_models,
)


def _check_load_levels(levels: int | None) -> None:
    """``--levels`` of ``run``: 2 .. the solver's sub-step cap (one sub-step per increment)."""
    from flexval.reducedmodels.core.settings import SolverSettings

    cap = SolverSettings().max_substeps
    if levels is not None and not 2 <= levels <= cap:
        raise SceneError(
            COMMAND_LINE,
            "--levels",
            levels,
            f"must be from 2 to {cap} (each of the levels - 1 load increments "
            f"takes at least one of the solver's {cap} sub-steps)",
        )


def _run_request(args: argparse.Namespace, scene) -> tuple[list, list, frozenset]:
    """The models, load cases and stress-field outputs ``flexval run`` is asked for, checked."""
    from flexval.reducedmodels.catalogue import FIELDS, families

    specs = parse_models(args.model or [], COMMAND_LINE, "--model")
    if not specs:
        specs = parse_models(scene.models, scene.source, "request.models")
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
        from ..studies.limits import check_arclength

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
    (:func:`flexval.validation.studies.yieldpoint.path_yield`)."""
    from ..studies.yieldpoint import scene_yield

    return {**lp.to_dict(), **(scene_yield(scene, lp) or {})}


def _yield_line(scene, lp) -> str | None:
    """The run table's line on first yield and safety factor (None without a yield strength)."""
    from ..studies.yieldpoint import scene_yield

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


def _uncalibrated_notes(scene, specs) -> list[str]:
    """A note per notch hinge outside the calibrated range of the reduced models' correction
    (:mod:`flexval.reducedmodels.notchcorrection`), where a reduced model without ``eb``
    runs: its factors are the nearest calibrated hinge's, not its own; and per taper
    steeper than :data:`~flexval.reducedmodels.core.validity.TAPER_SLOPE`, where a
    reduced model runs."""
    from flexval.reducedmodels.core.validity import TAPER_SLOPE, TAPER_STIFFENING, taper_slope
    from flexval.reducedmodels.notchcorrection import factors_of, takes_correction

    notes = []
    if any(s.family != "continuum" for s in specs):
        for flexure in scene.mechanism.flexures:
            slope = taper_slope(flexure.section)
            if slope is not None and slope > TAPER_SLOPE:
                notes.append(
                    f"note: taper {flexure.name} has a contour slope of {slope:.3g} rad: "
                    f"beyond {TAPER_SLOPE:.2g} rad beam theory's section integrals are more "
                    "than 0.5 % stiffer than 2D elasticity (about "
                    f"{100 * TAPER_STIFFENING * slope**2:.2g} % here under a moment), and the "
                    "reduced models do not correct it (compare with the continuum)"
                )
    if not any(takes_correction(s) for s in specs):
        return notes

    for flexure in scene.mechanism.flexures:
        found = factors_of(flexure, scene.mechanism.material.poisson_ratio)
        if found is not None and not found.inside:
            notes.append(
                f"note: notch hinge {flexure.name} ({found.where}) lies outside the range the "
                "reduced models' 2D correction is calibrated on: they take the nearest "
                "calibrated hinge's factors (compare with the continuum, or [eb])"
            )
    return notes


def run(args: argparse.Namespace) -> int:
    """``flexval run``: trace load paths with one or more models; returns the exit code."""
    from flexval.reducedmodels.catalogue import FIELDS

    from ..cache import ResultCache, result_key
    from ..run import run_model

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
    estimate = check_memory(  # a dynamic run's memory too; its time is estimated apart
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
    keep_cached(cache.enabled and not args.arclength)
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
        from ..series import write_series

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
            from ..studies.limits import DEFAULT_STEPS, trace_arclength

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
        return cache.path(key, lambda: run_model(scene, spec, case, args.levels, **record, **extra))

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
    from ..resources import long_seconds
    from ..studies.campaign import level_progress

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
    from ..report.drivereaction import along_drive, zero_crossings

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
    from ..studies.dynamic import run_dynamic
    from ..studies.modes import choose_density

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

    from ..resources import long_seconds
    from ..studies.dynamic import describe, estimate_dynamic, time_progress

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
        from ..studies.limits import DEFAULT_STEPS

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


FIBRE_MARK = "*"
"""Marks a run line's peak stress that is a notch's surface fibre stress (the continuum's,
or a reduced model's beam formula times the calibrated stress concentration K(s))."""


def _fibre_note(lp) -> str:
    """What a run line's :data:`FIBRE_MARK` means for ``lp``'s model."""
    if lp.model.startswith("continuum"):
        return (
            "the continuum's surface fibre stress at the notch, stress concentration "
            "included (elsewhere the beam formula of its section forces)"
        )
    return (
        "the notch's surface fibre stress: the largest of the beam formula times the "
        "notch's stress concentration K(s) along it, calibrated against the continuum"
    )


def _peak_cells(lp, scene) -> tuple[str, str]:
    """``peak MPa`` and ``at`` of a run line: the largest peak stress over the flexures at the
    last level (:func:`flexval.validation.studies.yieldpoint.flexure_peaks`, marked with
    :data:`FIBRE_MARK` where it is a notch's surface fibre stress) and where
    (``flexure@fraction`` of its length from its first end)."""
    from ..studies.yieldpoint import flexure_peaks

    peaks = flexure_peaks(lp)
    if not peaks:
        return "-", ""
    name = max(peaks, key=lambda f: peaks[f][0][-1])
    values, places, fibre = peaks[name]
    return sig(values[-1]) + (FIBRE_MARK if fibre else ""), f"{name}@{places[-1]:.2f}"


def add_parser(sub, context: ParserContext) -> None:
    """Declare ``flexval run``, its arguments and options."""
    ids = context.ids
    scene_help = context.scene_help
    from ..resources import LONG_ENV, LONG_SECONDS

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
    q.set_defaults(func=run)
