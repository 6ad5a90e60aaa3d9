"""Score the models against a test rig's load–displacement file, from Python.

What it shows
-------------
* the measurement file a rig gives: a CSV with a ``load`` column (N for a force
  case) and the target point's ``dx``, ``dy`` (mm) with their standard
  uncertainties ``dx_std``, ``dy_std``;
* reading and checking it against a load case
  (:func:`flexval.geometry.measured.read_measurement`: a bad cell is refused naming
  its line and column);
* tracing every model through the measured loads and scoring it
  (:func:`flexval.validation.studies.measuredcompare.compare_measurement`, what
  ``flexval compare`` runs), and the figure of the measurement against the models.

The "rig" here is synthetic: ``beam:100`` on the open chain's f+ case, read at
eight unevenly spaced loads as a rig would take them, with a seeded scatter
uniform within ±0.5 % of each column's range. The scores are in percent of the
measured range (the largest distance between two measured displacements, here the
displacement at the largest load): DCMM improves as its arcs are split, and
``beam:20`` lies within the rig's scatter.

Units: mm, N; scores in percent.

Run: ``python examples/rig_measurements.py`` (writes ``rig.csv`` and
``rig_open_chain_f+.png`` into the current folder)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexval.geometry import load_scene
from flexval.geometry.measured import read_measurement
from flexval.reducedmodels import parse_model
from flexval.validation.report.measured import plot, text_lines
from flexval.validation.run import run_model
from flexval.validation.studies.measuredcompare import compare_measurement

RIG_MODEL = "beam:100"
"""The model standing in for the rig."""
SCATTER = 0.005
"""Half-width of the rig's uniform scatter, as a fraction of each column's range."""
FRACTIONS = (0.0, 0.08, 0.2, 0.35, 0.5, 0.7, 0.85, 1.0)
"""The measured loads, as fractions of the case's full load."""
MODELS = ("beam:20", "prbm", "dcmm:1", "dcmm:2", "dcmm:3")


def write_rig_file(path: Path, scene, case) -> Path:
    """A synthetic measurement: ``RIG_MODEL``'s path at ``FRACTIONS`` of the load, scattered."""
    levels = 101  # the fractions above lie on this grid
    lp = run_model(scene, parse_model(RIG_MODEL), case, levels=levels)
    rows = np.rint(np.asarray(FRACTIONS) * (levels - 1)).astype(int)
    rng = np.random.default_rng(11)
    columns = {"load [N]": np.asarray(lp.load)[rows]}
    for name in ("dx", "dy"):
        exact = np.asarray(getattr(lp, name))[rows]
        half = SCATTER * float(np.ptp(exact))
        columns[f"{name} [mm]"] = exact + rng.uniform(-half, half, exact.size)
        columns[f"{name}_std"] = np.full(exact.size, half / np.sqrt(3.0))  # of the uniform
    lines = [",".join(columns)]
    lines += [",".join(f"{v:.6g}" for v in row) for row in zip(*columns.values())]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def main(folder: str | Path = ".") -> dict[str, float]:
    """Write the rig file, score every model against it, draw the figure; each model's
    largest displacement difference (percent of the measured range)."""
    folder = Path(folder)
    scene = load_scene("open_chain")
    case = scene.load_case("f+")
    csv = write_rig_file(folder / "rig.csv", scene, case)
    print(csv.read_text(encoding="utf-8"))
    measurement = read_measurement(csv, case)
    comparison = compare_measurement(scene, measurement, [parse_model(m) for m in MODELS])
    print("\n".join(text_lines(comparison)))
    plot(comparison, folder / "rig_open_chain_f+.png")
    return {s.model: s.errors["disp_max"] for s in comparison.scores}


if __name__ == "__main__":
    main()
