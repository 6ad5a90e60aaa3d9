"""A batch's process keeps freed memory for its next temporaries; where memory comes from
changes no result.

The thresholds are set once per process, so each case runs in a fresh one.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

BATCH = """
import json, sys
from flexval.geometry import load_scene
from flexval.reducedmodels.core import allocator
from flexval.reducedmodels.core.batch import run_batch
from flexval.reducedmodels.catalogue import parse_model

sc = load_scene("open_chain")
case = next(c for c in sc.load_cases if c.name == "f+")
paths = run_batch([sc.mechanism] * 40, parse_model(sys.argv[1]), [case] * 40)
print(json.dumps({
    "applied": allocator._applied,
    "paths": [[p.dx, p.dy, p.rotation, p.peak_stress, p.stats["iterations"]] for p in paths],
}))
"""


def _batch_in_a_fresh_process(model: str, malloc: str | None) -> dict:
    import os

    env = {k: v for k, v in os.environ.items() if k != "FLEXVAL_MALLOC"}
    if malloc is not None:
        env["FLEXVAL_MALLOC"] = malloc
    done = subprocess.run(
        [sys.executable, "-c", BATCH, model],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
        env=env,
    )
    return json.loads(done.stdout)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt: Linux")
@pytest.mark.parametrize("model", ["prbm", "dcmm:1"])
def test_a_batch_raises_the_malloc_thresholds_and_its_paths_do_not_change(model):
    """The first batch raises glibc's thresholds (FLEXVAL_MALLOC=system leaves them), and a
    batch's paths are the same bit for bit either way."""
    tuned = _batch_in_a_fresh_process(model, None)
    system = _batch_in_a_fresh_process(model, "system")
    assert tuned["applied"] is True
    assert system["applied"] is False
    assert tuned["paths"] == system["paths"]
