"""Tolerance studies: the distribution of each output, and of each model's errors, over the
random points of a sweep.

A sweep whose every axis is random (``sample = "normal"`` and the like) is a Monte Carlo
tolerance study: its points are draws of the uncertain parameters. For each model (the
reference included) and load case, :func:`study` gives the distribution of

* the target displacement |u| at full load (mm; from the rows' ``target_dx`` and
  ``target_dy``), the target rotation at full load (rows: ``target_rotation``, rad;
  reported in degrees) and the peak stress at full load (``peak_stress``, MPa), over the
  rows that reached full load (status ``ok``);
* the limit load (``limit_load``, N or N mm), over the rows whose run stopped at a limit
  point below full load;

and, for each compared model, the distribution of its errors against the reference (percent:
``end_disp_vec``, ``end_rot``, and ``peak_stress_error`` / ``limit_load_error`` with those
outputs) over the rows that carry them. The reference may run on a subsample of the points
(:attr:`flexval.validation.sweep.spec.Sweep.reference_sample`): a row without a value is
left out, and every distribution says over how many rows (``n``) of how many (``rows``) it
is taken.

The statistics (:func:`distribution`): mean; standard deviation with ``ddof = 1`` (the
unbiased variance of a sample); the 1st, 50th and 99th percentiles by
:func:`numpy.percentile` with ``method = "linear"`` (Hyndman and Fan's definition 7, numpy's
default: linear interpolation between order statistics). With 20 draws the 1st and 99th
percentiles are interpolations between the two smallest and the two largest values: they
describe the sample, not the population's tails, which a tolerance study of a few dozen
points cannot resolve.

The functions here take a sweep's rows (dicts, or
:class:`~flexval.validation.sweep.columns.Columns`) or numpy arrays and return plain dicts;
:func:`rounded` turns them into what the summary writes
(:data:`SIGNIFICANT` significant digits, None for an undefined value: never a NaN).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .columns import Columns, Rows

PERCENTILES = (1.0, 50.0, 99.0)
"""The percentiles reported (percent)."""
PERCENTILE_METHOD = "linear"
"""``numpy.percentile``'s method: linear interpolation between order statistics (H&F 7)."""
DDOF = 1
"""Delta degrees of freedom of the standard deviation: the sample's (n - 1) estimate."""
SIGNIFICANT = 4
"""Significant digits of every number the summary writes: the sampling error of a mean over
n draws is std / sqrt(n), a few per mille of the value for a tolerance of a few percent and a
few dozen draws, so a fifth digit would be noise."""
STAT_KEYS = ("mean", "std") + tuple(f"p{p:g}" for p in PERCENTILES)
"""The statistics of one distribution besides its counts, in the order of the tables."""
TARGET_COLUMNS = ("target_dx", "target_dy", "target_rotation")
"""The row columns of the target's displacement (mm, mm) and rotation (rad) at full load."""


def target_columns(path: Any) -> dict[str, float]:
    """The row columns :data:`TARGET_COLUMNS` of a converged load path: the target's
    displacement (mm) and rotation (rad) at its last level, full load.

    Parameters
    ----------
    path : flexval.reducedmodels.LoadPath
        A path that reached full load.
    """
    return {
        "target_dx": float(path.dx[-1]),
        "target_dy": float(path.dy[-1]),
        "target_rotation": float(path.rotation[-1]),
    }


@dataclass(frozen=True)
class Quantity:
    """One distributed quantity: its name (JSON key, figure file), its label and unit as
    written, and how the rows give it (NaN: a row has none)."""

    name: str
    label: str
    unit: str
    values: Callable[[Columns], np.ndarray]
    needs: tuple[str, ...]
    """The row columns it is computed from."""


def _col(column: str) -> Callable[[Columns], np.ndarray]:
    """A column's values (NaN: missing or not finite)."""
    return lambda table: table.floats(column)


def _converged(column: str) -> Callable[[Columns], np.ndarray]:
    """A column's values in the rows that reached full load."""
    return lambda table: np.where(table.ok(), table.floats(column), np.nan)


def _displacement(table: Columns) -> np.ndarray:
    dx, dy = _converged("target_dx")(table), _converged("target_dy")(table)
    return np.hypot(dx, dy)  # NaN where either is


