"""The unit and resolution the gauges send, read from their frames, against the session's.

A session declares a unit and a gauge resolution; the gauges send what they are set to. When
the two disagree every verdict is wrong by a factor (``01A+0000.001`` is 0.001 mm, not 0.001 in),
so the station compares them before anything is recorded. What the frames say:

* **the decimals** of the number in each frame (``0000.123`` → 3): the finest step the gauge
  shows is 10^-decimals (the protocol's :meth:`frame_decimals`);
* **the step between values**: the largest step every value is a whole multiple of (a gauge of
  resolution 0.005 shows 3 decimals, but only ever 0.005, 0.010 ...), trusted once enough
  distinct values were seen;
* **the unit**, where the frame states it (U-WAVE's ``M``/``I``, the Digimatic unit digit, the
  CDI's ``MM``/``IN``), or where the protocol's gauges show a known number of decimals per unit
  (the Mitutoyo 01A format: 3 decimals in mm, 4 or 5 in inches) — "which is mm on this
  protocol". That last one only words the sentence: a 0.001 in indicator also shows 3
  decimals, so only a unit the frames state, or the decimals and steps, refuse a session.

:func:`infer_channel` is pure over the readings' raw frames; :func:`frames_disagree` compares
the inference with the declared unit and resolution and returns the sentence naming both, or
``''``. :func:`unit_mismatch` is the per-set check of the units the frames state.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from station.instruments.base import Reading
from station.instruments.protocols.common import decimals_for

MIN_DISTINCT_FOR_STEP = 5
"""Distinct values needed before the step between values is trusted over the decimals."""

UNIT_WORDS = {"in": "inches", "mm": "mm"}


@dataclass(frozen=True)
class FrameSample:
    """What one frame shows: its value as the device sent it (before any software zero), the
    decimals written in the frame (None when the frame has no decimal point to count) and the
    unit the frame states (None when it states none)."""

    value: float
    decimals: int | None
    unit: str | None = None


@dataclass(frozen=True)
class FrameInference:
    """What a channel's frames say about its gauge.

    ``decimals``: digits after the point (the most any frame wrote). ``step``: the step the
    values move by (10^-decimals, or a multiple of it once ``MIN_DISTINCT_FOR_STEP`` distinct
    values show one). ``unit``: stated by the frames; ``protocol_unit``: implied by the
    decimals on this protocol; either may be None.
    """

    channel: str
    n: int
    decimals: int | None
    step: float | None
    unit: str | None = None
    protocol_unit: str | None = None
    distinct: int = 0

    @property
    def known_unit(self) -> str | None:
        """The unit the frames state, else the one their decimals imply on this protocol."""
        return self.unit or self.protocol_unit

    def describe(self) -> str:
        """``steps of 0.001, which is mm on this protocol`` / ``steps of 0.001 mm`` /
        ``steps of 0.001``; ``nothing yet`` without frames."""
        if self.n == 0 or self.step is None:
            return "nothing yet"
        step = step_text(self.step)
        if self.unit:
            return f"steps of {step} {self.unit}"
        if self.protocol_unit:
            return f"steps of {step}, which is {self.protocol_unit} on this protocol"
        return f"steps of {step} (the frames carry no unit)"


def step_text(step: float) -> str:
    """A step at its own decimals, never in exponent form (0.0001, not 1e-04)."""
    decimals = decimals_for(step) if step > 0 else 0
    return f"{step:.{decimals}f}"


def decimals_of_value(value: float, most: int = 6) -> int:
    """The fewest decimals that write ``value`` exactly (up to ``most``)."""
    for decimals in range(most + 1):
        if abs(round(value, decimals) - value) < 1e-9 * max(1.0, abs(value)):
            return decimals
    return most


def infer_channel(
    channel: str,
    samples: Sequence[FrameSample],
    units_by_decimals: Mapping[int, str] | None = None,
) -> FrameInference:
    """What ``channel``'s frames (``samples``, oldest first) say about its gauge."""
    if not samples:
        return FrameInference(channel, 0, None, None)
    counted = [s.decimals for s in samples if s.decimals is not None]
    # The most written: an adaptor that prints floats drops trailing zeros (0.1 for 0.100).
    values_decimals = (decimals_of_value(s.value) for s in samples)
    decimals = max(counted) if counted else max(values_decimals)
    unit_counts: dict[str, int] = {}
    for sample in samples:
        if sample.unit:
            unit_counts[sample.unit] = unit_counts.get(sample.unit, 0) + 1
    unit = max(unit_counts, key=unit_counts.__getitem__) if unit_counts else None
    scale = 10**decimals
    counts = sorted({round(s.value * scale) for s in samples})
    multiple = 0
    for count in counts:
        multiple = math.gcd(multiple, count)
    step = 10.0**-decimals
    if len(counts) >= MIN_DISTINCT_FOR_STEP and multiple > 1:
        step = round(multiple * step, decimals)
    protocol_unit = (units_by_decimals or {}).get(decimals)
    return FrameInference(channel, len(samples), decimals, step, unit, protocol_unit, len(counts))


