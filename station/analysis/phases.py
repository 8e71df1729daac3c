"""Phase I / phase II control limits (``reference/spc-extensions.md`` §2–§3).

Phase I estimates the limits from a first set of points and judges them retrospectively: a point
can change status as data arrive. Phase II fixes the limits (frozen after the first k points, or
taken from a baseline) and judges each new point against them, so a signal never disappears.
Live alarms are phase II: :class:`~station.analysis.monitor.LiveMonitor` raises them as readings
arrive, and :func:`phase_two_alarms` gives the same set over all points in one pass.

Beside the run rules, phase II watches the mean with an EWMA about the frozen centre line
(λ = 0.2, L = 3; σ the frozen point sigma): a slow drift, such as a robot warming up, shows there
long before a single point leaves the control limits.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

from station.analysis.constants import SIGMA_MULTIPLE
from station.analysis.diagnostics import (
    EWMA_LAMBDA,
    EWMA_WIDTH,
    ewma_limit_half_widths,
    ewma_values,
)
from station.analysis.rules import Alarm, PointCycles, check_rules, cycle_subject, flag_runs
from station.errors import StationError
from station.text import format_figure

if TYPE_CHECKING:
    import numpy as np

#: Chart points after which the live limits freeze when the procedure names no minimum count.
DEFAULT_FREEZE_AFTER = 20


@dataclass(frozen=True)
class FrozenLimits:
    """Phase II control limits of one channel's location chart: centre line, UCL and LCL of the
    plotted points (individuals or subgroup means), and where they came from (``source``:
    "frozen after the first 20 points", "baseline of robot R7 ..."). They never move once set."""

    center: float
    ucl: float
    lcl: float
    source: str = ""

    def __post_init__(self) -> None:
        for name in ("center", "ucl", "lcl"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise StationError(f"the baseline's {name} {value!r} is not a finite number.")
        if not self.lcl < self.center < self.ucl:
            raise StationError(
                f"baseline limits LCL {format_figure(self.lcl, None)} < centre "
                f"{format_figure(self.center, None)} < UCL {format_figure(self.ucl, None)} "
                "do not hold: give a centre line between the limits."
            )

    @property
    def point_sigma(self) -> float:
        """The sigma of a plotted point the limits imply, (UCL − centre)/3."""
        return (self.ucl - self.center) / SIGMA_MULTIPLE


@dataclass(frozen=True)
class ControlBaseline:
    """Fixed control limits per channel (a robot's baseline, e.g. from its last accepted
    session): the live analysis judges every reading against them from the first one."""

    limits: Mapping[str, FrozenLimits] = field(default_factory=dict)
    source: str = ""
    """Where the baseline comes from, for the session header and the report."""

    def limits_for(self, channel: str) -> FrozenLimits | None:
        """The channel's limits, naming the baseline's source when they name none."""
        found = self.limits.get(channel)
        if found is None or found.source or not self.source:
            return found
        return replace(found, source=self.source)


@dataclass(frozen=True)
class EwmaAlarms:
    """The EWMA alarms of a run of points, and the EWMA state after the last point (its value
    and, while it is beyond a limit, the point where that run began)."""

    alarms: tuple[Alarm, ...]
    state: float | None
    run_start: int | None
    side: int = 0


def ewma_alarm(
    points: Sequence[int],
    cycles: tuple[int, ...],
    value: float,
    half_width: float,
    frozen: FrozenLimits,
    unit: str | None,
    resolution: float | None = None,
) -> Alarm:
    """One EWMA alarm over consecutive flagged ``points`` (1-based), with the cycles behind
    them (ascending, each once; empty when unknown) and the EWMA ``value`` and limit
    ``half_width`` at its last point. Its sentence is written when read."""
    sentence = _EwmaSentence(frozen, unit, (value,), (half_width,), points[-1], resolution)
    return Alarm("ewma", tuple(points), sentence, cycles)


@dataclass(frozen=True)
class _EwmaSentence:
    """Writes the sentence of an EWMA alarm from its points and cycles: the EWMA and its limit
    at the alarm's last point are ``values`` and ``half_widths`` from point ``first_point`` on
    (one writer serves every alarm of a chart)."""

    frozen: FrozenLimits
    unit: str | None
    values: Sequence[float] | np.ndarray
    half_widths: Sequence[float] | np.ndarray
    first_point: int
    resolution: float | None = None

    def __call__(self, alarm: Alarm) -> str:
        frozen, unit = self.frozen, self.unit
        at = alarm.points[-1] - self.first_point
        value, half_width = float(self.values[at]), float(self.half_widths[at])
        above = value > frozen.center
        limit = frozen.center + (half_width if above else -half_width)
        # Written as every figure (one decimal beyond the gauge step), as the run-rule sentences.
        ewma_text = format_figure(value, self.resolution, unit=unit or "")
        limit_text = format_figure(limit, self.resolution, unit=unit or "")
        where = cycle_subject(alarm.cycles) if alarm.cycles else f"Point {alarm.points[-1]}"
        return (
            f"{where}: the EWMA ({ewma_text}) is {'above' if above else 'below'} "
            f"its {'upper' if above else 'lower'} limit ({limit_text}): the mean "
            f"is drifting {'up' if above else 'down'}; let the robot warm up, look for a loose "
            "fixture or gauge, and repeat."
        )


def ewma_alarms(
    points: Sequence[float] | np.ndarray,
    frozen: FrozenLimits,
    cycles: PointCycles,
    *,
    unit: str | None = None,
    resolution: float | None = None,
    lam: float = EWMA_LAMBDA,
    width: float = EWMA_WIDTH,
) -> EwmaAlarms:
    """The EWMA of ``points`` about the frozen centre (z₀ = centre, σ the frozen point sigma):
    one alarm per run of points beyond its limits, its sentence written at the gauge
    ``resolution``."""
    if not len(points):
        return EwmaAlarms((), None, None, 0)
    z = ewma_values(points, frozen.center, lam)
    half = ewma_limit_half_widths(frozen.point_sigma, z.size, lam, width)
    sentence = _EwmaSentence(frozen, unit, z, half, 1, resolution)
    found: list[Alarm] = []
    run_start, side = None, 0
    for direction, flags in ((1, z - frozen.center > half), (-1, frozen.center - z > half)):
        for first, last in flag_runs(flags):
            found.append(
                Alarm("ewma", tuple(range(first + 1, last + 2)), sentence, cycles.span(first, last))
            )
            if last + 1 == z.size:
                run_start, side = first + 1, direction
    # Runs above and below never share a point: ordered by first point, as the chart reads.
    found.sort(key=lambda alarm: alarm.points[0])
    return EwmaAlarms(tuple(found), float(z[-1]), run_start, side)


def phase_two_alarms(
    points: Sequence[float] | np.ndarray,
    frozen: FrozenLimits,
    rule_set: str,
    cycles: PointCycles,
    *,
    unit: str | None = None,
    resolution: float | None = None,
) -> tuple[Alarm, ...]:
    """Every alarm of the points against frozen limits, run rules then the EWMA: the union of
    what the live analysis flags point by point once its limits are frozen."""
    rules = check_rules(
        points,
        frozen.center,
        frozen.point_sigma,
        rule_set,
        unit=unit,
        resolution=resolution,
        cycles=cycles,
    )
    ewma = ewma_alarms(points, frozen, cycles, unit=unit, resolution=resolution)
    return tuple(rules) + ewma.alarms


def baseline_to_json(baseline: ControlBaseline) -> dict[str, object]:
    """A baseline as the session header records it."""
    return {
        "source": baseline.source,
        "limits": {
            channel: {"center": f.center, "ucl": f.ucl, "lcl": f.lcl}
            for channel, f in baseline.limits.items()
        },
    }


def baseline_from_json(value: object) -> ControlBaseline | None:
    """The baseline a session header records (None when it records none). A damaged entry is
    a StationError naming the channel."""
    if not isinstance(value, Mapping):
        return None
    source = str(value.get("source") or "baseline")
    limits: dict[str, FrozenLimits] = {}
    for channel, spec in (value.get("limits") or {}).items():
        try:
            limits[str(channel)] = FrozenLimits(
                float(spec["center"]), float(spec["ucl"]), float(spec["lcl"]), source
            )
        except (KeyError, TypeError, ValueError):
            raise StationError(
                f"the baseline of channel {channel!r} needs numbers center, ucl and lcl."
            ) from None
    return ControlBaseline(limits, source)
