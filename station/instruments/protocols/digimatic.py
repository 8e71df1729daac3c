"""The 13-digit Mitutoyo Digimatic (SPC) frame written as text by bit-level adaptors.

An adaptor (Arduino, Pico) clocks the 52 bits off the gauge's Digimatic cable and writes the 13
nibbles as hex digit characters, e.g. ``FFFF000012330`` (spaces between the digits are
accepted). Digits (gauges.md §1, CONFIRMED): d1-d4 header ``FFFF``; d5 sign (``0`` +, ``8`` -);
d6-d11 six BCD digits, most significant first; d12 decimal point position n (value x 10^-n,
n = 0..5); d13 unit: ``0`` mm, ``1`` inch, LSM-6200 codes ``2``-``7`` = unit with a GO/NG
judgement (2 mm +NG, 3 mm GO, 4 mm -NG, 5 inch +NG, 6 inch GO, 7 inch -NG; the value is still
taken), and ``8`` = inch as a Mahr Maxum III manual writes it (UNCONFIRMED, accepted).
A bad header, sign, point position, unit or a non-BCD digit is ``malformed``.

Terminator CR by default (configurable); push by default, ``request_template`` for an adaptor
that answers a request byte. The frame has no channel: device channel ``channels[0]``.
"""

from __future__ import annotations

from dataclasses import dataclass

from station.instruments.base import Rejected, Value
from station.instruments.protocols.common import GaugeProtocol, decimals_for, quantise

_UNIT_CODES = {
    48 + code: unit
    for code, unit in enumerate(("mm", "in", "mm", "mm", "mm", "in", "in", "in", "in"))
}
"""d13 character -> unit: 0 mm, 1 in, 2-4 mm (LSM-6200), 5-7 in (LSM-6200), 8 in (Mahr)."""

_SIGNS = {ord("0"): 1.0, ord("8"): -1.0}
# Divide by an exact power of ten: 1248 * 10.0**-2 is 12.480000000000001, 1248 / 100 is 12.48.
_DIVISOR = tuple(10**n for n in range(6))
_FRAME_LENGTH = 13


@dataclass
class DigimaticText(GaugeProtocol):
    """Digimatic nibbles as hex text: ``FFFF000012330`` -> +0.123 mm."""

    name = "digimatic"
    description = "Digimatic 13-digit frame as text from a bit-level adaptor (FFFF000012330)"

    carries_unit = True
    terminator: bytes = b"\r"

    def frame_decimals(self, frame: bytes) -> int | None:
        """The point-position digit (d12): ``FFFF000012330`` -> 3."""
        frame = frame.replace(b" ", b"")
        if len(frame) != _FRAME_LENGTH or not 48 <= frame[11] <= 53:
            return None
        return frame[11] - 48

    def parse(self, frame: bytes) -> Value | Rejected:
        """``FFFF021076540`` -> +21.0765 mm; ``FFFF801234530`` -> -12.345 mm."""
        if b" " in frame:
            frame = frame.replace(b" ", b"")
        if len(frame) != _FRAME_LENGTH:
            return Rejected("malformed", f"a Digimatic frame has 13 digits, not {len(frame)}")
        if frame[:4].upper() != b"FFFF":
            return Rejected("malformed", "a Digimatic frame starts with the header FFFF")
        sign = _SIGNS.get(frame[4])
        if sign is None:
            return Rejected("malformed", "the Digimatic sign digit must be 0 (+) or 8 (-)")
        digits = frame[5:11]
        if not (digits.isdigit() and digits.isascii()):
            return Rejected("malformed", "the Digimatic value digits must be BCD (0 to 9)")
        point = frame[11] - 48
        if not 0 <= point <= 5:
            return Rejected("malformed", "the Digimatic point position must be 0 to 5")
        unit = _UNIT_CODES.get(frame[12])
        if unit is None:
            return Rejected("malformed", "the Digimatic unit digit must be 0 to 8")
        return self.accept(self.channels[0], sign * int(digits) / _DIVISOR[point], unit)

    def encode(self, device_channel: str, value: float, resolution: float, unit: str) -> bytes:
        """``FFFF{sign}{6 BCD digits}{point}{unit}`` and the terminator."""
        point = decimals_for(resolution)
        if point > 5:
            raise ValueError(f"a Digimatic frame has at most 5 decimals, not {point}")
        counts = round(abs(quantise(value, resolution)) * 10**point)
        if counts > 999_999:
            raise ValueError(f"{value} does not fit in 6 Digimatic digits at {resolution}")
        sign = "8" if value < 0 and counts else "0"
        text = f"FFFF{sign}{counts:06d}{point}{1 if unit == 'in' else 0}"
        return text.encode() + self.terminator
