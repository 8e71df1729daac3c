"""Mitutoyo command-style RS-232C of the ID-H indicators (likely also EH/EV counters).

``GA**`` CR LF asks indicator ``**`` (ID No. 00-99) for its value; it answers
``GN**,+0016.2345`` CR LF in normal mode, ``GX``/``GM``/``GW`` for max/min/TIR modes, all taken
as readings of that indicator (gauges.md §4, format CONFIRMED). ``CR**`` zero-sets and is
acknowledged by ``CH**``; ``CH``/``DH`` answers (acks, judgements) are ``status``. Baud, parity
and stop bits are UNCONFIRMED: 9600 8N1 by default, change them per site.

Device channel = the ID number without leading zeros (``"1"`` is ID ``01`` on the wire). The
value width copies the manual's example (9 characters: ``0016.2345``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from station.instruments.base import Rejected, RejectReason, SerialSettings, Value
from station.instruments.protocols.common import GaugeProtocol, format_magnitude, malformed

_DATA = re.compile(rb"G[NXMW]\d\d,[+-](?:\d+\.?\d*|\.\d+)")
_DEVICE_CHANNELS = {b"%02d" % number: str(number) for number in range(100)}
_MODES = {"N": "normal", "X": "max", "M": "min", "W": "TIR"}

VALUE_WIDTH = 9


@dataclass
class MitutoyoIDH(GaugeProtocol):
    """Mitutoyo ID-H style: ``GA01`` -> ``GN01,+0016.2345``; ``CR01`` zero-sets."""

    name = "idh"
    description = "Mitutoyo ID-H indicator command set (GA** / GN**, CRLF)"

    settings: SerialSettings = field(default_factory=lambda: SerialSettings(9600, 8, "N", 1))
    terminator: bytes = b"\r\n"
    request_template: bytes | None = b"GA{channel}\r\n"
    zero_template: bytes | None = b"CR{channel}\r\n"
    mode: str = "N"
    """The indicator's mode letter in the replies :meth:`encode` writes (N, X, M or W)."""

    def parse(self, frame: bytes) -> Value | Rejected:
        """``GN01,+0016.2345`` -> Value("1", 16.2345); ``CH01`` / ``DH01,…`` -> status."""
        if _DATA.fullmatch(frame) is not None:
            return self.accept(_DEVICE_CHANNELS[frame[2:4]], float(frame[5:]), None)
        kind = frame[:2]
        if kind == b"CH":
            return Rejected("status", "command acknowledged, not a measurement")
        if kind == b"DH":
            answer = frame[5:].decode("ascii", "replace")
            return Rejected("status", f"indicator answer {answer!r}, not a measurement")
        return malformed("ID-H GN")

    def wire_channel(self, device_channel: str) -> str:
        """The two-digit ID number: ``"1"`` -> ``01``."""
        wire = f"{int(device_channel):02d}"
        if wire.encode() not in _DEVICE_CHANNELS:
            raise ValueError("an ID-H ID number is 0 to 99")
        return wire

    def encode(self, device_channel: str, value: float, resolution: float, unit: str) -> bytes:
        """``G{mode}{id},{sign}{9 chars}`` CR LF."""
        if self.mode not in _MODES:
            raise ValueError(f"ID-H mode must be one of {', '.join(_MODES)}, not {self.mode!r}")
        sign, magnitude = format_magnitude(value, resolution, VALUE_WIDTH)
        text = f"G{self.mode}{self.wire_channel(device_channel)},{sign}{magnitude}"
        return text.encode() + self.terminator

    def fault_frames(self, device_channel: str) -> dict[RejectReason, bytes]:
        """The zero-set acknowledgement ``CH**``."""
        return {"status": f"CH{self.wire_channel(device_channel)}".encode() + self.terminator}
