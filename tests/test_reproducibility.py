"""Dynamic runs are bit-reproducible: in one process and from process to process.

``benchmarks/paper_protocol.py`` sets its ramp times in periods of the reference's
first natural mode; the reference (beam:100) has more coordinates than
:data:`flexval.reducedmodels.modes.DENSE_MODES_LIMIT`, so its modes come from ARPACK, whose
default starting vector is drawn from the operating system's entropy. The frequencies
then differed in the 9th digit between processes, and the adaptive time stepping
carried that into end-of-ramp errors that moved by up to 0.8 percentage points from run
to run. Here the same chain (sparse modes, a ramp in periods of them, an adaptive
run) is repeated in one process and in two processes, and every bit must agree.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

RUN = """
import hashlib, json
import numpy as np
from flexval.geometry.timelaw import TimeLaw
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.dynamics import DynamicSettings, Rayleigh, solve_dynamic
from flexval.reducedmodels.models import build_system
from flexval.reducedmodels.modes import DENSE_MODES_LIMIT, natural_modes
from tests.builders import tip_moment
from tests.test_modes import RHO, straight

system = build_system(straight(density=RHO), parse_model("beam:201"))
f = natural_modes(system, count=2).frequencies_hz
ramp = 2.0 / f[0]
histories = []
for _ in range(2):
    lp = solve_dynamic(system, tip_moment(1e-3), TimeLaw("eq15", 0.0, ramp), ramp,
                       Rayleigh.from_ratio(0.05, f[0], f[1]),
                       DynamicSettings(first_step=0.01, max_step=0.05))
    history = np.array([lp.time, lp.dx, lp.dy, lp.rotation])
    histories.append(hashlib.sha256(history.tobytes()).hexdigest())
print(json.dumps({"sparse": system.n_dofs > DENSE_MODES_LIMIT,
                  "frequencies": [x.hex() for x in f], "histories": histories,
                  "steps": lp.stats["steps"], "rejected": lp.stats["rejected_steps"]}))
"""
"""A cantilever beam:201 (603 coordinates: sparse modes), 1e-3 N mm at its tip ramped over
two first periods with 5 % damping: about 30 adaptive steps, a few rejected (the step
size decisions that amplify a difference in the last digits are exercised)."""


def _run_twice_in_two_processes() -> list[dict]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", RUN],
            env=env,
            cwd=ROOT,
            text=True,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        for _ in range(2)
    ]
    outs = []
    for p in procs:
        out, err = p.communicate()
        assert p.returncode == 0, err
        outs.append(json.loads(out))
    return outs


def test_dynamic_run_is_bit_identical_in_one_process_and_across_processes():
    first, second = _run_twice_in_two_processes()
    assert first["sparse"]  # the ARPACK path is the one exercised
    assert first["rejected"] > 0  # and step rejections happen
    assert first["frequencies"] == second["frequencies"]
    assert first["histories"][0] == first["histories"][1]  # same process
    assert first["histories"] == second["histories"]  # another process
