"""Relative accuracy with two fixtures (the report's §2.8): per placement and overall.

At each placement of the two fixtures the robot is homed at the first, moved to the second
(whose teach-pendant coordinates P are recorded, home set again), and commanded back by −P; the
first fixture's indicators then read the robot's error per axis. The report analyses these
"similar to ... repeatability" (§2.8.3) and asks to "evaluate the overall average accuracy in the
direction of each axis". So:

* **overall**: every reading of x, y, z with the repeatability statistics, capability, control
  chart and rules, the 3-D figures (:func:`~station.analysis.summary.analyze`);
* the **3-D error** of each reading, sqrt(x² + y² + z²) (the report's total), and its statistics;
* **per placement**: the same analysis of that placement's readings, its pendant coordinates and
  the distance moved (sqrt(X² + Y² + Z²));
* **across placements**: per axis the placement means, their average (the overall average
  accuracy in the direction of the axis) and their spread (sample σ and range: how the accuracy
  varies over the work envelope); and, with pendant coordinates at 3 or more placements, the
  error per unit moved: the least-squares map e = M·P (no intercept: no move, no error), whose
  diagonal is the scale error of each axis and whose off-diagonal terms show a rotation.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from station.analysis.document import channel_to_json, json_number
from station.analysis.summary import (
    Analysis,
    AnalysisConfig,
    ChannelAnalysis,
    analyze,
    analyze_channel,
)
from station.errors import StationError

AXES = ("x", "y", "z")
#: The name of the 3-D error channel.
ERROR_3D = "3d"


@dataclass(frozen=True)
class PlacementResult:
    """One placement: its readings' analysis, mean error per axis and mean 3-D error, and the
    pendant coordinates (None when not recorded) with the distance moved."""

    number: int
    n: int
    mean: Mapping[str, float]
    sd: Mapping[str, float | None]
    error_3d: float
    pendant: tuple[float, float, float] | None
    distance: float | None
    analysis: Analysis


@dataclass(frozen=True)
class AccuracyAnalysis:
    """Relative accuracy overall, per placement and across placements (see the module).

    ``average``/``spread``/``span`` are per axis the mean, sample σ (None with one placement)
    and range of the placement means. ``per_unit`` is the 3×3 error-per-unit-moved map M (rows:
    error axis, columns: pendant axis) and ``scale_error`` its diagonal, both None without
    pendant coordinates at 3 or more placements.
    """

    overall: Analysis
    error_3d: ChannelAnalysis
    placements: tuple[PlacementResult, ...]
    average: Mapping[str, float]
    spread: Mapping[str, float | None]
    span: Mapping[str, float]
    per_unit: tuple[tuple[float, float, float], ...] | None
    scale_error: Mapping[str, float] | None


def _pendant(value: Any) -> tuple[float, float, float]:
    coordinates = tuple(float(v) for v in value)
    if len(coordinates) != 3 or not all(np.isfinite(coordinates)):
        raise StationError(
            f"pendant coordinates must be three finite numbers X, Y, Z, not {value}."
        )
    x, y, z = coordinates
    return x, y, z


def analyze_accuracy(
    placements: Sequence[int] | Any,
    errors: Mapping[str, Any],
    config: AnalysisConfig,
    *,
    pendant: Mapping[int, Sequence[float]] | None = None,
    excluded_cycles: Sequence[int] = (),
) -> AccuracyAnalysis:
    """Analyse the indicator errors ``errors`` (x, y, z: one reading per row) whose rows belong
    to the fixture placements ``placements`` (numbers, one per row). ``pendant`` maps a
    placement number to the teach pendant's X, Y, Z there.
    """
    missing = [axis for axis in AXES if axis not in errors]
    if missing:
        raise StationError(
            f"relative accuracy needs the indicator errors x, y and z; {missing[0]!r} is missing."
        )
    numbers = np.asarray(placements, dtype=float).ravel()
    arrays = {axis: np.asarray(errors[axis], dtype=float).ravel() for axis in AXES}
    if numbers.size == 0:
        raise StationError("there are no readings to analyse.")
    for axis, values in arrays.items():
        if values.size != numbers.size:
            raise StationError(
                f"channel {axis!r} has {values.size} readings but there are {numbers.size} rows."
            )
    if np.any(numbers != np.round(numbers)):
        raise StationError("the placement column must hold whole numbers (1, 2, 3, ...).")
    pendant_at = {int(k): _pendant(v) for k, v in (pendant or {}).items()}

    overall = analyze(arrays, config, excluded_cycles=excluded_cycles)
    total = np.sqrt(sum(values**2 for values in arrays.values()))
    # The 3-D error is a length: no two-sided limits apply; its nominal (the ideal) is 0.
    total_config = replace(config, limits={}, default_limits=None, nominal={ERROR_3D: 0.0})
    error_3d = analyze_channel(ERROR_3D, total, total_config)

    results = []
    for number in dict.fromkeys(numbers.astype(int).tolist()):
        rows = numbers == number
        chosen = {axis: values[rows] for axis, values in arrays.items()}
        coordinates = pendant_at.get(number)
        results.append(
            PlacementResult(
                number=number,
                n=int(rows.sum()),
                mean={axis: float(v.mean()) for axis, v in chosen.items()},
                sd={
                    axis: float(v.std(ddof=1)) if v.size > 1 else None for axis, v in chosen.items()
                },
                error_3d=float(total[rows].mean()),
                pendant=coordinates,
                distance=None if coordinates is None else float(np.linalg.norm(coordinates)),
                analysis=analyze(chosen, config),
            )
        )
    means = {axis: np.asarray([r.mean[axis] for r in results]) for axis in AXES}
    per_unit: tuple[tuple[float, float, float], ...] | None = None
    located = [r for r in results if r.pendant is not None]
    if len(located) >= 3:
        moves = np.asarray([r.pendant for r in located])
        observed = np.asarray([[r.mean[axis] for axis in AXES] for r in located])
        if np.linalg.matrix_rank(moves) == 3:
            # observed ≈ moves @ M.T: one least-squares problem per error axis.
            solution, *_ = np.linalg.lstsq(moves, observed, rcond=None)
            per_unit = tuple((float(a), float(b), float(c)) for a, b, c in solution.T)
    return AccuracyAnalysis(
        overall=overall,
        error_3d=error_3d,
        placements=tuple(results),
        average={axis: float(m.mean()) for axis, m in means.items()},
        spread={axis: float(m.std(ddof=1)) if m.size > 1 else None for axis, m in means.items()},
        span={axis: float(np.ptp(m)) for axis, m in means.items()},
        per_unit=per_unit,
        scale_error=None
        if per_unit is None
        else {axis: per_unit[i][i] for i, axis in enumerate(AXES)},
    )


def accuracy_json(result: AccuracyAnalysis) -> dict[str, Any]:
    """The ``"accuracy"`` document of ``station analyze --json``: per axis across placements,
    each placement, the 3-D error's statistics, and the error per unit moved."""
    return {
        "axes": {
            axis: {
                "average": json_number(result.average[axis]),
                "spread": json_number(result.spread[axis]),
                "range": json_number(result.span[axis]),
                "scale_error": None
                if result.scale_error is None
                else json_number(result.scale_error[axis]),
            }
            for axis in AXES
        },
        "placements": [
            {
                "placement": p.number,
                "n": p.n,
                "pendant": None
                if p.pendant is None
                else {axis: json_number(v) for axis, v in zip(AXES, p.pendant, strict=True)},
                "distance": json_number(p.distance),
                "mean": {axis: json_number(v) for axis, v in p.mean.items()},
                "sd": {axis: json_number(v) for axis, v in p.sd.items()},
                "error_3d": json_number(p.error_3d),
            }
            for p in result.placements
        ],
        "error_3d": channel_to_json(result.error_3d),
        "per_unit": None
        if result.per_unit is None
        else [[json_number(v) for v in row] for row in result.per_unit],
    }
