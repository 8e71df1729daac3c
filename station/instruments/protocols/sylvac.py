"""Sylvac Opto-RS (duplex cable), also sold as Käfer and Bowers.

4800 baud, 7 data bits, even parity, 2 stop bits; CR terminator (gauges.md §6, CONFIRMED).
Request ``?`` CR -> ``[sign][digits].[digits]`` CR, sign ``+``, ``-`` or a space (the frame
splitter strips a leading space, so an unsigned value reads as positive); digit counts depend
on unit and resolution (the reference's ``+012.345`` is illustrative: :meth:`Sylvac.encode`
writes 3 integer digits in mm and 2 in inch). ``ERR<n>`` errors: 0 sensor error, 1 incorrect
command, 2 parity error, 3 measurement range exceeded (-> ``out_of_range``). The identification
line ``SY<instr>.<opt>…`` sent at power-on and the ``BAT0``/``BAT1`` battery answer are
``status``. The frame carries no unit and no channel: one instrument per port, device channel
``channels[0]``. No documented zero command: the station zeroes in software. A simplex cable
requests by dropping DTR, which the station does not do; use a duplex cable.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from station.instruments.base import Rejected, RejectReason, SerialSettings, Value
from station.instruments.protocols.common import (
    GaugeProtocol,
    decimals_for,
    format_magnitude,
    malformed,
)

_DATA = re.compile(rb"[+\- ]?(?:\d+\.?\d*|\.\d+)")

ERROR_CODES = {
    "0": "sensor error",
    "1": "incorrect command",
    "2": "parity error (check the 7E2 serial settings)",
    "3": "measurement range exceeded",
}


@dataclass
class Sylvac(GaugeProtocol):
    """Sylvac Opto-RS: ``?`` CR -> ``+012.345`` CR."""

    name = "sylvac"
    description = "Sylvac Opto-RS duplex (4800 7E2)"

    settings: SerialSettings = field(default_factory=lambda: SerialSettings(4800, 7, "E", 2))
    terminator: bytes = b"\r"
    request_template: bytes | None = b"?\r"

    def parse(self, frame: bytes) -> Value | Rejected:
        """``+012.345`` -> 12.345; ``ERR3`` -> out_of_range; ``ERRn`` -> error; ``SY…`` status."""
        if _DATA.fullmatch(frame) is not None:
            return self.accept(self.channels[0], float(frame), None)
        if frame[:3] == b"ERR":
            code = frame[3:].decode("ascii", "replace")
            meaning = ERROR_CODES.get(code, "unknown error")
            reason = "out_of_range" if code == "3" else "error"
            return Rejected(reason, f"Sylvac error {code}: {meaning}")
        if frame[:2] == b"SY":
            return Rejected("status", "instrument identification, not a measurement")
        if frame in (b"BAT0", b"BAT1"):
            state = "low" if frame == b"BAT0" else "ok"
            return Rejected("status", f"battery {state}, not a measurement")
        return malformed("Sylvac Opto-RS")

    def encode(self, device_channel: str, value: float, resolution: float, unit: str) -> bytes:
        """``{sign}{digits}.{digits}`` CR; 3 integer digits in mm, 2 in inch."""
        integer_digits = 2 if unit == "in" else 3
        width = integer_digits + 1 + decimals_for(resolution)
        sign, magnitude = format_magnitude(value, resolution, width)
        return f"{sign}{magnitude}".encode() + self.terminator

    def fault_frames(self, device_channel: str) -> dict[RejectReason, bytes]:
        """A sensor error, the identification line and a range-exceeded error."""
        return {
            "error": b"ERR0" + self.terminator,
            "status": b"SY203.1" + self.terminator,
            "out_of_range": b"ERR3" + self.terminator,
        }
