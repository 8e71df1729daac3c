"""A plain number per line, with an optional channel tag: home-made adaptors and wedges.

Accepted frames: ``0.0012``, ``-.5``, ``x: 0.0012``, ``2,+0.0012``, ``ch1=0.0012``, optionally
followed by a unit ``mm`` or ``in`` (``0.0012 mm``). An untagged number belongs to the first
device channel of the port (``channels[0]``); a tag is the device channel as written (``x``,
``2``). A frame starting with ``#`` is an error (apirek's Pico Digimatic adaptor).

Terminator LF by default (CR LF works too: the frame splitter ends lines at CR or LF) and
configurable. Push by default; set ``request_template`` for an adaptor that answers a byte
(apirek's Pico: any byte; Opentrons' bridge: ``r``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from station.instruments.base import Rejected, RejectReason, Value
from station.instruments.protocols.common import GaugeProtocol, format_magnitude, malformed

_LINE = re.compile(rb"(?:([A-Za-z0-9_]+) *[:,=] *)?([+-]?) *(\d+\.?\d*|\.\d+)(?: *(mm|in|MM|IN))?")
_TAG = re.compile(r"[A-Za-z0-9_]+")
_UNITS = {None: None, b"mm": "mm", b"MM": "mm", b"in": "in", b"IN": "in"}


@dataclass
class AsciiLines(GaugeProtocol):
    """One number per line, ``[tag: ]number[ unit]``; ``#…`` = error."""

    name = "ascii"
    description = "one number per line, optional channel tag (x: 0.0012, 2,+0.0012)"

    terminator: bytes = b"\n"
    tag_channel: bool = True
    """Whether :meth:`encode` writes the channel tag (``2,+0.0012``) or the bare number."""

    def parse(self, frame: bytes) -> Value | Rejected:
        """``x: 0.0012`` -> Value("x", 0.0012); ``0.0012`` -> Value(channels[0], 0.0012)."""
        match = _LINE.fullmatch(frame)
        if match is not None:
            value = float(match[3])
            if match[2] == b"-":
                value = -value
            tag = match[1]
            channel = tag.decode() if tag is not None else self.channels[0]
            return self.accept(channel, value, _UNITS[match[4]])
        if frame[:1] == b"#":
            message = frame[1:].strip().decode("ascii", "replace")
            return Rejected("error", f"adaptor error: {message or 'no message'}")
        return malformed("number-per-line")

    def wire_channel(self, device_channel: str) -> str:
        """The tag as written; raises ValueError unless it is letters, digits or ``_``."""
        if _TAG.fullmatch(device_channel) is None:
            raise ValueError("a channel tag is letters, digits or _, e.g. x or 2")
        return device_channel

    def encode(self, device_channel: str, value: float, resolution: float, unit: str) -> bytes:
        """``{channel},{sign}{value}`` (or the bare signed value) and the terminator."""
        sign, magnitude = format_magnitude(value, resolution)
        text = f"{sign}{magnitude}"
        if self.tag_channel:
            text = f"{self.wire_channel(device_channel)},{text}"
        return text.encode() + self.terminator

    def fault_frames(self, device_channel: str) -> dict[RejectReason, bytes]:
        """An adaptor error line (the gauge did not answer its request)."""
        return {"error": b"# no answer from gauge" + self.terminator}