def _rotation_deg(table: Columns) -> np.ndarray:
    return np.degrees(_converged("target_rotation")(table))


OUTPUTS = (
    Quantity("displacement", "target displacement |u|", "mm", _displacement, TARGET_COLUMNS[:2]),
    Quantity("rotation", "target rotation", "deg", _rotation_deg, TARGET_COLUMNS[2:]),
    Quantity("peak_stress", "peak stress", "MPa", _converged("peak_stress"), ("peak_stress",)),
    Quantity("limit_load", "limit load", "N or N mm", _col("limit_load"), ("limit_load",)),
)
"""The outputs whose distribution a tolerance study gives (displacement, rotation and peak
stress at full load; the limit load of a run that stopped at one)."""
ERRORS = (
    Quantity("end_disp_vec", "end displacement error", "%", _col("end_disp_vec"), ()),
    Quantity("end_rot", "end rotation error", "%", _col("end_rot"), ()),
    Quantity(
        "peak_stress_error",
        "peak stress error",
        "%",
        _col("peak_stress_error"),
        ("peak_stress",),
    ),
    Quantity(
        "limit_load_error",
        "limit load error",
        "%",
        _col("limit_load_error"),
        ("limit_load",),
    ),
)
"""The errors against the reference (percent; the peak stress and limit load errors signed)
whose distribution a tolerance study gives; ``needs`` names the sweep output they come with."""


def distribution(values: Iterable[float | None] | np.ndarray) -> dict[str, Any]:
    """The statistics of the finite values among ``values`` (None and NaN are missing).

    Parameters
    ----------
    values : iterable of float or None, or array
        One quantity over the rows (in its unit).

    Returns
    -------
    dict
        ``n`` (the finite values counted), ``mean``, ``std`` (ddof :data:`DDOF`) and the
        percentiles ``p1``, ``p50``, ``p99`` (:data:`PERCENTILES`, method
        :data:`PERCENTILE_METHOD`), in the values' unit; each None where it is undefined
        (no value; the standard deviation of fewer than two).
    """
    if isinstance(values, np.ndarray) and values.dtype.kind == "f":
        a = values.ravel()
    else:
        a = np.array([np.nan if v is None else v for v in values], dtype=float).ravel()
    a = a[np.isfinite(a)]
    out: dict[str, Any] = {"n": int(a.size)}
    if a.size == 0:
        return out | {k: None for k in STAT_KEYS}
    q = np.percentile(a, PERCENTILES, method=PERCENTILE_METHOD)
    out["mean"] = float(np.mean(a))
    out["std"] = float(np.std(a, ddof=DDOF)) if a.size > DDOF else None
    out.update({f"p{p:g}": float(v) for p, v in zip(PERCENTILES, q)})
    return out


def samples(
    rows: Rows,
    models: Sequence[str],
    cases: Sequence[str],
    quantity: Quantity,
) -> dict[str, dict[str, tuple[np.ndarray, int]]]:
    """{model: {case: (the quantity's finite values, the number of rows)}} over ``rows``.

    Rows of other models or cases, and rows of invalid points (model ``-``), are left out.
    """
    table = Columns.of(rows)
    values = quantity.values(table)
    out = {}
    for m in models:
        out[m] = {}
        for c in cases:
            chosen = values[table.rows_of(m, c)]
            out[m][c] = (chosen[np.isfinite(chosen)], int(chosen.size))
    return out


