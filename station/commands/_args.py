"""Numbers from the command line, read the same way by every command.

Commands take numeric options as text and parse them here, so that a bad value is the same
one-line ``station: ...`` error as every other bad input (not argparse's usage block), worded
the same whichever command it came to.
"""

from __future__ import annotations

import math
import re

from station.errors import StationError

_DECIMAL = re.compile(
    r"^\s*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf|infinity|nan)\s*$",
    re.IGNORECASE | re.ASCII,
)
"""A number as a person types it: ASCII digits, no ``1_000`` (Python's float() takes it), no
other scripts' digits."""


def parse_number(text: str | None, option: str) -> float | None:
    """A finite number given as ``option``; None when absent or blank."""
    if text is None or not text.strip():
        return None
    if not _DECIMAL.match(text):
        raise StationError(f"{option} {text!r} is not a number.")
    value = float(text)
    if not math.isfinite(value):
        raise StationError(f"{option} {text!r} is not a finite number.")
    if abs(value) > LIMIT_MAGNITUDE:
        raise StationError(f"{option} {text!r} is beyond ±{LIMIT_MAGNITUDE:g}.")
    return value


def positive_number(text: str | None, option: str, kind: type = float) -> float | int | None:
    """A number above 0 given as ``option`` (a whole one with ``kind=int``); None when absent."""
    if text is None:
        return None
    if kind is int:
        try:
            if not re.fullmatch(r"\s*[+-]?\d+\s*", text, re.ASCII):
                raise ValueError(text)
            value: float | int = int(text)
        except ValueError:
            word = "a whole number" if _is_float(text) else "a number"
            raise StationError(f"{option} {text!r} is not {word}.") from None
    else:
        value = parse_number(text, option) if text.strip() else None
        if value is None:
            raise StationError(f"{option} {text!r} is not a number.")
    if not value > 0:
        raise StationError(f"{option} must be more than 0, not {text}.")
    return value


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def bounded_number(
    text: str | None, option: str, low: float, high: float, *, default: float | None = None
) -> float | None:
    """A finite number from ``low`` to ``high`` given as ``option`` (``default`` when absent)."""
    value = parse_number(text, option)
    if value is None:
        return default
    if not low <= value <= high:
        raise StationError(f"{option} must be from {low:g} to {high:g}, not {text}.")
    return value


def bounded_int(text: str | None, option: str, low: int, high: int) -> int | None:
    """A whole number from ``low`` to ``high`` given as ``option``; None when absent."""
    if text is None or not text.strip():
        return None
    try:
        if not re.fullmatch(r"\s*[+-]?\d+\s*", text, re.ASCII):
            raise ValueError(text)
        value = int(text)
    except ValueError:
        word = "a whole number" if _is_float(text) else "a number"
        raise StationError(f"{option} {text!r} is not {word}.") from None
    if not low <= value <= high:
        raise StationError(f"{option} must be a whole number from {low} to {high}, not {text}.")
    return value


def limit_value(text: str | None, option: str, side: str) -> float | None:
    """A specification limit: a finite number, or ``-inf`` for no lower limit (``side``
    ``"lower"``) and ``inf`` for no upper one (``"upper"``), which mean the same as leaving it
    out. None when absent."""
    if text is None or not text.strip():
        return None
    if not _DECIMAL.match(text):
        raise StationError(f"{option} {text!r} is not a number.")
    value = float(text)
    if math.isinf(value) and (value < 0) == (side == "lower"):
        return None
    if not math.isfinite(value):
        raise StationError(f"{option} {text!r} is not a finite number.")
    if abs(value) > LIMIT_MAGNITUDE:
        raise StationError(f"{option} {text!r} is beyond ±{LIMIT_MAGNITUDE:g}.")
    return value


def parse_limit(text: str) -> tuple[str, float | None, float | None]:
    """Split ``CH=LSL:USL`` (either side may be empty) into channel, lsl, usl."""
    channel, equals, bounds = text.partition("=")
    lsl_text, colon, usl_text = bounds.partition(":")
    if not equals or not colon or not channel.strip():
        raise StationError(
            f"--limit {text!r} is not CH=LSL:USL; write e.g. --limit x=-0.001:0.001 "
            "(or x=:0.001 for an upper limit only)."
        )
    lsl = limit_value(lsl_text, f"--limit {channel.strip()} lower limit", "lower")
    usl = limit_value(usl_text, f"--limit {channel.strip()} upper limit", "upper")
    if lsl is None and usl is None:
        raise StationError(f"--limit {text!r} gives neither a lower nor an upper limit.")
    return channel.strip(), lsl, usl


LIMIT_MAGNITUDE = 1e150
"""Limits, like readings, stay within ±1e150 so the capability arithmetic stays finite."""
RESOLUTION_RANGE = (1e-12, 1e6)
"""A gauge resolution from a picometre-class 1e-12 to 1e6 (any unit): the bins stay countable."""
