"""A zero from several readings: the mean over a settle window, refused while a gauge moves.

One reading is no zero: a noisy one shifts every later reading by its noise (a −0.0010 zero
made a robot centred on 0 read "16 above USL"). :func:`zero_from_readings` takes the readings of
each channel over a settle window and returns, per channel, how many there were (``n``), their
mean, their spread (max − min) and the method (the device's own zero command, or a software
offset). It refuses, naming the channel, when a channel's readings spread over more than
``still`` resolutions (the robot or the gauge moves) or when a channel has fewer readings than
asked for. No I/O: :meth:`station.instruments.gauge.GaugeSet.zero` collects the readings.

The software offset is the mean at one decimal finer than the gauge shows (the mean of N
readings at resolution r is known better than r, but not to the last binary digit).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from station.errors import StationError
from station.instruments.protocols.common import decimals_for
from station.text import format_spread

ZeroMethod = Literal["device", "software"]

DEFAULT_ZERO_READINGS = 10
"""Readings per channel :func:`zero_from_readings` wants unless told (a zero step without
``readings`` asks for 5, or 3 DATA presses: ``station.run.steps.zero``)."""
DEFAULT_ZERO_SETTLE = 1.0
"""Seconds the readings of a zero are spread over when the procedure does not say."""
DEFAULT_ZERO_STILL = 3.0
"""Resolutions the readings of a zero may spread before the gauge counts as moving."""


@dataclass(frozen=True)
class ChannelZero:
    """How one channel was zeroed, from ``n`` device readings taken over the settle window.

    ``offset`` is what is subtracted from later readings: the mean (software zero) or 0.0 (the
    device zeroed itself on its own command, so it already reports zeroed values).
    """

    channel: str
    method: ZeroMethod
    offset: float
    n: int = 1
    mean: float = 0.0
    spread: float = 0.0
    values: tuple[float, ...] = ()
    resolution: float = 0.0

    @property
    def uncertainty(self) -> float:
        """Standard uncertainty of the zero, in the gauge's unit: the standard error of the
        mean combined with the gauge's rounding (resolution / √12), which averaging readings
        that all show the same digit does not remove."""
        rounding = self.resolution / math.sqrt(12.0)
        if self.n < 2:
            return rounding
        mean = sum(self.values) / len(self.values) if self.values else self.mean
        variance = (
            sum((v - mean) ** 2 for v in self.values) / (len(self.values) - 1)
            if len(self.values) > 1
            else 0.0
        )
        return math.sqrt(variance / self.n + rounding**2)

    def record(self) -> dict[str, Any]:
        """The channel's entry of a ``zero`` event: method, offset, n, mean, spread, values."""
        return {
            "method": self.method,
            "offset": self.offset,
            "n": self.n,
            "mean": self.mean,
            "spread": self.spread,
            "values": list(self.values),
        }


def _per_channel(value: float | Mapping[str, float], channel: str, what: str) -> float:
    if isinstance(value, Mapping):
        if channel not in value:
            raise StationError(f"No {what} is given for channel {channel}.")
        return float(value[channel])
    return float(value)


def _clean(value: float) -> float:
    """Without binary noise far below any gauge's resolution (0.1 + 0.2 → 0.3)."""
    return round(value, 10)


def zero_from_readings(
    readings: Mapping[str, Sequence[float]],
    resolution: float | Mapping[str, float],
    *,
    methods: Mapping[str, ZeroMethod] | None = None,
    min_readings: int = DEFAULT_ZERO_READINGS,
    still: float = DEFAULT_ZERO_STILL,
    window: float | None = None,
    unit: str = "",
) -> tuple[ChannelZero, ...]:
    """The zero of each channel from its device readings (in ``readings``' order).

    ``methods`` says per channel whether the device zeroes itself (``device``: offset 0) or the
    station subtracts the mean (``software``, the default). Raises StationError naming the
    channels with fewer than ``min_readings`` readings, or whose readings spread over more than
    ``still`` × resolution (they move; ``window``, the seconds the readings span, and ``unit``
    only word the sentence).
    """
    if min_readings < 1:
        raise StationError(f"A zero needs at least 1 reading per channel, not {min_readings}.")
    short = [c for c, values in readings.items() if len(values) < min_readings]
    if short:
        counts = ", ".join(f"{c} {len(readings[c])}" for c in short)
        over = f" in {window:.1f} s" if window else ""
        raise StationError(
            f"Could not zero {', '.join(short)}: too few readings{over} ({counts}; "
            f"{min_readings} wanted). Check the gauges and zero again."
        )
    zeros = []
    moving = []
    for channel, values in readings.items():
        res = _per_channel(resolution, channel, "resolution")
        spread = _clean(max(values) - min(values))
        if spread > still * res + 1e-12:
            moving.append((channel, spread, res))
            continue
        mean = _clean(sum(values) / len(values))
        method: ZeroMethod = (methods or {}).get(channel, "software")
        offset = round(mean, decimals_for(res) + 1) if method == "software" else 0.0
        zeros.append(
            ChannelZero(channel, method, offset, len(values), mean, spread, tuple(values), res)
        )
    if moving:
        raise GaugesMoving(
            moving_message(moving, still, window, unit), tuple(c for c, _, _ in moving)
        )
    return tuple(zeros)


class GaugesMoving(StationError):
    """A zero refused because channels move (``channels``): nothing was zeroed; wait for the
    robot to be still and zero again."""

    def __init__(self, message: str, channels: tuple[str, ...]) -> None:
        super().__init__(message)
        self.channels = channels


class NotAtFixture(GaugesMoving):
    """A zero refused because the robot is not (known to be) at rest at the fixture: the
    indicators sit at their free-travel stop, or the stop is not known yet and no return was
    seen. Nothing was zeroed; wait for the robot and zero again."""


def moving_message(
    moving: Sequence[tuple[str, float, float]], still: float, window: float | None, unit: str
) -> str:
    """The refusal for channels that move: ``(channel, spread, resolution)`` each."""
    over = f" over {window:.1f} s" if window else ""
    # The spread and the gauge step in the one number format (never 1e-05), as every figure.
    parts = [
        f"{channel} moves (its readings spread {format_spread(spread, res, unit=unit)}{over}, "
        f"more than {still:g} × {format_spread(res, res)})"
        for channel, spread, res in moving
    ]
    return (
        f"Could not zero: {'; '.join(parts)}. Keep the robot still at the fixture, wait for the "
        "indicators to settle, then zero again."
    )


__all__ = [
    "ChannelZero",
    "GaugesMoving",
    "NotAtFixture",
    "DEFAULT_ZERO_READINGS",
    "DEFAULT_ZERO_SETTLE",
    "DEFAULT_ZERO_STILL",
    "ZeroMethod",
    "moving_message",
    "zero_from_readings",
]
