"""Mitutoyo U-WAVE-R wireless receiver (U-WAVE-T transmitters on the gauges).

Push only, 57600 8N1, CR terminator (gauges.md §3, CONFIRMED by manual and captures). A reading:
``DT`` + ``1`` (API version) + group(2) + channel(2) + signed value + unit (``M`` mm, ``I`` inch),
e.g. ``DT10000+00000011.88M`` -> 11.88 mm; the number of digits is not fixed (captures pad the
value to 11 characters, which :meth:`UWave.encode` copies).

Device channel: the transmitter channel as a plain number (``"0"``, ``"2"``) for group 00, the
usual single-receiver set-up; ``"{group}/{channel}"`` (``"1/2"``) for other groups.

``ST1…`` status frames (battery low, instrument not responding, ...), ``TI1…`` transmitter info
and ``RI1…`` receiver info are ``status`` rejections, never readings. The ST layout (grp(2)
ch(2) txID(10) code(2)) is from one repository; other layouts still count as status.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from station.instruments.base import Rejected, RejectReason, SerialSettings, Value
from station.instruments.protocols.common import GaugeProtocol, format_magnitude, malformed

# The unit letter is required (every capture has one), so a frame torn short is not a reading.
_DATA = re.compile(rb"DT1\d{4}[+-](?:\d+\.?\d*|\.\d+)[MI]")
_UNITS = {ord("M"): "mm", ord("I"): "in"}
# Group and channel digits -> device channel, computed once: "0002" -> "2", "0102" -> "1/2".
_DEVICE_CHANNELS = {
    b"%02d%02d" % (group, channel): (f"{channel}" if group == 0 else f"{group}/{channel}")
    for group in range(100)
    for channel in range(100)
}

STATUS_CODES = {
    "00": "battery low",
    "01": "instrument not responding",
    "02": "unregistered transmitter",
    "03": "data loss",
    "04": "transmitter disconnected",
    "05": "no data",
    "50": "request packet error",
    "51": "end of search",
    "99": "data cancelled",
}
"""The code ending an ``ST1`` frame (U-WAVEPAK manual, via Ihorhaleliuka/Mitutoyo-U-WAVE-R)."""

VALUE_WIDTH = 11
_ST_LENGTH = len("ST1" + "00" + "01" + "FFFFFFFFFF" + "00")


@dataclass
class UWave(GaugeProtocol):
    """U-WAVE-R receiver frames (``DT1…`` readings, ``ST``/``TI``/``RI`` status)."""

    name = "uwave"
    description = "Mitutoyo U-WAVE-R wireless receiver (push)"

    carries_unit = True
    settings: SerialSettings = field(default_factory=lambda: SerialSettings(57600, 8, "N", 1))
    terminator: bytes = b"\r"

    def parse(self, frame: bytes) -> Value | Rejected:
        """``DT10000+00000011.88M`` -> Value("0", 11.88, "mm"); ST/TI/RI -> status."""
        if _DATA.fullmatch(frame) is not None:
            device_channel = _DEVICE_CHANNELS[frame[3:7]]
            return self.accept(device_channel, float(frame[7:-1]), _UNITS[frame[-1]])
        kind = frame[:2]
        if kind == b"ST":
            return _status(frame)
        if kind == b"TI":
            return Rejected("status", "transmitter information, not a measurement")
        if kind == b"RI":
            return Rejected("status", "receiver information, not a measurement")
        return malformed("U-WAVE DT1")

    def wire_channel(self, device_channel: str) -> str:
        """Group and channel as four digits: ``"2"`` -> ``0002``, ``"1/2"`` -> ``0102``."""
        group, _, channel = device_channel.rpartition("/")
        wire = f"{int(group or 0):02d}{int(channel):02d}"
        if wire.encode() not in _DEVICE_CHANNELS:
            raise ValueError("a U-WAVE group and channel are numbers 0 to 99, e.g. 2 or 1/2")
        return wire

    def encode(self, device_channel: str, value: float, resolution: float, unit: str) -> bytes:
        """``DT1{group}{channel}{sign}{11 chars}{M|I}`` CR."""
        sign, magnitude = format_magnitude(value, resolution, VALUE_WIDTH)
        unit_letter = "I" if unit == "in" else "M"
        text = f"DT1{self.wire_channel(device_channel)}{sign}{magnitude}{unit_letter}"
        return text.encode() + self.terminator

    def fault_frames(self, device_channel: str) -> dict[RejectReason, bytes]:
        """An ``ST`` frame saying the battery of the channel's transmitter is low."""
        wire = self.wire_channel(device_channel)
        return {"status": f"ST1{wire}FFFFFFFFFF00".encode() + self.terminator}


def _status(frame: bytes) -> Rejected:
    if len(frame) == _ST_LENGTH and frame[-2:].isdigit():
        code = frame[-2:].decode()
        meaning = STATUS_CODES.get(code, "unknown status")
        channel = frame[5:7].decode("ascii", "replace")
        return Rejected("status", f"U-WAVE status {code} on channel {channel}: {meaning}")
    return Rejected("status", "U-WAVE status frame")
