"""The gauge wire protocols by name, and :func:`get_protocol` to configure one for a port.

Options of :func:`get_protocol` (``None`` means "not given", so a CLI can pass every flag):

* ``baudrate``, ``bytesize``, ``parity``, ``stopbits``: override the default serial settings.
* ``terminator``: the frame terminator.
* ``request``: the poll request template (``{channel}`` = device channel); ``""`` = push only.
* ``zero``: the zero command template; ``""`` = zero in software.
* ``channels``: the device channels the port serves (a sequence or ``"1,2,3"``).
* ``gauge_range``: ``(low, high)``; values outside are rejected as ``out_of_range``.
* any other field of the protocol's dataclass, e.g. ``tag_channel`` for ``ascii``.

Byte options may be given as text with backslash escapes (``"1\\r"``, ``"GA{channel}\\r\\n"``),
as typed on a command line.
"""

from __future__ import annotations

import dataclasses

from station.errors import StationError
from station.instruments.base import SerialSettings
from station.instruments.protocols.ascii import AsciiLines
from station.instruments.protocols.cdi import ChicagoDialIndicator
from station.instruments.protocols.common import GaugeProtocol
from station.instruments.protocols.digimatic import DigimaticText
from station.instruments.protocols.idh import MitutoyoIDH
from station.instruments.protocols.mitutoyo import Mitutoyo
from station.instruments.protocols.sylvac import Sylvac
from station.instruments.protocols.uwave import UWave

PROTOCOLS: dict[str, type[GaugeProtocol]] = {
    cls.name: cls
    for cls in (
        Mitutoyo,
        UWave,
        Sylvac,
        ChicagoDialIndicator,
        MitutoyoIDH,
        AsciiLines,
        DigimaticText,
    )
}
"""Every protocol class by its name (each a :class:`~station.instruments.base.Protocol`)."""

_SETTINGS_OPTIONS = ("baudrate", "bytesize", "parity", "stopbits")
_ALIASES = {"request": "request_template", "zero": "zero_template"}
_BYTE_FIELDS = ("terminator", "request_template", "zero_template")


def protocol_names() -> list[str]:
    """The known protocol names, in registry order."""
    return list(PROTOCOLS)


def as_bytes(text: str | bytes) -> bytes:
    """Bytes from an option value; text may carry backslash escapes such as ``\\r``."""
    if isinstance(text, bytes | bytearray):
        return bytes(text)
    try:
        return text.encode("latin-1").decode("unicode_escape").encode("latin-1")
    except (UnicodeError, ValueError) as exc:
        raise StationError(
            f"{text!r} is not valid text for bytes on the wire ({exc}); "
            "use plain ASCII and escapes such as \\r, \\n or \\x03"
        ) from None


def get_protocol(name: str, **options: object) -> GaugeProtocol:
    """A configured protocol instance; raises StationError for an unknown name or option."""
    cls = PROTOCOLS.get(name)
    if cls is None:
        raise StationError(
            f"unknown gauge protocol {name!r}; the known protocols are {', '.join(PROTOCOLS)}"
        )
    given = {_ALIASES.get(key, key): value for key, value in options.items() if value is not None}
    field_names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(given) - field_names - set(_SETTINGS_OPTIONS))
    if unknown:
        raise StationError(
            f"the {name} protocol has no option {', '.join(unknown)}; it takes "
            f"{', '.join(sorted(set(field_names) - {'settings'} | set(_SETTINGS_OPTIONS)))}"
        )
    overrides = {key: given.pop(key) for key in _SETTINGS_OPTIONS if key in given}
    for key in _BYTE_FIELDS:
        if key in given:
            given[key] = as_bytes(given[key]) or None  # type: ignore[arg-type]
    if "terminator" in given and given["terminator"] is None:
        raise StationError("a frame terminator cannot be empty")
    if isinstance(given.get("channels"), str):
        given["channels"] = given["channels"].split(",")  # type: ignore[union-attr]
    if "channels" in given:
        channels = tuple(str(c).strip() for c in given["channels"])  # type: ignore[union-attr]
        if not channels or not all(channels):
            raise StationError("give at least one device channel, e.g. 1 or 1,2,3")
        given["channels"] = channels
    if "gauge_range" in given:
        given["gauge_range"] = _gauge_range(given["gauge_range"])
    protocol = cls(**given)  # type: ignore[arg-type]
    if overrides:
        protocol.settings = _settings(protocol.settings, overrides)
    for channel in protocol.channels:
        try:
            protocol.wire_channel(channel)
        except ValueError as exc:
            raise StationError(
                f"the {name} protocol has no device channel {channel!r}: {exc}"
            ) from None
    return protocol


def _gauge_range(value: object) -> tuple[float, float]:
    try:
        low, high = (float(v) for v in value)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise StationError(f"a gauge range is two numbers, low and high, not {value!r}") from None
    if not low < high:
        raise StationError(f"the gauge range {low:g} to {high:g} is empty; give low < high")
    return (low, high)


def _settings(default: SerialSettings, overrides: dict[str, object]) -> SerialSettings:
    converters = {
        "baudrate": int,
        "bytesize": int,
        "parity": lambda v: str(v).upper(),
        # pyserial compares with 1, 1.5 and 2; keep whole numbers as int for describe().
        "stopbits": lambda v: int(float(v)) if float(v).is_integer() else float(v),
    }
    try:
        settings = dataclasses.replace(
            default, **{key: converters[key](value) for key, value in overrides.items()}
        )
    except (TypeError, ValueError):
        raise StationError(f"bad serial settings {overrides}; e.g. baudrate 9600") from None
    problems = []
    if settings.baudrate <= 0:
        problems.append(f"baud rate {settings.baudrate}")
    if settings.bytesize not in (5, 6, 7, 8):
        problems.append(f"data bits {settings.bytesize} (5 to 8)")
    if settings.parity not in ("N", "E", "O", "M", "S"):
        problems.append(f"parity {settings.parity} (N, E, O, M or S)")
    if settings.stopbits not in (1, 1.5, 2):
        problems.append(f"stop bits {settings.stopbits:g} (1, 1.5 or 2)")
    if problems:
        raise StationError(f"impossible serial settings: {', '.join(problems)}")
    return settings


__all__ = ["PROTOCOLS", "GaugeProtocol", "as_bytes", "get_protocol", "protocol_names"]
