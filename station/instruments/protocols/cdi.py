"""Chicago Dial Indicator (CDI) USB/RS-232 output (also the Starrett IQ's reply shape).

9600 8N1; ``R`` CR reads, ``C`` CR zeroes (gauges.md §8, CONFIRMED by dialindicator.com).
The reply is 15 characters: polarity ``+``/``-``, an 8-character reading including the
point, a comma and a space, the unit ``IN`` or ``MM``, CR LF, e.g. ``+0012.345, MM``. The
vendor notes the reading may include blanks for readability and the summary in the reference
writes ``+####.### , MM``; the parser takes spaces on either side of the comma and inside the
reading (Starrett IQ: ``+ 2.1380, MM``). One gauge per port: device channel ``channels[0]``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from station.instruments.base import Rejected, SerialSettings, Value
from station.instruments.protocols.common import GaugeProtocol, format_magnitude, malformed

_DATA = re.compile(rb"([+-]) *(\d+\.?\d*|\.\d+) *, *(MM|IN|mm|in)")

READING_WIDTH = 8


@dataclass
class ChicagoDialIndicator(GaugeProtocol):
    """Chicago Dial Indicator: ``R`` CR -> ``+0012.345, MM`` CR LF; ``C`` CR zeroes."""

    name = "cdi"
    description = "Chicago Dial Indicator USB/RS-232 (R to read, C to zero)"
    carries_unit = True

    settings: SerialSettings = field(default_factory=lambda: SerialSettings(9600, 8, "N", 1))
    terminator: bytes = b"\r\n"
    request_template: bytes | None = b"R\r"
    zero_template: bytes | None = b"C\r"

    def parse(self, frame: bytes) -> Value | Rejected:
        """``+0012.345, MM`` -> 12.345 mm; ``-0.04500, IN`` -> -0.045 in."""
        match = _DATA.fullmatch(frame)
        if match is None:
            return malformed("Chicago Dial Indicator")
        value = float(match[2])
        if match[1] == b"-":
            value = -value
        unit = "in" if match[3] in (b"IN", b"in") else "mm"
        return self.accept(self.channels[0], value, unit)

    def encode(self, device_channel: str, value: float, resolution: float, unit: str) -> bytes:
        """``{sign}{8-char reading}, {MM|IN}`` CR LF."""
        sign, reading = format_magnitude(value, resolution, READING_WIDTH)
        return f"{sign}{reading}, {'IN' if unit == 'in' else 'MM'}".encode() + self.terminator
