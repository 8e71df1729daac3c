"""The live (incremental) analysis behind the capture dashboard: one reading in, figures out.

:meth:`LiveChannel.add` costs the same at the 100 000th reading as at the first: it updates
running sums and returns a :class:`LiveUpdate` with the figures the dashboard shows between
redraws (n, mean, sd, skewness, modes, min, max, range, the chart's centre and limits, Cp/Cpk
and the verdict) and the run-rule alarms the new point raises.

* Mean, sd and the third central moment: Welford's update extended to the third moment
  (Pébay 2008), stable where the naive power sums cancel, on the readings minus the first
  one so that an indicator far from zero keeps its digits.
* Modes: a count per gauge step (per exact value without a resolution) and the set of steps
  tied at the highest count.
* Within sigma and chart limits: the running sum of moving ranges (single readings) or of the
  complete subgroups' ranges or SDs, as :mod:`charts` defines them.
* Capability: the report's indices from the running mean and sd, with the same formulas as
  :func:`capability.capability`.

These running figures equal the batch ones to rounding: 1e-12 relative in the tests, except for
readings far from zero with a very fine spread, where the batch's own two-pass rounding
(about eps·|x|/s) is the larger error and the live form, shifted by its first reading, the
more exact.

**Alarms.** The control limits move with every reading, so a point that was inside the
2-sigma zone at the 10th reading may be outside it at the 30th; a truly incremental alarm list
would have to re-judge old points whenever a limit crosses them. We split the job:

* ``add()`` checks only the windows the new point completes (the last 16 points: the longest
  pattern of any rule set and one more) against the limits as they are now. This is O(1) and
  tells the runner at once that "point 17 is above the upper control limit". The rules it
  returns are exactly the batch alarms that flag the newest point of the same readings (tested
  at every reading); their ``points`` reach back at most 16 points. Later readings move the
  limits and may flag or clear *earlier* points: only the snapshot sees that.
* ``snapshot()`` re-evaluates every rule over all points against the current limits, lazily
  (at most once between two readings, cached) — that is, at most once per redraw. Its alarms,
  like the whole snapshot, are exactly those of the batch :func:`summary.analyze_channel` on
  the same readings, because it *is* that computation on the stored readings.

So the dashboard reads ``snapshot()`` (once per redraw, O(n) in numpy, as drawing the chart
is anyway) and the journal records ``add()``'s alarms as they happen.

**Cycle numbers.** ``add(value, cycle)`` labels each reading with its cycle number (the
default is its position, 1, 2, 3 ...). The alarms of ``add()`` and of ``snapshot()`` list the
cycles they flag in ``Alarm.cycles`` and name them in their sentences, exactly as the batch
:func:`summary.analyze` given the same cycle numbers: a runner that skipped a rejected cycle
records "Cycle 7 is above ..." for the 6th accepted reading without translating positions.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from station.analysis.capability import SpecLimits, capability_indices, cpk_lower_bound
from station.analysis.charts import LARGEST_RANGE_SUBGROUP, chart_type
from station.analysis.constants import SIGMA_MULTIPLE, chart_factors
from station.analysis.descriptive import step_multiple
from station.analysis.diagnostics import EWMA_LAMBDA, EWMA_WIDTH, ewma_limit_half_width
from station.analysis.discrimination import limit_half_width
from station.analysis.phases import (
    ControlBaseline,
    FrozenLimits,
    ewma_alarm,
    ewma_alarms,
)
from station.analysis.rules import Alarm, PointCycles, check_rules
from station.analysis.summary import (
    Analysis,
    AnalysisConfig,
    ChannelAnalysis,
    analyze_channel,
    combine,
)
from station.errors import StationError

#: The points the live rules look back over: the longest pattern of any rule (15 points: report
#: rule 3, Nelson 7) and one more. A run that goes on past its pattern then still shows the point
#: before the newest as flagged, so the alarm overlaps the one already raised and the ledger
#: keeps it as one alarm for the run; with exactly 15 points a 15-point rule saw only the newest
#: point flagged and re-raised the run on every cycle.
RULE_WINDOW = 16


@dataclass(frozen=True)
class LiveUpdate:
    """The figures after one more reading (undefined ones are None).

    ``alarms`` are the rule alarms that flag the new point (its 1-based number is ``n`` for
    single readings; the subgroup's number when a subgroup was just completed), judged against
    the limits as they stand now. An EWMA run that goes on is named by its last two points
    (it was raised whole at its first).
    """

    channel: str
    n: int
    value: float
    mean: float | None
    sd: float | None
    skewness: float | None
    modes: tuple[float, ...]
    min: float | None
    max: float | None
    range: float | None
    sigma_within: float | None
    center: float | None
    ucl: float | None
    lcl: float | None
    cp: float | None
    cpu: float | None
    cpl: float | None
    cpk: float | None
    cpk_lower: float | None
    cp_within: float | None
    cpk_within: float | None
    capable: bool | None
    above_usl: int
    below_lsl: int
    alarms: tuple[Alarm, ...]
    phase: str = "I"
    """"I" while the control limits are being estimated, "II" once they are frozen."""
    frozen: FrozenLimits | None = None
    """The frozen (phase II) limits the alarms are judged against; None in phase I."""
    ewma: float | None = None
    """The EWMA of the chart points about the frozen centre (phase II only)."""
    out_of_spec: str | None = None
    """"above" or "below" when this reading is beyond a specification limit, else None."""


class LiveChannel:
    """Running analysis of one channel; ``add`` is O(1), ``snapshot`` equals the batch result.

    ``config`` gives the channel's limits (none: no capability verdict, as in the batch analysis),
    the resolution, subgroup, rule set, threshold and confidence.
    """

    def __init__(
        self,
        name: str,
        config: AnalysisConfig,
        *,
        freeze_after: int | None = None,
        baseline: FrozenLimits | None = None,
    ) -> None:
        self.name = name
        self.config = config
        self.limits: SpecLimits | None = config.limits_for(name)
        if freeze_after is not None and freeze_after < 2:
            raise ValueError("control limits need at least 2 chart points before they freeze")
        self.freeze_after = freeze_after
        # Phase II: the limits the alarms are judged against, once known; they never move.
        self._frozen: FrozenLimits | None = baseline
        self._ewma: float | None = None
        self._ewma_run_start: int | None = None
        self._ewma_side = 0
        # The readings, their cycles and times: appended in O(1), handed to a snapshot without
        # a copy (see _Growing).
        self._values = _Growing(float)
        self._cycles = _Growing(np.int64)
        self._times = _Growing(float)
        self._untimed = 0  # readings added without a time
        # Moments of the readings minus the first one: readings far from 0 (an indicator not
        # zeroed) would otherwise lose digits in the running mean.
        self._origin = 0.0
        self._shifted_mean = 0.0
        self._m2 = 0.0
        self._m3 = 0.0
        self._min = math.inf
        self._max = -math.inf
        self._above = 0
        self._below = 0
        # Modes: count per gauge step (or per exact value), and the keys tied at the top.
        self._step_counts: dict[float, int] = {}
        self._top_count = 0
        self._top_keys: set[float] = set()
        # Chart: the plotted points (individuals or subgroup means) and the running dispersion.
        self._subgroup = config.subgroup
        self._factors = chart_factors(config.subgroup)
        self._points: list[float] = []
        self._spread_sum = 0.0  # sum of moving ranges, subgroup ranges or subgroup SDs
        self._spread_count = 0
        self._open_group: list[float] = []
        self._points_sum = 0.0
        self._snapshot: ChannelAnalysis | None = None

    @property
    def n(self) -> int:
        """Readings added so far."""
        return len(self._values)

    @property
    def values(self) -> list[float]:
        """A copy of the readings in the order they were added."""
        return self._values.view().tolist()

    @property
    def cycles(self) -> list[int]:
        """A copy of the readings' cycle numbers, in the order they were added."""
        return self._cycles.view().tolist()

    def add(self, value: float, cycle: int | None = None, t: float | None = None) -> LiveUpdate:
        """Add one reading (a finite number) of cycle number ``cycle`` (default: its position,
        1, 2, 3 ...), read at time ``t`` (seconds; the drift's trend runs on reading times when
        every reading has one), and return the updated figures."""
        x = float(value)
        if not math.isfinite(x):
            raise StationError(
                f"{self.name}: reading {len(self._values) + 1} is not a finite number ({value!r})"
            )
        previous = self._values.last()
        self._values.append(x)
        self._cycles.append(len(self._values) if cycle is None else int(cycle))
        self._times.append(math.nan if t is None else float(t))
        self._untimed += t is None
        self._snapshot = None
        n = len(self._values)

        # Welford / Pébay: update the third moment with the old second moment first.
        if n == 1:
            self._origin = x
        delta = (x - self._origin) - self._shifted_mean
        delta_n = delta / n
        term = delta * delta_n * (n - 1)
        self._shifted_mean += delta_n
        self._m3 += term * delta_n * (n - 2) - 3.0 * delta_n * self._m2
        self._m2 += term
        self._min = min(self._min, x)
        self._max = max(self._max, x)
        side = None
        if self.limits is not None:
            if self.limits.usl is not None and x > self.limits.usl:
                self._above += 1
                side = "above"
            if self.limits.lsl is not None and x < self.limits.lsl:
                self._below += 1
                side = "below"
        self._count_mode(x)

        new_point = False
        if self._subgroup == 1:
            self._points.append(x)
            self._points_sum += x
            if previous is not None:
                self._spread_sum += abs(x - previous)
                self._spread_count += 1
            new_point = True
        else:
            self._open_group.append(x)
            if len(self._open_group) == self._subgroup:
                self._close_group()
                new_point = True
        update = self._update(x, new_point)
        if self.freeze_after is None and self._frozen is None:
            # Phase I only (no freeze asked for): limits move with every reading.
            return replace(update, out_of_spec=side)
        alarms: tuple[Alarm, ...] = ()
        if new_point:
            alarms = self._phase_two_alarms(update)
        return replace(
            update,
            alarms=alarms,
            phase="I" if self._frozen is None else "II",
            frozen=self._frozen,
            ewma=self._ewma,
            out_of_spec=side,
        )

    def _count_mode(self, x: float) -> None:
        step = self.config.resolution
        key = float(math.floor(x / step + 0.5)) if step else x
        count = self._step_counts.get(key, 0) + 1
        self._step_counts[key] = count
        if count > self._top_count:
            self._top_count = count
            self._top_keys = {key}
        elif count == self._top_count:
            self._top_keys.add(key)

    def _close_group(self) -> None:
        group = self._open_group
        self._open_group = []
        size = len(group)
        group_mean = sum(group) / size
        if size <= LARGEST_RANGE_SUBGROUP:
            spread = max(group) - min(group)
        else:
            spread = math.sqrt(sum((v - group_mean) ** 2 for v in group) / (size - 1))
        self._points.append(group_mean)
        self._points_sum += group_mean
        self._spread_sum += spread
        self._spread_count += 1

    def modes(self) -> tuple[float, ...]:
        """Every most frequent value at the resolution, ascending; empty when none repeats."""
        if self._top_count < 2:
            return ()
        step = self.config.resolution
        if step:
            return tuple(step_multiple(int(key), step) for key in sorted(self._top_keys))
        return tuple(sorted(self._top_keys))

    def _sigma_within(self) -> float | None:
        if self._spread_count == 0:
            return None
        spread = self._spread_sum / self._spread_count
        kind = chart_type(self._subgroup)
        if kind == "Xbar-S":
            return spread / self._factors.c4
        return spread / self._factors.d2

    def _update(self, x: float, new_point: bool) -> LiveUpdate:
        n = len(self._values)
        mean = self._origin + self._shifted_mean
        sd = math.sqrt(self._m2 / (n - 1)) if n >= 2 else None
        skewness = None
        if n >= 3 and self._m2 > 0:
            skewness = (self._m3 / n) / (self._m2 / (n - 1)) ** 1.5
        within = self._sigma_within()
        center = ucl = lcl = None
        if within is not None:
            center = self._points_sum / len(self._points)
            # Never narrower than the gauge can tell apart, as the batch chart's.
            half_width = limit_half_width(
                within, self._subgroup, self.config.resolution, SIGMA_MULTIPLE
            )
            ucl, lcl = center + half_width, center - half_width
        cp = cpu = cpl = cpk = cpk_lower = cp_within = cpk_within = None
        if self.limits is not None and n >= 2:
            lsl, usl = self.limits.lsl, self.limits.usl
            cp, cpu, cpl, cpk = capability_indices(mean, sd, lsl, usl)
            cp_within, _, _, cpk_within = capability_indices(mean, within, lsl, usl)
            if cpk is not None:
                cpk_lower = cpk_lower_bound(cpk, n, self.config.confidence)
        alarms: tuple[Alarm, ...] = ()
        if new_point and center is not None and ucl is not None and ucl > center:
            alarms = self._newest_point_alarms(center, (ucl - center) / SIGMA_MULTIPLE)
        return LiveUpdate(
            channel=self.name,
            n=n,
            value=x,
            mean=mean,
            sd=sd,
            skewness=skewness,
            modes=self.modes(),
            min=self._min,
            max=self._max,
            range=self._max - self._min,
            sigma_within=within,
            center=center,
            ucl=ucl,
            lcl=lcl,
            cp=cp,
            cpu=cpu,
            cpl=cpl,
            cpk=cpk,
            cpk_lower=cpk_lower,
            cp_within=cp_within,
            cpk_within=cpk_within,
            capable=None if cpk is None else cpk >= self.config.threshold,
            above_usl=self._above,
            below_lsl=self._below,
            alarms=alarms,
        )

    def _newest_point_alarms(self, center: float, sigma: float) -> tuple[Alarm, ...]:
        """Alarms flagging the newest point, from the windows it completes (O(RULE_WINDOW))."""
        tail = self._points[-RULE_WINDOW:]
        newest = len(self._points)
        first = newest - len(tail) + 1
        # The cycles behind the tail's points only: O(RULE_WINDOW · subgroup), not O(n).
        behind = PointCycles(
            self._cycles.view()[(first - 1) * self._subgroup :], self._subgroup, len(tail)
        )
        alarms = check_rules(
            tail,
            center,
            sigma,
            self.config.rule_set,
            unit=self.config.unit or None,
            resolution=self.config.resolution,
            first_point=first,
            cycles=behind,
        )
        return tuple(alarm for alarm in alarms if newest in alarm.points)

    @property
    def frozen(self) -> FrozenLimits | None:
        """The phase II limits (from the baseline, or frozen after ``freeze_after`` points)."""
        return self._frozen

    def _phase_two_alarms(self, update: LiveUpdate) -> tuple[Alarm, ...]:
        """The alarms a new chart point raises against the frozen limits. At the moment the
        limits freeze, every earlier point is judged against them too (those alarms are raised
        then): the live alarms are then exactly the rules over all points against the frozen
        limits, which is what :func:`phase_two_alarms` computes in one pass."""
        if self._frozen is None:
            assert self.freeze_after is not None
            if len(self._points) < self.freeze_after:
                return ()
            if update.center is None or update.ucl is None or not update.ucl > update.center:
                return ()  # no spread yet: wait for limits that can judge anything
            self._frozen = FrozenLimits(
                center=update.center,
                ucl=update.ucl,
                lcl=update.lcl if update.lcl is not None else update.center,
                source=f"frozen after the first {len(self._points)} points",
            )
            return self._catch_up()
        return self._newest_frozen_alarms()

    def _point_labels(self, first: int) -> PointCycles:
        """Cycles behind the chart points from number ``first`` (1-based) on."""
        count = len(self._points) - first + 1
        return PointCycles(
            self._cycles.view()[(first - 1) * self._subgroup :], self._subgroup, count
        )

    def _catch_up(self) -> tuple[Alarm, ...]:
        frozen = self._frozen
        assert frozen is not None
        alarms = check_rules(
            self._points,
            frozen.center,
            frozen.point_sigma,
            self.config.rule_set,
            unit=self.config.unit or None,
            resolution=self.config.resolution,
            cycles=self._point_labels(1),
        )
        ewma = ewma_alarms(
            self._points,
            frozen,
            self._point_labels(1),
            unit=self.config.unit or None,
            resolution=self.config.resolution,
        )
        # Carry the EWMA state on from the last point.
        self._ewma, self._ewma_run_start = ewma.state, ewma.run_start
        self._ewma_side = ewma.side
        return tuple(alarms) + ewma.alarms

    def _newest_frozen_alarms(self) -> tuple[Alarm, ...]:
        frozen = self._frozen
        assert frozen is not None
        tail = self._points[-RULE_WINDOW:]
        newest = len(self._points)
        first = newest - len(tail) + 1
        alarms = check_rules(
            tail,
            frozen.center,
            frozen.point_sigma,
            self.config.rule_set,
            unit=self.config.unit or None,
            resolution=self.config.resolution,
            first_point=first,
            cycles=self._point_labels(first),
        )
        found = [alarm for alarm in alarms if newest in alarm.points]
        # The EWMA, one step on.
        previous = frozen.center if self._ewma is None else self._ewma
        self._ewma = EWMA_LAMBDA * self._points[-1] + (1 - EWMA_LAMBDA) * previous
        half = ewma_limit_half_width(frozen.point_sigma, newest, EWMA_LAMBDA, EWMA_WIDTH)
        if abs(self._ewma - frozen.center) > half:
            side = 1 if self._ewma > frozen.center else -1
            if self._ewma_run_start is not None and side != self._ewma_side:
                self._ewma_run_start = None
            self._ewma_side = side
            if self._ewma_run_start is None:
                self._ewma_run_start = newest
            # A run goes on: it was raised, whole, at its first point (or when the limits froze).
            # Named again whole it would cost O(run) a reading, quadratic over a long drift:
            # its last two points say that it goes on (the ledger knows the earlier one) and
            # flag the new one.
            run = range(max(self._ewma_run_start, newest - 1), newest + 1)
            labels = self._point_labels(run[0])
            found.append(
                ewma_alarm(
                    run,
                    labels.span(0, len(run) - 1),
                    self._ewma,
                    half,
                    frozen,
                    self.config.unit or None,
                    self.config.resolution,
                )
            )
        else:
            self._ewma_run_start = None
        return tuple(found)

    def readings(self) -> ChannelReadings:
        """The readings so far, to analyse later or on another thread: O(1), views of arrays
        that later readings do not change (no copy, no analysis)."""
        times = None if self._untimed else self._times.view()
        return ChannelReadings(self.name, self._values.view(), self._cycles.view(), times)

    def snapshot(self) -> ChannelAnalysis:
        """The full analysis of the readings so far: equal to the batch analysis (cached)."""
        if self._snapshot is None:
            if not len(self._values):
                raise StationError(f"channel {self.name!r} has no readings yet.")
            self._snapshot = self.readings().analysis(self.config)
        return self._snapshot


class _Growing:
    """Numbers appended one at a time to an array that doubles when full (O(1) each, amortized).
    :meth:`view` gives the numbers so far without a copy: later appends write past its end or
    into a new array, so a view never changes once handed out."""

    def __init__(self, dtype: Any) -> None:
        self._array = np.empty(64, dtype=dtype)
        self._size = 0

    def append(self, value: float) -> None:
        if self._size == self._array.size:
            grown = np.empty(2 * self._array.size, dtype=self._array.dtype)
            grown[: self._size] = self._array
            self._array = grown
        self._array[self._size] = value
        self._size += 1

    def last(self) -> float | None:
        return float(self._array[self._size - 1]) if self._size else None

    def view(self) -> np.ndarray:
        view = self._array[: self._size]
        view.flags.writeable = False
        return view

    def __len__(self) -> int:
        return self._size


@dataclass(frozen=True, eq=False)
class ChannelReadings:
    """One channel's readings at one moment of a live analysis, with their cycles and times
    (read-only arrays; ``times`` None unless every reading has one)."""

    name: str
    values: np.ndarray
    cycles: np.ndarray
    times: np.ndarray | None

    def analysis(self, config: AnalysisConfig) -> ChannelAnalysis:
        """The batch analysis of these readings (what :meth:`LiveChannel.snapshot` gives)."""
        return analyze_channel(self.name, self.values, config, self.cycles, self.times)


@dataclass(frozen=True)
class LiveReadings:
    """The readings of a :class:`LiveAnalysis` at one moment: its :meth:`snapshot` is the live
    analysis's as it was then, computed without the live analysis (so its owner may go on
    adding readings on another thread meanwhile)."""

    config: AnalysisConfig
    channels: tuple[ChannelReadings, ...]

    def snapshot(self) -> Analysis:
        """The whole analysis of these readings: equal to :meth:`LiveAnalysis.snapshot`."""
        if not self.channels:
            raise StationError("no readings yet: capture a cycle first.")
        return combine({c.name: c.analysis(self.config) for c in self.channels}, self.config)


class LiveAnalysis:
    """Live analysis of several channels sharing one configuration (see :class:`LiveChannel`)."""

    def __init__(
        self,
        config: AnalysisConfig,
        channels: list[str] | tuple[str, ...] = (),
        *,
        freeze_after: int | None = None,
        baseline: ControlBaseline | None = None,
    ) -> None:
        self.config = config
        self.freeze_after = freeze_after
        self.baseline = baseline
        self.channels: dict[str, LiveChannel] = {}
        for name in channels:
            self.channel(name)

    def channel(self, name: str) -> LiveChannel:
        """The live channel ``name``, created on first use (with the baseline's limits for it,
        else freezing after ``freeze_after`` points, else with moving limits)."""
        if name not in self.channels:
            fixed = None if self.baseline is None else self.baseline.limits_for(name)
            self.channels[name] = LiveChannel(
                name, self.config, freeze_after=self.freeze_after, baseline=fixed
            )
        return self.channels[name]

    def add(
        self, name: str, value: float, cycle: int | None = None, t: float | None = None
    ) -> LiveUpdate:
        """Add one reading of channel ``name`` (of cycle number ``cycle``, read at ``t``, see
        :meth:`LiveChannel.add`)."""
        return self.channel(name).add(value, cycle, t)

    def add_set(
        self,
        readings: Mapping[str, float],
        cycle: int | None = None,
        times: Mapping[str, float] | None = None,
    ) -> dict[str, LiveUpdate]:
        """Add one cycle's reading set (channel → value); ``cycle`` is its number, so alarms
        name cycles (default: each channel's reading count); ``times`` the readings' times."""
        stamps = times or {}
        return {
            name: self.add(name, value, cycle, stamps.get(name)) for name, value in readings.items()
        }

    def readings(self) -> LiveReadings:
        """A copy of every channel's readings so far (channels with readings), to analyse
        without this object: ``readings().snapshot()`` equals :meth:`snapshot` now."""
        return LiveReadings(
            self.config, tuple(live.readings() for live in self.channels.values() if live.n)
        )

    def snapshot(self) -> Analysis:
        """The whole analysis so far (channels with readings): equal to the batch ``analyze``."""
        channels = {name: live.snapshot() for name, live in self.channels.items() if live.n}
        if not channels:
            raise StationError("no readings yet: capture a cycle first.")
        return combine(channels, self.config)
