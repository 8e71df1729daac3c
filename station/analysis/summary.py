"""The whole analysis of a set of channels: what `station analyze`, the reports and the TUI show.

:func:`analyze` runs the report's statistics on every channel (descriptive figures, histogram,
capability, control chart and run rules), the 3-D figures when channels x, y and z are present,
and the verdict hints. :func:`station.analysis.document.to_json` turns the result into the
documented JSON document.

Run rules are checked on the location chart (individuals or subgroup means) against its own
centre line and sigma, ``(UCL − centre)/3``; the dispersion chart's limits are reported, not
rule-checked.

Readings are labelled by their cycle numbers (``cycles``): a session that rejected cycle 3 has
cycle 7 as its 6th reading, and the report, the alarms and the hints name cycle 7. Without
labels the readings are cycles 1, 2, 3 ... in order.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from station.analysis.capability import Capability, SpecLimits, capability
from station.analysis.charts import ControlChart, control_chart
from station.analysis.column import Column
from station.analysis.descriptive import Descriptive, Histogram, describe, histogram
from station.analysis.diagnostics import (
    ALPHA,
    SHAPIRO_MAX_N,
    Autocorrelation,
    Drift,
    Normality,
    OutOfSpec,
    PercentileCapability,
    autocorrelation,
    drift,
    normality,
    out_of_spec,
    p_phrase,
    percentile_capability,
)
from station.analysis.discrimination import Discrimination, discrimination
from station.analysis.false_alarms import FalseAlarmChance, false_alarm_chance
from station.analysis.hints import channel_hints
from station.analysis.phases import (
    DEFAULT_FREEZE_AFTER,
    ControlBaseline,
    FrozenLimits,
    phase_two_alarms,
)
from station.analysis.rules import RULE_SETS, Alarm, PointCycles, check_rules
from station.analysis.spatial import AXES, Spatial, find_axes, spatial_figures
from station.analysis.uncertainty import (
    Budget,
    BudgetResult,
    GaugeRecord,
    ReadingDecisions,
    Rule,
    channel_budget,
    evaluate,
    judge_readings,
)
from station.analysis.verdict import DEFAULT_MIN_N, NOT_CAPABLE, Verdict, judge_verdict
from station.analysis.zeros import ZeroDraw, zeros_variance
from station.errors import StationError

NO_LIMITS_MESSAGE = "no specification limits: give limits for this channel"
NO_CYCLES = Column((), dtype=np.int64)
NO_TIMES = Column(())


@dataclass(frozen=True)
class AnalysisConfig:
    """How to judge the channels.

    ``limits`` holds per-channel specification limits; ``default_limits`` applies to every
    other channel (None: capability is undefined there, with the reason). ``resolution`` is the
    gauge step used for modes and histogram bins; ``subgroup`` groups consecutive readings for
    the chart and the within sigma; ``rule_set`` is one of RULE_SETS; a channel is capable when
    Cpk ≥ ``threshold``. ``nominal`` gives a channel's nominal when its limits name none (the
    indicators are zeroed at the taught pose, so it defaults to 0).
    """

    limits: Mapping[str, SpecLimits] = field(default_factory=dict)
    default_limits: SpecLimits | None = None
    resolution: float | None = None
    unit: str = ""
    subgroup: int = 1
    rule_set: str = "report"
    threshold: float = 1.0
    confidence: float = 0.95
    nominal: Mapping[str, float] = field(default_factory=dict)
    min_n: int = DEFAULT_MIN_N
    """Below this many readings a verdict is PROVISIONAL (the procedure's minimum count)."""
    freeze_after: int | None = DEFAULT_FREEZE_AFTER
    """Chart points after which the live (phase II) limits freeze; None: no live limits."""
    baseline: ControlBaseline | None = None
    """Fixed phase II limits per channel (a robot's baseline); they replace the freeze."""
    zero_uncertainty: Mapping[str, float] = field(default_factory=dict)
    """The standard uncertainty of the zero in force per channel (from the session's zero
    events): an offset from nominal within what it explains is said to be the zero's."""
    zero_draws: Mapping[str, tuple[ZeroDraw, ...]] = field(default_factory=dict)
    """Per channel, the zeros its readings were taken under (their count of readings and
    within-rest spread): each is one rest of the robot, so the mean's offset carries its
    rest-to-rest uncertainty (:mod:`station.analysis.zeros`). None for a channel not zeroed."""
    decision_rule: str = Rule.GUARDED.value
    """How a reading is judged against its limits with the budget's U: ``guarded``
    acceptance (ISO 14253-1, the default) or ``simple`` (no guard band), from the header."""
    gauges: Mapping[str, GaugeRecord] = field(default_factory=dict)
    """Per channel, what the gauge register said of its gauge (certificate, Type-1
    repeatability): lines of the channel's measurement budget."""

    def __post_init__(self) -> None:
        if self.resolution is not None and not self.resolution > 0:
            raise StationError(
                f"the gauge resolution must be a positive number, not {self.resolution!r}."
            )
        if self.subgroup < 1:
            raise StationError(f"the subgroup size must be 1 or more, not {self.subgroup}.")
        if self.rule_set not in RULE_SETS:
            raise StationError(
                f"unknown rule set {self.rule_set!r}; choose one of {', '.join(RULE_SETS)}."
            )
        if self.min_n < 0:
            raise StationError(f"the minimum count must be 0 or more, not {self.min_n}.")
        if self.freeze_after is not None and self.freeze_after < 2:
            raise StationError(
                f"the live limits need at least 2 points to freeze, not {self.freeze_after}."
            )
        if self.decision_rule not in {rule.value for rule in Rule}:
            raise StationError(
                f"unknown decision rule {self.decision_rule!r}; choose guarded or simple."
            )
        if not self.threshold > 0:
            raise StationError(
                f"the capability threshold must be a positive number, not {self.threshold!r}."
            )

    def limits_for(self, channel: str) -> SpecLimits | None:
        """The specification limits that apply to ``channel`` (None when there are none)."""
        return self.limits.get(channel, self.default_limits)

    def budget_for(self, channel: str) -> Budget | None:
        """The measurement budget of one reading of ``channel`` (:func:`channel_budget`): the
        gauge step, the gauge's certificate and Type-1 repeatability, the zero's uncertainty;
        None when nothing of it is known."""
        return channel_budget(
            self.resolution,
            self.gauges.get(channel),
            self.zero_uncertainty.get(channel),
            self.unit,
        )

    def nominal_for(self, channel: str) -> float:
        """The nominal of ``channel``: its limits' nominal, else ``nominal``, else 0."""
        limits = self.limits_for(channel)
        if limits is not None and limits.nominal is not None:
            return float(limits.nominal)
        return float(self.nominal.get(channel, 0.0))


@dataclass(frozen=True)
class ChannelAnalysis:
    """Everything computed for one channel, plus its readings in order and their cycles."""

    name: str
    descriptive: Descriptive
    histogram: Histogram
    capability: Capability
    chart: ControlChart
    alarms: tuple[Alarm, ...]
    readings: Column
    """The readings in order: one array, read as a sequence of floats."""
    limits: SpecLimits | None
    nominal: float
    cycles: Column = NO_CYCLES
    """The cycle number of each reading (same order); the alarms' ``cycles`` come from it."""
    verdict: Verdict | None = None
    """The verdict word (PROVISIONAL below ``config.min_n``) and its line."""
    out_of_spec: OutOfSpec | None = None
    frozen: FrozenLimits | None = None
    """The phase II limits the live alarms are judged against (None: too few points yet)."""
    phase_rules: tuple[str, str, int, float | None] = ("report", "", 1, None)
    """Rule set, unit, subgroup size and gauge resolution the live alarms are judged (and
    worded) with."""
    times: Column = NO_TIMES
    """The time of each reading in seconds, when every reading has one (else empty)."""
    resolution: float | None = None
    """The gauge step the readings were judged at (the normality test's ties, the drift's
    figures)."""
    budget: BudgetResult | None = None
    """The evaluated measurement budget of one reading (U at k = 2): what every decision of a
    reading against the limits takes, and what every output shows (None: nothing known)."""
    decision_rule: str = Rule.GUARDED.value
    """The rule a reading is judged against the limits by (``guarded`` or ``simple``)."""

    # The checks of what the capability assumes are worked out on first use: tens of ms a
    # channel (a test of normality sorts the readings), too much for every redraw of a live
    # snapshot that does not show them.

    @cached_property
    def reading_decisions(self) -> ReadingDecisions | None:
        """Every reading judged against the limits with :attr:`budget`'s U by the config's
        decision rule (guarded acceptance unless the header says ``simple``); None without
        limits or a budget."""
        limits, budget = self.limits, self.budget
        if limits is None or budget is None or (limits.lsl is None and limits.usl is None):
            return None
        return judge_readings(
            self.readings.array,
            self.cycles.array,
            limits.lsl,
            limits.usl,
            budget,
            self.decision_rule,
        )

    @cached_property
    def discrimination(self) -> Discrimination | None:
        """Whether the gauge step resolves the readings' spread (None without a resolution):
        judged on the chart's within sigma and its range (or moving-range) chart's limit."""
        chart = self.chart
        range_chart = {"I-MR": "moving range", "Xbar-R": "range"}.get(chart.type)
        return discrimination(
            self.readings.array,
            self.resolution,
            sigma=chart.sigma_within,
            range_ucl=chart.dispersion.ucl if range_chart else None,
            range_chart=range_chart or "S",
        )

    @cached_property
    def false_alarm(self) -> FalseAlarmChance | None:
        """The chance that a stable process raises some alarm of the rule set on a chart of
        this many points (simulated once per chart length, cached): what an alarm is worth."""
        rule_set, _, size, _ = self.phase_rules
        return false_alarm_chance(rule_set, len(self.chart.points), size)

    @property
    def coarse(self) -> bool:
        """True when the gauge step is too coarse for the spread (inadequate discrimination)."""
        found = self.discrimination
        return found is not None and not found.adequate

    @property
    def shape_hidden(self) -> bool:
        """True when the rounding hides the readings' shape: no normality test, no percentile
        index (see :attr:`Discrimination.resolves_shape`)."""
        found = self.discrimination
        return found is not None and not found.resolves_shape

    @cached_property
    def normality(self) -> Normality | None:
        """Shapiro-Wilk or Anderson-Darling test of the readings; not run (with the reason)
        when the gauge rounded them to a few values: ties, not the process, would decide it."""
        if self.shape_hidden:
            found = self.discrimination
            assert found is not None
            n = len(self.readings)
            return Normality(
                "Shapiro-Wilk" if n <= SHAPIRO_MAX_N else "Anderson-Darling",
                None,
                None,
                ALPHA,
                None,
                n,
                message=found.shape_reason(),
            )
        return normality(self.readings.array, self.resolution)

    @cached_property
    def autocorrelation(self) -> Autocorrelation | None:
        """The lag-1 autocorrelation of the readings, against the within sigma."""
        return autocorrelation(self.readings.array, sigma_within=self.chart.sigma_within)

    @cached_property
    def drift(self) -> Drift | None:
        """The EWMA about the mean and the trend on the readings' times (else cycle order)."""
        return drift(
            self.readings.array,
            self.chart.sigma_within,
            times=self.times.array if len(self.times) else None,
            cycles=self.cycles.array,
            name=self.name,
            unit=self.phase_rules[1],
            resolution=self.resolution,
        )

    @cached_property
    def live_alarms(self) -> tuple[Alarm, ...]:
        """The alarms against the frozen limits: those the live analysis raised. Computed on
        first use: against limits frozen early a long drifting record raises very many."""
        if self.frozen is None:
            return ()
        rule_set, unit, size, resolution = self.phase_rules
        values = self.readings.array
        complete = len(values) // size
        if not complete:
            return ()
        # The plotted points as the live analysis has them (a chart of one reading has none).
        points = values if size == 1 else values[: complete * size].reshape(complete, size).mean(1)
        return phase_two_alarms(
            points,
            self.frozen,
            rule_set,
            PointCycles(self.cycles, size, complete),
            unit=unit or None,
            resolution=resolution,
        )

    @cached_property
    def percentile(self) -> PercentileCapability | None:
        """ISO 22514-2 percentile indices when normality is rejected and limits are given
        (None otherwise, and never from readings the gauge rounded to a few values: their
        fitted tails are the rounding's, not the process's). Computed on first use: the
        distribution fit costs ~20 ms, too much for every redraw of a live snapshot that does
        not show it."""
        if self.shape_hidden:
            return None
        if self.normality is None or not self.normality.rejected or self.limits is None:
            return None
        return percentile_capability(self.readings.array, self.limits, self.capability.threshold)

    @property
    def capability_method(self) -> str:
        """How the verdict's index was computed: the normal indices from sigma, or (normality
        rejected) the percentile method."""
        if self.percentile is not None:
            return "percentile"
        return "normal"

    @cached_property
    def live_cycles_by_rule(self) -> Mapping[str, frozenset[int]]:
        """The cycles each rule flagged live (phase II): the index :meth:`alarm_is_live` looks
        up, built once so that judging every alarm stays linear in the alarms."""
        flagged: dict[str, set[int]] = {}
        for live in self.live_alarms:
            flagged.setdefault(live.rule, set()).update(live.cycles)
        return {rule: frozenset(cycles) for rule, cycles in flagged.items()}

    def alarm_is_live(self, alarm: Alarm) -> bool:
        """True when a live (phase II) alarm of the same rule flagged one of its cycles."""
        flagged = self.live_cycles_by_rule.get(alarm.rule)
        return flagged is not None and not flagged.isdisjoint(alarm.cycles)


@dataclass(frozen=True)
class Analysis:
    """The analysis of every channel, the 3-D figures (x, y, z present) and the hints.

    ``excluded_cycles`` lists the cycle numbers left out (rejected in a session file).
    """

    channels: dict[str, ChannelAnalysis]
    spatial: Spatial | None
    config: AnalysisConfig
    excluded_cycles: tuple[int, ...] = ()
    given_hints: tuple[str, ...] | None = None
    """The hints of an analysis built with its own (a linearity summary's; none for a kind
    whose report block says what its figures point to); None: the channels' hints."""

    @cached_property
    def hints(self) -> tuple[str, ...]:
        """The verdict hints: :attr:`given_hints`, else every channel's (:func:`hints_of`).
        Worked out on first use: the hint on non-normal readings fits a distribution (tens of
        ms a channel), too slow for every live snapshot of a screen that shows no hints."""
        if self.given_hints is not None:
            return self.given_hints
        return hints_of(list(self.channels.values()), self.config)

    @property
    def incapable_channels(self) -> list[str]:
        """Channels whose verdict is NOT CAPABLE (undefined, inconclusive and provisional
        verdicts are not listed)."""
        return [
            name
            for name, c in self.channels.items()
            if c.verdict is not None and c.verdict.word == NOT_CAPABLE
        ]


def undefined_capability(
    descriptive: Descriptive, chart: ControlChart, config: AnalysisConfig, message: str
) -> Capability:
    """A Capability without indices (no limits), keeping the sigmas that need no limits."""
    return Capability(
        lsl=None,
        usl=None,
        cp=None,
        cpu=None,
        cpl=None,
        cpk=None,
        cpk_lower=None,
        cp_within=None,
        cpk_within=None,
        sigma=descriptive.sd,
        sigma_within=chart.sigma_within,
        threshold=config.threshold,
        capable=None,
        above_usl=0,
        below_lsl=0,
        message=message,
        n=descriptive.n,
        mean=descriptive.mean,
        confidence=config.confidence,
    )


def cycle_labels(name: str, cycles: Sequence[int] | np.ndarray | None, n: int) -> Column:
    """Checked cycle numbers for ``n`` readings of channel ``name``: 1 .. n when None."""
    if cycles is None:
        return Column(np.arange(1, n + 1), dtype=np.int64)
    given = np.asarray(cycles)
    whole = given.ndim == 1 and given.dtype.kind in "iuf"
    if whole and given.dtype.kind == "f":
        whole = bool(np.all(np.isfinite(given))) and bool(np.all(given == np.trunc(given)))
    if not whole or len(given) != n:
        raise StationError(
            f"channel {name!r} has {n} readings but {given.size} cycle numbers: give one whole "
            "cycle number per reading."
        )
    return Column(given, dtype=np.int64)


def chart_alarms(
    chart: ControlChart,
    rule_set: str,
    unit: str = "",
    cycles: Sequence[int] | np.ndarray | None = None,
    resolution: float | None = None,
) -> tuple[Alarm, ...]:
    """The run-rule alarms of a chart's location points, labelled by ``cycles`` (the cycle
    number of each reading; 1, 2, 3 ... when None).

    None while the chart has no limits, and none when its sigma is 0 (every reading equal):
    limits on the centre line make every zone rule meaningless.
    """
    sigma = chart.point_sigma
    if chart.center is None or sigma is None or not sigma > 0 or not chart.points:
        return ()
    if cycles is None:
        cycles = range(1, len(chart.points) * chart.subgroup + 1)
    return tuple(
        check_rules(
            chart.points.array,
            chart.center,
            sigma,
            rule_set,
            unit=unit or None,
            resolution=resolution,
            cycles=PointCycles(cycles, chart.subgroup, len(chart.points)),
        )
    )


def frozen_limits_of(name: str, values: np.ndarray, config: AnalysisConfig) -> FrozenLimits | None:
    """The phase II limits the live analysis froze (or the baseline's): the chart of the first
    ``freeze_after`` points, or of the first points after that whose chart has a spread."""
    if config.baseline is not None and name in config.baseline.limits:
        return config.baseline.limits_for(name)
    k = config.freeze_after
    size = config.subgroup
    points = len(values) // size
    if k is None or points < k:
        return None

    def chart_of(m: int) -> ControlChart:
        return control_chart(values[: m * size], size, resolution=config.resolution)

    def usable(chart: ControlChart) -> bool:
        return chart.center is not None and chart.ucl is not None and chart.ucl > chart.center

    first = chart_of(k)
    if not usable(first):
        # A spread, once there, stays: find the first count of points with one.
        if not usable(chart_of(points)):
            return None
        low, high = k, points
        while high - low > 1:
            middle = (low + high) // 2
            low, high = (low, middle) if usable(chart_of(middle)) else (middle, high)
        first, k = chart_of(high), high
    assert first.center is not None and first.ucl is not None
    lcl = first.lcl if first.lcl is not None else first.center
    return FrozenLimits(first.center, first.ucl, lcl, f"frozen after the first {k} points")


def analyze_channel(
    name: str,
    values: np.ndarray | Sequence[float],
    config: AnalysisConfig,
    cycles: Sequence[int] | np.ndarray | None = None,
    times: Sequence[float] | np.ndarray | None = None,
) -> ChannelAnalysis:
    """The full analysis of one channel's readings (in cycle order); ``cycles`` numbers them
    (1, 2, 3 ... when None); ``times`` (seconds, one per reading) date them for the trend."""
    values = np.asarray(values, dtype=float)
    labels = cycle_labels(name, cycles, len(values))
    label_array = labels.array
    limits = config.limits_for(name)
    descriptive = describe(values, config.resolution)
    hist = histogram(
        values,
        config.resolution,
        lsl=None if limits is None else limits.lsl,
        usl=None if limits is None else limits.usl,
    )
    chart = control_chart(values, config.subgroup, resolution=config.resolution)
    if limits is None:
        cap = undefined_capability(descriptive, chart, config, NO_LIMITS_MESSAGE)
    else:
        cap = capability(
            values,
            limits,
            threshold=config.threshold,
            subgroup=config.subgroup,
            confidence=config.confidence,
            # The chart's within sigma is the estimator capability() would compute again.
            sigma_within=chart.sigma_within,
        )
    frozen = frozen_limits_of(name, values, config)
    clock = None if times is None or len(times) != len(values) else Column(times)
    return ChannelAnalysis(
        name=name,
        descriptive=descriptive,
        histogram=hist,
        capability=cap,
        chart=chart,
        alarms=chart_alarms(chart, config.rule_set, config.unit, label_array, config.resolution),
        readings=Column(values),
        limits=limits,
        nominal=config.nominal_for(name),
        cycles=labels,
        verdict=judge_verdict(cap, config.min_n),
        out_of_spec=out_of_spec(values, limits, label_array),
        frozen=frozen,
        phase_rules=(config.rule_set, config.unit, config.subgroup, config.resolution),
        times=clock or NO_TIMES,
        resolution=config.resolution,
        budget=None if (budget := config.budget_for(name)) is None else evaluate(budget),
        decision_rule=config.decision_rule,
    )


def spatial_of(channels: Mapping[str, np.ndarray], config: AnalysisConfig) -> Spatial | None:
    """The 3-D figures when channels x, y, z exist with one reading each per cycle."""
    axes = find_axes(list(channels))
    if axes is None:
        return None
    x, y, z = (np.asarray(channels[axes[axis]], dtype=float) for axis in AXES)
    if not len(x) == len(y) == len(z) or len(x) == 0:
        return None
    nominal = (
        config.nominal_for(axes["x"]),
        config.nominal_for(axes["y"]),
        config.nominal_for(axes["z"]),
    )
    return spatial_figures(x, y, z, nominal=nominal)


def zero_sd_of(channel: ChannelAnalysis, config: AnalysisConfig) -> float | None:
    """The standard uncertainty the zero puts on ``channel``'s mean: √Var(z) from its zero
    draws and the session's own spread (rest to rest, :func:`zeros_variance`); where the
    session records no draws, the zero's recorded within-rest uncertainty; None when the
    channel was not zeroed by the session."""
    draws = config.zero_draws.get(channel.name)
    sd = channel.descriptive.sd
    if draws and sd is not None:
        return math.sqrt(zeros_variance(sd, draws))
    return config.zero_uncertainty.get(channel.name)


def hints_of(channels: Sequence[ChannelAnalysis], config: AnalysisConfig) -> tuple[str, ...]:
    """Every channel's hints, in channel order."""
    hints: list[str] = []
    for channel in channels:
        hints.extend(
            channel_hints(
                channel.name,
                channel.descriptive,
                channel.capability,
                channel.alarms,
                limits=channel.limits,
                nominal=channel.nominal,
                resolution=config.resolution,
                unit=config.unit,
                zero_sd=zero_sd_of(channel, config),
            )
        )
        hints.extend(diagnostic_hints(channel))
    return tuple(hints)


def diagnostic_hints(channel: ChannelAnalysis) -> list[str]:
    """Hints from the checks of what the capability assumes: a gauge too coarse for the spread,
    readings out of specification, drift, autocorrelation and non-normal data."""
    hints: list[str] = []
    found_coarse = channel.discrimination
    coarse = (
        None
        if found_coarse is None
        else found_coarse.sentence(channel.name, channel.phase_rules[1])
    )
    if coarse is not None:
        hints.append(coarse)
    # An alarm is read against how often the rules fire on a stable process of this length.
    if channel.alarms and channel.false_alarm is not None:
        hints.append(f"{channel.name}: {channel.false_alarm.text()}")
    found = channel.out_of_spec
    if found is not None and found.total:
        hints.append(
            f"{channel.name}: {found.total} reading{'s' if found.total > 1 else ''} out of "
            f"specification ({found.below} below, {found.above} above)."
        )
    if channel.drift is not None and channel.drift.message:
        hints.append(f"{channel.drift.message}.")
    auto = channel.autocorrelation
    if auto is not None and auto.significant and auto.message:
        hints.append(f"{channel.name}: {auto.message}.")
    normality = channel.normality
    # A percentile index exists only when the test rejected normality, on a p-value.
    if channel.percentile is not None and normality is not None and normality.p_value is not None:
        ppk = channel.percentile.ppk
        hints.append(
            f"{channel.name}: the readings are not normal ({normality.test}, "
            f"{p_phrase(normality.p_value)}): judge by the percentile index "
            f"Ppk (percentile) {'undefined' if ppk is None else f'{ppk:.2f}'} as well as Cpk."
        )
    return hints


def analyze(
    channels: Mapping[str, np.ndarray],
    config: AnalysisConfig,
    *,
    excluded_cycles: Sequence[int] = (),
    cycles: Mapping[str, Sequence[int]] | None = None,
    times: Mapping[str, Sequence[float]] | None = None,
) -> Analysis:
    """Analyse every channel, the 3-D figures and the hints.

    ``times`` maps a channel to the time (seconds) of each of its readings, for the drift's
    trend test (a session's :meth:`~station.session.model.Session.channel_times`); without
    them the trend is on cycle order.

    ``cycles`` maps a channel to the cycle number of each of its readings (a session's
    :meth:`~station.session.model.Session.channel_cycles`); a channel without an entry is
    numbered 1, 2, 3 ... Raises StationError when there is no channel, when a channel has no
    readings, when its cycle numbers do not match its readings, or when ``config.limits``
    names a channel that is not in ``channels``.
    """
    if not channels:
        raise StationError("there are no channels to analyse.")
    unknown = [name for name in config.limits if name not in channels]
    if unknown:
        raise StationError(
            f"limits are given for channel {unknown[0]!r}, which is not in the data "
            f"(channels: {', '.join(channels)})."
        )
    for name, values in channels.items():
        if len(values) == 0:
            raise StationError(f"channel {name!r} has no readings.")
    labels = cycles or {}
    clocks = times or {}
    analysed = {
        name: analyze_channel(name, values, config, labels.get(name), clocks.get(name))
        for name, values in channels.items()
    }
    return combine(analysed, config, excluded_cycles=excluded_cycles)


def combine(
    channels: Mapping[str, ChannelAnalysis],
    config: AnalysisConfig,
    *,
    excluded_cycles: Sequence[int] = (),
) -> Analysis:
    """The Analysis of channels already analysed: adds the 3-D figures and the hints."""
    readings = {name: c.readings.array for name, c in channels.items()}
    return Analysis(
        channels=dict(channels),
        spatial=spatial_of(readings, config),
        config=config,
        excluded_cycles=tuple(excluded_cycles),
    )
