"""What the gauge protocols share: configurable request/zero templates, the gauge range, digits.

Every protocol in this package is a :class:`GaugeProtocol`. Its instance fields are the parts a
site may have to change because the reference marks them UNCONFIRMED or because gauges differ:
serial settings, terminator, the poll request and zero command (byte templates where
``{channel}`` stands for the device channel as the device writes it), the device channels
served by the port, and the gauge range. A protocol is *polled* when it has a request template;
without one the device pushes (a DATA button, a foot switch, a data logger).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from decimal import Decimal

from station.instruments.base import Protocol, Rejected, RejectReason, Value

CHANNEL_PLACEHOLDER = b"{channel}"


def decimals_for(resolution: float) -> int:
    """Digits after the point that a gauge of this resolution shows (0.001 -> 3, 0.005 -> 3)."""
    if not resolution > 0 or not math.isfinite(resolution):
        raise ValueError(f"a gauge resolution must be a positive number, not {resolution!r}")
    exponent = Decimal(repr(resolution)).normalize().as_tuple().exponent
    return max(0, -int(exponent))


def quantise(value: float, resolution: float) -> float:
    """``value`` rounded to the nearest multiple of ``resolution``, as the gauge displays it."""
    return round(value / resolution) * resolution


def format_magnitude(value: float, resolution: float, width: int = 0) -> tuple[str, str]:
    """The sign character and the zero-padded magnitude of ``value`` at ``resolution``.

    ``width`` counts the digits and the point (Mitutoyo pads to 8: ``0000.123``; 0 = no
    padding). A value that rounds to zero is written with ``+``. Raises ValueError when the
    value does not fit in ``width``.
    """
    decimals = decimals_for(resolution)
    text = f"{abs(quantise(value, resolution)):0{width}.{decimals}f}"
    if width and len(text) > width:
        raise ValueError(f"{value} does not fit in {width} characters at resolution {resolution}")
    sign = "-" if value < 0 and text.strip("0.") else "+"
    return sign, text


@dataclass
class GaugeProtocol(Protocol):
    """A :class:`Protocol` with configurable request/zero templates and a gauge range."""

    request_template: bytes | None = None
    """What to send for one reading (``{channel}`` = device channel); None = the device pushes."""
    zero_template: bytes | None = None
    """What to send to zero the device; None = no zero command (the station zeroes in software)."""
    gauge_range: tuple[float, float] | None = None
    """(low, high) in the unit the gauge reports; a value outside it is ``out_of_range``."""

    @property
    def polled(self) -> bool:
        """True when the station sends a request for each reading."""
        return bool(self.request_template)

    def wire_channel(self, device_channel: str) -> str:
        """The device channel as the device writes it in requests and frames."""
        return device_channel

    def _fill(self, template: bytes | None, device_channel: str) -> bytes | None:
        if not template:
            return None
        return template.replace(CHANNEL_PLACEHOLDER, self.wire_channel(device_channel).encode())

    def request(self, device_channel: str) -> bytes | None:
        """Bytes that ask the device for one reading of ``device_channel``; None when pushed."""
        return self._fill(self.request_template, device_channel)

    def zero_command(self, device_channel: str) -> bytes | None:
        """Bytes that zero the device, or None when it has no zero command."""
        return self._fill(self.zero_template, device_channel)

    def fault_frames(self, device_channel: str) -> dict[RejectReason, bytes]:
        """Example frames (with terminator) the device sends instead of a reading, by reason.

        Only the reasons this device can produce are present (``error``, ``status``,
        ``out_of_range`` when the device itself reports it); the simulator injects them and
        :meth:`parse` rejects each with that reason.
        """
        return {}

    def accept(self, device_channel: str, value: float, unit: str | None) -> Value | Rejected:
        """A value, or ``out_of_range`` when it lies outside the configured gauge range."""
        gauge_range = self.gauge_range
        if gauge_range is not None and not gauge_range[0] <= value <= gauge_range[1]:
            return Rejected(
                "out_of_range",
                f"{value:g} is outside the gauge range {gauge_range[0]:g} to {gauge_range[1]:g}",
            )
        return new_value(device_channel, value, unit)


_new_object = object.__new__


def new_value(device_channel: str, value: float, unit: str | None) -> Value:
    """``Value(device_channel, value, unit)``, built in about half the time.

    A frozen dataclass's ``__init__`` sets each field through ``object.__setattr__``; at
    500,000 frames/s that is a third of the parse budget. Filling the instance dictionary
    directly gives the same (equal, hashable, still frozen) object.
    """
    made = _new_object(Value)
    made.__dict__.update(device_channel=device_channel, value=value, unit=unit)
    return made


def malformed(what: str) -> Rejected:
    """A ``malformed`` rejection naming the format the frame failed to match."""
    return Rejected("malformed", f"not a {what} frame")
