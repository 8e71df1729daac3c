"""The whole analysis of a set of channels: what `station analyze`, the reports and the TUI show.

:func:`analyze` runs the report's statistics on every channel (descriptive figures, histogram,
capability, control chart and run rules), the 3-D figures when channels x, y and z are present,
and the verdict hints. :func:`to_json` turns the result into the documented JSON document.

Run rules are checked on the location chart (individuals or subgroup means) against its own
centre line and sigma, ``(UCL − centre)/3``; the dispersion chart's limits are reported, not
rule-checked.

Readings are labelled by their cycle numbers (``cycles``): a session that rejected cycle 3 has
cycle 7 as its 6th reading, and the report, the alarms and the hints name cycle 7. Without
labels the readings are cycles 1, 2, 3 ... in order.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from station.analysis.capability import Capability, SpecLimits, capability
from station.analysis.charts import ControlChart, control_chart
from station.analysis.descriptive import Descriptive, Histogram, describe, histogram
from station.analysis.hints import channel_hints
from station.analysis.rules import RULE_SETS, Alarm, check_rules
from station.analysis.spatial import AXES, Spatial, find_axes, spatial_figures
from station.errors import StationError

NO_LIMITS_MESSAGE = "no specification limits: give --lsl/--usl or --limit CH=LSL:USL"


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
        if not self.threshold > 0:
            raise StationError(
                f"the capability threshold must be a positive number, not {self.threshold!r}."
            )

    def limits_for(self, channel: str) -> SpecLimits | None:
        """The specification limits that apply to ``channel`` (None when there are none)."""
        return self.limits.get(channel, self.default_limits)

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
    readings: tuple[float, ...]
    limits: SpecLimits | None
    nominal: float
    cycles: tuple[int, ...] = ()
    """The cycle number of each reading (same order); the alarms' ``cycles`` come from it."""


@dataclass(frozen=True)
class Analysis:
    """The analysis of every channel, the 3-D figures (x, y, z present) and the hints.

    ``excluded_cycles`` lists the cycle numbers left out (rejected in a session file).
    """

    channels: dict[str, ChannelAnalysis]
    spatial: Spatial | None
    hints: tuple[str, ...]
    config: AnalysisConfig
    excluded_cycles: tuple[int, ...] = ()

    @property
    def incapable_channels(self) -> list[str]:
        """Channels whose verdict is NOT CAPABLE (undefined verdicts are not listed)."""
        return [name for name, c in self.channels.items() if c.capability.capable is False]


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


class PointCycles(Sequence[tuple[int, ...]]):
    """The cycle numbers behind each of the first ``points`` chart points: one cycle per point
    for single readings, the ``subgroup`` consecutive cycles of each subgroup mean.

    Computed on demand: the rules look up only the points of their alarms, and building a
    tuple per point of a million-point chart cost more than the rules themselves.
    """

    def __init__(self, cycles: Sequence[int], subgroup: int, points: int) -> None:
        self._cycles = cycles
        self._subgroup = subgroup
        self._points = points

    def __len__(self) -> int:
        return self._points

    def __getitem__(self, index):  # type: ignore[override]
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self._points))]
        if index < 0:
            index += self._points
        if not 0 <= index < self._points:
            raise IndexError(index)
        start = index * self._subgroup
        return tuple(self._cycles[start : start + self._subgroup])


def point_cycles(cycles: Sequence[int], subgroup: int, points: int) -> PointCycles:
    """The cycle numbers behind each of the first ``points`` chart points (see PointCycles)."""
    return PointCycles(cycles, subgroup, points)


def cycle_labels(name: str, cycles: Sequence[int] | None, n: int) -> tuple[int, ...]:
    """Checked cycle numbers for ``n`` readings of channel ``name``: 1 .. n when None."""
    if cycles is None:
        return tuple(range(1, n + 1))
    labels = tuple(int(c) for c in cycles)
    if len(labels) != n or any(c != float(given) for c, given in zip(labels, cycles, strict=True)):
        raise StationError(
            f"channel {name!r} has {n} readings but {len(labels)} cycle numbers: give one whole "
            "cycle number per reading."
        )
    return labels


def chart_alarms(
    chart: ControlChart, rule_set: str, unit: str = "", cycles: Sequence[int] | None = None
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
            chart.points,
            chart.center,
            sigma,
            rule_set,
            unit=unit or None,
            cycles=point_cycles(cycles, chart.subgroup, len(chart.points)),
        )
    )


def analyze_channel(
    name: str,
    values: np.ndarray | Sequence[float],
    config: AnalysisConfig,
    cycles: Sequence[int] | None = None,
) -> ChannelAnalysis:
    """The full analysis of one channel's readings (in cycle order); ``cycles`` numbers them
    (1, 2, 3 ... when None)."""
    values = np.asarray(values, dtype=float)
    labels = cycle_labels(name, cycles, len(values))
    limits = config.limits_for(name)
    descriptive = describe(values, config.resolution)
    hist = histogram(
        values,
        config.resolution,
        lsl=None if limits is None else limits.lsl,
        usl=None if limits is None else limits.usl,
    )
    chart = control_chart(values, config.subgroup)
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
    return ChannelAnalysis(
        name=name,
        descriptive=descriptive,
        histogram=hist,
        capability=cap,
        chart=chart,
        alarms=chart_alarms(chart, config.rule_set, config.unit, labels),
        readings=tuple(values.tolist()),
        limits=limits,
        nominal=config.nominal_for(name),
        cycles=labels,
    )


