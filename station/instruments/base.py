"""What every gauge protocol, reader and simulator shares: readings, rejections, settings.

A *frame* is the bytes of one message from a device without its terminator. A protocol turns a
frame into a :class:`Value` (device channel, value, unit) or a :class:`Rejected` with a named
reason; the reader stamps accepted values into :class:`Reading` objects with wall and monotonic
time and maps device channels to station channels (``x``, ``y``, ``z`` ...).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import ClassVar, Literal

_DECIMALS = re.compile(rb"\.(\d+)")

RejectReason = Literal["error", "status", "malformed", "out_of_range"]
"""Why a frame is not a reading: the device reported an error, it is a status/info frame, it
does not parse, or the value is outside the gauge's range."""

Parity = Literal["N", "E", "O", "M", "S"]


@dataclass(frozen=True)
class SerialSettings:
    """Line settings handed to ``serial.serial_for_url`` (ignored by ``socket://``)."""

    baudrate: int = 9600
    bytesize: int = 8
    parity: Parity = "N"
    stopbits: float = 1

    def describe(self) -> str:
        """The settings in the usual short form, e.g. ``4800 7E2``."""
        stop = int(self.stopbits) if float(self.stopbits).is_integer() else self.stopbits
        return f"{self.baudrate} {self.bytesize}{self.parity}{stop}"

    def as_kwargs(self) -> dict[str, object]:
        """Keyword arguments for ``serial.serial_for_url``."""
        return {
            "baudrate": self.baudrate,
            "bytesize": self.bytesize,
            "parity": self.parity,
            "stopbits": self.stopbits,
        }


@dataclass(frozen=True)
class Value:
    """A frame that parsed into a measurement, before time-stamping and channel mapping."""

    device_channel: str
    value: float
    unit: str | None = None
    """``"mm"`` or ``"in"`` when the frame says so, else ``None`` (the session's unit applies)."""


@dataclass(frozen=True)
class Rejected:
    """A frame that is not a measurement, with the reason and a sentence for the operator."""

    reason: RejectReason
    detail: str


@dataclass(frozen=True)
class Reading:
    """One accepted measurement of one station channel, as it reached the station."""

    channel: str
    value: float
    unit: str
    raw: str
    t_wall: float
    t_mono: float
    device_channel: str = ""
    port: str = ""


@dataclass(frozen=True)
class Rejection:
    """One rejected frame, kept (with its raw text) so the operator can see what the line said."""

    reason: RejectReason
    detail: str
    raw: str
    t_wall: float
    t_mono: float
    port: str = ""


@dataclass
class Protocol:
    """A gauge wire format. Subclasses set the class attributes and implement :meth:`parse`.

    Instances carry the configurable parts (settings, terminator, request bytes, channels) so that
    details the reference marks UNCONFIRMED can be changed per site without code.
    """

    name: ClassVar[str]
    description: ClassVar[str]
    carries_unit: ClassVar[bool] = False
    """True when every data frame states its unit (mm or inch); else the session's applies."""
    units_by_decimals: ClassVar[Mapping[int, str]] = MappingProxyType({})
    """The unit this protocol's gauges usually show at a number of decimals (the Mitutoyo 01A
    format: 3 in mm, 4 or 5 in inches); words the resolution check, never decides it."""

    settings: SerialSettings = field(default_factory=SerialSettings)
    terminator: bytes = b"\r"
    channels: tuple[str, ...] = ("1",)
    """Device channels this port serves, in the order they are polled."""

    @property
    def polled(self) -> bool:
        """True when the device answers a request; False when it pushes frames by itself."""
        raise NotImplementedError

    def parse(self, frame: bytes) -> Value | Rejected:
        """Turn one frame (terminator stripped) into a value or a named rejection. Never raises."""
        raise NotImplementedError

    def request(self, device_channel: str) -> bytes | None:
        """Bytes that ask the device for one reading of ``device_channel``; None when push-only."""
        return None

    def zero_command(self, device_channel: str) -> bytes | None:
        """Bytes that zero the device, or None when it has no zero command (zero in software)."""
        return None

    def encode(self, device_channel: str, value: float, resolution: float, unit: str) -> bytes:
        """The frame (with terminator) a device sends for ``value``; the simulator speaks it."""
        raise NotImplementedError

    def frame_decimals(self, frame: bytes) -> int | None:
        """Digits after the decimal point of the value in a data ``frame`` (terminator
        stripped): what resolution the gauge shows. None when the frame writes no point.

        By default the digits after the last point followed by a digit; a protocol whose
        frames write the point another way (the Digimatic point digit) overrides it."""
        found = _DECIMALS.findall(frame)
        return len(found[-1]) if found else None