def _is_multiple(value: float, step: float) -> bool:
    ratio = value / step
    return abs(ratio - round(ratio)) < 1e-6


def frames_disagree(
    inferred: Mapping[str, FrameInference],
    unit: str,
    resolution: float | Mapping[str, float],
    samples: Mapping[str, Sequence[FrameSample]] | None = None,
) -> str:
    """'' when the frames agree with the declared ``unit`` and ``resolution``; else one sentence
    naming both, e.g. "the gauges send steps of 0.001, which is mm on this protocol; the
    session is in inches at 0.0001".

    They disagree when the frames state another unit; when the frames show fewer decimals
    than the declared resolution needs (the gauge is coarser); or when a value is not a whole
    multiple of the declared resolution (the gauge is finer; ``samples`` give the values, else
    the inferred step is used). Channels with no frames say nothing.
    """
    problems: dict[str, list[str]] = {}
    for channel, inference in inferred.items():
        if inference.n == 0 or inference.step is None:
            continue
        declared = float(resolution[channel] if isinstance(resolution, Mapping) else resolution)
        # Only a unit the frames state refuses: decimals per unit are a habit of a protocol's
        # gauges (a 0.001 in indicator also shows 3 decimals), good for wording only.
        wrong_unit = inference.unit is not None and inference.unit != unit
        coarser = inference.decimals is not None and inference.decimals < decimals_for(declared)
        values = [s.value for s in (samples or {}).get(channel, ())]
        finer = (
            any(not _is_multiple(v, declared) for v in values)
            if values
            else not _is_multiple(inference.step, declared)
        )
        if wrong_unit or coarser or finer:
            problems.setdefault(inference.describe(), []).append(channel)
    if not problems:
        return ""
    declared_text = _declared_text(resolution, list(inferred))
    everyone = sum(len(channels) for channels in problems.values()) == len(
        [i for i in inferred.values() if i.n]
    )
    parts = []
    for what, channels in problems.items():
        who = "the gauges" if everyone and len(problems) == 1 else ", ".join(channels)
        verb = "send" if who == "the gauges" or len(channels) > 1 else "sends"
        parts.append(f"{who} {verb} {what}")
    return f"{'; '.join(parts)}; the session is in {UNIT_WORDS.get(unit, unit)} at {declared_text}"


def _declared_text(resolution: float | Mapping[str, float], channels: Sequence[str]) -> str:
    if not isinstance(resolution, Mapping):
        return step_text(float(resolution))
    values = {step_text(float(resolution[c])) for c in channels if c in resolution}
    if len(values) == 1:
        return values.pop()
    return ", ".join(f"{c} {step_text(float(resolution[c]))}" for c in channels if c in resolution)


def describe_inference(inferred: Mapping[str, FrameInference]) -> str:
    """One line for ``station read``: ``x, y, z send steps of 0.001, which is mm on this
    protocol`` (channels that say the same thing are named together)."""
    groups: dict[str, list[str]] = {}
    for channel, inference in inferred.items():
        groups.setdefault(inference.describe(), []).append(channel)
    parts = []
    for what, channels in groups.items():
        verb = "send" if len(channels) > 1 else "sends"
        if what == "nothing yet":
            parts.append(f"{', '.join(channels)}: nothing yet")
        else:
            parts.append(f"{', '.join(channels)} {verb} {what}")
    return "; ".join(parts)


def unit_mismatch(readings: Mapping[str, Reading], channels: Iterable[str], unit: str) -> str:
    """'' when every one of ``channels`` in ``readings`` reads in ``unit``; else the sentence
    (without a full stop) ``x, y read in mm but the session is in in``."""
    other: dict[str, list[str]] = {}
    for channel in channels:
        reading = readings.get(channel)
        if reading is not None and reading.unit != unit:
            other.setdefault(reading.unit, []).append(channel)
    if not other:
        return ""
    parts = [
        f"{', '.join(names)} {'reads' if len(names) == 1 else 'read'} in {other_unit}"
        for other_unit, names in other.items()
    ]
    return "; ".join(parts) + f" but the session is in {unit}"


__all__ = [
    "FrameInference",
    "FrameSample",
    "MIN_DISTINCT_FOR_STEP",
    "decimals_of_value",
    "describe_inference",
    "frames_disagree",
    "infer_channel",
    "step_text",
    "unit_mismatch",
]