def spatial_of(channels: Mapping[str, np.ndarray], config: AnalysisConfig) -> Spatial | None:
    """The 3-D figures when channels x, y, z exist with one reading each per cycle."""
    axes = find_axes(list(channels))
    if axes is None:
        return None
    arrays = [np.asarray(channels[axes[axis]], dtype=float) for axis in AXES]
    if len({len(a) for a in arrays}) != 1 or len(arrays[0]) == 0:
        return None
    nominal = tuple(config.nominal_for(axes[axis]) for axis in AXES)
    return spatial_figures(*arrays, nominal=nominal)  # type: ignore[arg-type]


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
            )
        )
    return tuple(hints)


def analyze(
    channels: Mapping[str, np.ndarray],
    config: AnalysisConfig,
    *,
    excluded_cycles: Sequence[int] = (),
    cycles: Mapping[str, Sequence[int]] | None = None,
) -> Analysis:
    """Analyse every channel, the 3-D figures and the hints.

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
    analysed = {
        name: analyze_channel(name, values, config, labels.get(name))
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
    readings = {name: np.asarray(c.readings, dtype=float) for name, c in channels.items()}
    return Analysis(
        channels=dict(channels),
        spatial=spatial_of(readings, config),
        hints=hints_of(list(channels.values()), config),
        config=config,
        excluded_cycles=tuple(excluded_cycles),
    )


def _number(value: float | None) -> float | None:
    """A JSON number, or None for undefined (never NaN or inf)."""
    if value is None:
        return None
    value = float(value)
    return value if np.isfinite(value) else None


def channel_to_json(channel: ChannelAnalysis) -> dict[str, Any]:
    """One channel of the JSON document."""
    d, cap, chart = channel.descriptive, channel.capability, channel.chart
    document = {
        "n": d.n,
        "mean": _number(d.mean),
        "sd": _number(d.sd),
        "skewness": _number(d.skewness),
        "mode": [_number(m) for m in d.modes],
        "min": _number(d.min),
        "max": _number(d.max),
        "range": _number(d.range),
        "nominal": _number(channel.nominal),
        # Absent when the readings are cycles 1 to n in order (a million-row CSV would
        # otherwise print a million numbers that say nothing).
        **({} if _numbered_in_order(channel.cycles) else {"cycles": list(channel.cycles)}),
        "capability": {
            "lsl": _number(cap.lsl),
            "usl": _number(cap.usl),
            "cp": _number(cap.cp),
            "cpu": _number(cap.cpu),
            "cpl": _number(cap.cpl),
            "cpk": _number(cap.cpk),
            "cpk_lower": _number(cap.cpk_lower),
            "cp_within": _number(cap.cp_within),
            "cpk_within": _number(cap.cpk_within),
            "sigma": _number(cap.sigma),
            "sigma_within": _number(cap.sigma_within),
            "threshold": _number(cap.threshold),
            "capable": cap.capable,
            "above_usl": cap.above_usl,
            "below_lsl": cap.below_lsl,
            "message": cap.message,
        },
        "chart": {
            "type": chart.type,
            "subgroup": chart.subgroup,
            "center": _number(chart.center),
            "ucl": _number(chart.ucl),
            "lcl": _number(chart.lcl),
            "sigma_within": _number(chart.sigma_within),
            "dispersion": {
                "center": _number(chart.dispersion.center),
                "ucl": _number(chart.dispersion.ucl),
                "lcl": _number(chart.dispersion.lcl),
            },
            "message": chart.message,
        },
        "alarms": [
            {"rule": a.rule, "points": list(a.points), "cycles": list(a.cycles), "text": a.text}
            for a in channel.alarms
        ],
    }
    return document


def spatial_to_json(spatial: Spatial) -> dict[str, Any]:
    """The 3-D figures of the JSON document."""
    return {
        "n": spatial.n,
        "nominal": {axis: _number(v) for axis, v in spatial.nominal.items()},
        "offset": {axis: _number(v) for axis, v in spatial.offset.items()},
        "total_offset": _number(spatial.total_offset),
        "ap": {key: _number(v) for key, v in spatial.ap.items()},
        "rp": _number(spatial.rp),
        "l_mean": _number(spatial.l_mean),
        "l_sd": _number(spatial.l_sd),
        "message": spatial.message,
    }


def to_json(analysis: Analysis) -> dict[str, Any]:
    """The JSON document of `station analyze --json` (undefined values are None → null).

    ``spatial`` is always present: an object when channels x, y, z exist, else null.
    """
    config = analysis.config
    return {
        "unit": config.unit,
        "resolution": _number(config.resolution),
        "subgroup": config.subgroup,
        "rules": config.rule_set,
        "threshold": _number(config.threshold),
        "excluded_cycles": list(analysis.excluded_cycles),
        "channels": {name: channel_to_json(c) for name, c in analysis.channels.items()},
        "spatial": None if analysis.spatial is None else spatial_to_json(analysis.spatial),
        "hints": list(analysis.hints),
    }


def _numbered_in_order(cycles: Any) -> bool:
    """True when ``cycles`` is exactly 1, 2, ..., n."""
    import numpy as np

    numbers = np.asarray(cycles)
    return bool(numbers.size == 0 or np.array_equal(numbers, np.arange(1, numbers.size + 1)))
