"""flexval ``beam:N`` side by side with OpenSeesPy's corotational beams, in one process.

The models, the orders of timing and what the columns mean are in
:mod:`flexval.validation.studies.peers`. Per load case: both median wall times of the
interleaved runs (model build included), OpenSees' sub-steps per level,
the ratio, the agreement of the end values in per cent (the bar: 0.01 %),
the ratio of the fastest CPU times (``time.process_time``: on a shared
machine wall times also count the time the process waited for a core), and
the back-to-back ("b2b") medians and ratio.

OpenSeesPy is an optional extra: ``pip install -e ".[peers]"`` (on Debian
it needs the system's ``libblas3`` and ``liblapack3``).

Usage: ``python benchmarks/bench_peers.py [SCENE ...] [--n 100] [--repeats 5]``
(default: both built-in scenes, all their load cases).
"""

from __future__ import annotations

import argparse
import statistics
import sys

from flexval.geometry import load_scene
from flexval.validation.studies.peers import (
    AGREEMENT_BAR,
    PeerUnavailable,
    compare_with_opensees,
    geometric_mean,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "scene",
        nargs="*",
        default=["open_chain", "closed_chain"],
        help="built-in scene names or scene TOML files",
    )
    parser.add_argument("--n", type=int, default=100, help="elements per flexure (default 100)")
    parser.add_argument("--repeats", type=int, default=5, help="timing repeats (median)")
    args = parser.parse_args()
    print(
        f"beam:{args.n} against OpenSeesPy, {args.n} corotational elements per flexure; "
        f"median of {args.repeats}, model build included"
    )
    print(
        f"{'scene':<13}{'case':<5}{'flexval ms':>11}{'OpenSees ms':>12}{'substeps':>9}"
        f"{'OpenSees/flexval':>17}{'agree %':>10}{'CPU ratio':>10}"
        f"{'b2b ours':>10}{'b2b OS':>10}{'b2b':>9}"
    )
    rows = []
    for name in args.scene:
        scene = load_scene(name)
        try:
            scene_rows = compare_with_opensees(scene, args.n, args.repeats)
        except PeerUnavailable as exc:
            sys.exit(f"bench_peers: {exc}")
        for row in scene_rows:
            if row.substeps is None:
                print(f"{scene.name:<13}{row.case:<5} {row.reason}")
                continue
            rows.append(row)
            flag = "" if row.agreement <= AGREEMENT_BAR else "  (above the 0.01 % bar)"
            print(
                f"{scene.name:<13}{row.case:<5}{1e3 * statistics.median(row.ours):>11.1f}"
                f"{1e3 * statistics.median(row.theirs):>12.1f}{row.substeps:>9}"
                f"{row.ratio:>16.2f}x{row.agreement:>10.4f}{row.cpu_ratio:>9.2f}x"
                f"{1e3 * statistics.median(row.ours_b2b):>10.1f}"
                f"{1e3 * statistics.median(row.theirs_b2b):>10.1f}{row.b2b_ratio:>8.2f}x{flag}"
            )
    if rows:
        print(
            f"geometric mean OpenSees/flexval: {geometric_mean([r.ratio for r in rows]):.2f}x "
            f"interleaved (fastest CPU times: "
            f"{geometric_mean([r.cpu_ratio for r in rows]):.2f}x), "
            f"{geometric_mean([r.b2b_ratio for r in rows]):.2f}x back to back"
        )


if __name__ == "__main__":
    main()