def study(
    rows: Rows,
    reference: str,
    models: Sequence[str],
    cases: Sequence[str],
    quantities: Sequence[Quantity] = OUTPUTS,
    errors: Sequence[Quantity] = ERRORS,
) -> dict[str, Any]:
    """The tolerance study of a sweep's rows (unrounded; see :func:`rounded`).

    Parameters
    ----------
    rows : sequence of dict or Columns
        The sweep's result rows (any subset of the store's columns).
    reference : str
        The reference model's id: its outputs are distributed, its errors are not.
    models : sequence of str
        The compared models' ids.
    cases : sequence of str
        The load cases.
    quantities, errors : sequence of Quantity
        The outputs and the error metrics to distribute.

    Returns
    -------
    dict
        ``{"percentile_method", "ddof", "outputs": {quantity: {"label", "unit",
        "models": {model: {case: distribution + "rows"}}}}, "errors": {...} (the compared
        models only)}``; a quantity's unit is that of its values (the limit load's is the
        load case's ``load_unit``, N or N mm, in ``"units"`` per case).
    """
    everyone = [reference, *models]
    table = Columns.of(rows)
    units = table.units(cases)

    def section(qs: Sequence[Quantity], who: Sequence[str]) -> dict[str, Any]:
        out = {}
        for q in qs:
            per = samples(table, who, cases, q)
            entry: dict[str, Any] = {"label": q.label, "unit": q.unit, "models": {}}
            if q.name == "limit_load":
                entry["units"] = {c: units.get(c) for c in cases}
            for m, by_case in per.items():
                entry["models"][m] = {
                    c: distribution(v) | {"rows": n} for c, (v, n) in by_case.items()
                }
            out[q.name] = entry
        return out

    return {
        "percentile_method": PERCENTILE_METHOD,
        "ddof": DDOF,
        "outputs": section(quantities, everyone),
        "errors": section(errors, list(models)),
    }


def significant(x: float | None, digits: int = SIGNIFICANT) -> float | None:
    """``x`` rounded to ``digits`` significant digits (None for None or a non-finite value)."""
    if x is None or not math.isfinite(x):
        return None
    return float(f"{x:.{digits}g}")


def rounded(data: Any) -> Any:
    """``data`` (a :func:`study`) with every float rounded by :func:`significant`."""
    if isinstance(data, float):
        return significant(data)
    if isinstance(data, dict):
        return {k: rounded(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [rounded(v) for v in data]
    return data


def recorded(section: dict[str, Any]) -> dict[str, Any]:
    """The quantities of a study's ``outputs`` or ``errors`` that some row carries."""
    return {
        name: q
        for name, q in section.items()
        if any(d["n"] for per in q["models"].values() for d in per.values())
    }


def _cell(x: float | None) -> str:
    return "–" if x is None else f"{x:.{SIGNIFICANT}g}"


def _table(entry: dict[str, Any], cases: Sequence[str]) -> list[str]:
    """A Markdown table of one quantity: a line per model and load case (the limit load's
    case with its unit)."""
    units = entry.get("units") or {}
    lines = [
        f"| model | load case | n / rows | {' | '.join(STAT_KEYS)} |",
        "|---|---|---:|" + "---:|" * len(STAT_KEYS),
    ]
    for m, per in entry["models"].items():
        for c in cases:
            d = per[c]
            case = f"{c} ({units[c]})" if units.get(c) else c
            cells = " | ".join(_cell(d[k]) for k in STAT_KEYS)
            lines.append(f"| {m} | {case} | {d['n']} / {d['rows']} | {cells} |")
    return lines


def markdown(data: dict[str, Any], cases: Sequence[str], reference: str) -> list[str]:
    """Markdown lines of a study: one table per recorded output and error metric."""
    method = data["percentile_method"]
    lines = [
        "",
        "## Tolerance study",
        "",
        "Every axis is a random draw: the distribution over the points of each output at "
        "full load (rows that reached it) and of the limit load (rows that stopped at "
        "one), per model and load case, and of each model's errors against "
        f"`{reference}` over the rows that carry them. *n / rows*: the values counted / "
        f"the rows of that model and case. std: sample standard deviation (ddof "
        f"{data['ddof']}); p1, p50, p99: percentiles (numpy, method `{method}`). "
        f"Histograms: `tolerance_<quantity>.png`; the numbers also in `tolerance.json`.",
    ]
    outputs, errors = recorded(data["outputs"]), recorded(data["errors"])
    missing = [q["label"] for n, q in data["outputs"].items() if n not in outputs]
    for title, section in (("Outputs", outputs), (f"Errors against `{reference}`", errors)):
        for entry in section.values():
            unit = "load case unit" if entry.get("units") else entry["unit"]
            lines += ["", f"### {title}: {entry['label']} ({unit})", ""]
            lines += _table(entry, cases)
    if missing:
        lines += ["", f"No row carries: {', '.join(missing)}."]
    return lines
