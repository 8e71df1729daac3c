"""Mitutoyo "01A" ASCII format: USB-ITN input tools in serial mode, MUX-10 format multiplexers.

Frame (gauges.md §2, CONFIRMED): ``0{channel}A{sign}{8 chars}`` CR, e.g. ``01A+0000.123``; the
8 characters are the value zero-padded with a floating point (0.1234 in -> ``000.1234``).
The channel is one character (``1`` on single-channel tools); the reader maps it to ``x``/``y``/
``z``. Error frames start with ``9``: ``9{channel}{code}`` (1 no data, 2 format error, 9 system
error; CODE-ONLY). A ``1…`` frame is the device-information reply. The frame carries no unit.

Poll request ``1`` CR (USB-ITN, CODE-ONLY). A real MUX-10F's request, settings and channel-10
encoding are UNCONFIRMED: set ``request_template`` (e.g. ``b"{channel}\\r"``), the settings and
the channel map per site. 9600 8N1 by default. No zero command: the station zeroes in software.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from types import MappingProxyType

from station.instruments.base import Rejected, RejectReason, SerialSettings, Value
from station.instruments.protocols.common import GaugeProtocol, format_magnitude, malformed

# Exactly 8 value characters: a frame torn short (``01A+0000.12``) must not pass as a reading.
# float() then rejects two points; a plain pattern and a slice beat capture groups on speed.
_DATA = re.compile(rb"0[0-9A-Za-z]A[+-][\d.]{8}")

ERROR_CODES = {"1": "no data", "2": "format error", "9": "system error"}
"""Error codes after ``9{channel}`` (horvathzoltan/mitutoyo_reader; CODE-ONLY)."""

VALUE_WIDTH = 8


@dataclass
class Mitutoyo(GaugeProtocol):
    """The Mitutoyo "01A" ASCII format (MUX-10 format)."""

    name = "mitutoyo"
    description = "Mitutoyo 01A ASCII (USB-ITN input tool, MUX-10 format multiplexer)"

    settings: SerialSettings = field(default_factory=lambda: SerialSettings(9600, 8, "N", 1))
    terminator: bytes = b"\r"
    request_template: bytes | None = b"1\r"
    units_by_decimals = MappingProxyType({3: "mm", 4: "in", 5: "in"})
    """0.123 mm at 0.001 -> ``0000.123``; 0.1234 in -> ``000.1234``; 0.12345 in ->
    ``00.12345`` (QM-Height manual §6.3): the usual decimals per unit, for wording."""

    def parse(self, frame: bytes) -> Value | Rejected:
        """``01A+0000.123`` -> Value("1", 0.123); ``9…`` -> error; ``1…`` -> status."""
        if _DATA.fullmatch(frame) is not None:
            try:
                value = float(frame[3:])
            except ValueError:
                return malformed("Mitutoyo 01A")
            return self.accept(chr(frame[1]), value, None)
        if frame[:1] == b"9":
            return _error(frame)
        if frame[:1] == b"1":
            return Rejected("status", "device information, not a measurement")
        return malformed("Mitutoyo 01A")

    def wire_channel(self, device_channel: str) -> str:
        """The channel character itself; raises ValueError unless it is one digit or letter."""
        if not (len(device_channel) == 1 and device_channel.isascii() and device_channel.isalnum()):
            raise ValueError("a Mitutoyo 01A channel is one digit or letter")
        return device_channel

    def encode(self, device_channel: str, value: float, resolution: float, unit: str) -> bytes:
        """``0{channel}A{sign}{8 chars}`` CR at the resolution's digits (unit is not sent)."""
        sign, magnitude = format_magnitude(value, resolution, VALUE_WIDTH)
        text = f"0{self.wire_channel(device_channel)}A{sign}{magnitude}"
        return text.encode() + self.terminator

    def fault_frames(self, device_channel: str) -> dict[RejectReason, bytes]:
        """A no-data error and a device-information line."""
        return {
            "error": f"9{self.wire_channel(device_channel)}1".encode() + self.terminator,
            "status": b"1MITUTOYO" + self.terminator,
        }


def _error(frame: bytes) -> Rejected:
    code = chr(frame[2]) if len(frame) >= 3 else ""
    meaning = ERROR_CODES.get(code, "unknown error")
    channel = chr(frame[1]) if len(frame) >= 2 else "?"
    return Rejected("error", f"device error {code or '?'} on channel {channel}: {meaning}")
