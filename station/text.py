"""Text in and out, in one place: channel maps, limits, numbers at a gauge's resolution and the
verdict words.

Both front ends (the set-up screen and the command line) read what the operator typed with these
functions, and every screen, report and command prints numbers and verdicts with them, so a
value looks the same wherever it is shown and a typing rule is the same wherever it is typed.
Errors are :class:`~station.errors.StationError` sentences that name no option or key (the
front end adds where to type).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from decimal import Decimal
from typing import Any

from station.errors import StationError

NOT_AVAILABLE = "-"
"""What a figure that is undefined shows (σ of one reading, Cpk without limits)."""

LIMIT_HELP = "±0.001 or LSL:USL, e.g. -0.001:0.0015 (one side may be empty)"
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


# -- numbers at a resolution ------------------------------------------------------------------


def _step_decimals(resolution: float | None) -> int:
    """How many decimals a gauge of ``resolution`` shows (0.0001 -> 4, 0.0005 -> 4, 0.002 -> 3,
    1e-05 -> 5); 5 when the resolution is unknown."""
    if resolution is None or not math.isfinite(resolution) or resolution <= 0:
        return 5
    exponent = Decimal(repr(float(resolution))).normalize().as_tuple().exponent
    return max(0, -int(exponent))


def figure_decimals(resolution: float | None) -> int:
    """Decimals of every figure in the session's unit: one beyond the gauge's step (0.0001 ->
    5; 6 when the step is unknown). A reading after a zero taken as a mean of several readings
    is no whole step (+0.00103 at a 0.0001 in gauge), and a mean or a limit keeps the digit it
    resolves: at the step's own decimals the value shown would not be the value judged."""
    return _step_decimals(resolution) + 1


def format_figure(
    value: float | None, resolution: float | None, *, signed: bool = True, unit: str = ""
) -> str:
    """The one number format of the station: a figure in the session's unit (a reading, a
    zero, a mean, σ, a limit, a control line, an offset) at :func:`figure_decimals`, signed for
    a position (``+0.00012``: a reading, a mean, a limit, an offset) and unsigned for a spread
    or a size (``signed=False``: σ, a range, a tolerance), never in scientific notation, with
    `` unit`` after it when given; ``-`` when undefined.

    Every screen, message, alarm, command and report writes its figures with this function, so
    a value reads the same wherever it is shown. Rounding is for the eye only: the session file
    keeps the full value."""
    if value is None or isinstance(value, bool) or not math.isfinite(value):
        return NOT_AVAILABLE
    decimals = figure_decimals(resolution)
    text = f"{value:+.{decimals}f}" if signed else f"{value:.{decimals}f}"
    if text.startswith("-") and not text.strip("-0."):
        # -0.000004 at five decimals would read "-0.00000": a zero has no sign worth showing.
        text = ("+" if signed else "") + text[1:]
    return f"{text} {unit}" if unit else text


def format_spread(value: float | None, resolution: float | None, *, unit: str = "") -> str:
    """A spread or a size (σ, a range, a tolerance): :func:`format_figure` unsigned."""
    return format_figure(value, resolution, signed=False, unit=unit)


def format_index(value: float | None) -> str:
    """A capability index (Cp, Cpk) or a₁ with two decimals, or ``-`` when undefined."""
    if value is None or not math.isfinite(value):
        return NOT_AVAILABLE
    return f"{value:.2f}"


# -- verdict words ----------------------------------------------------------------------------

CAPABLE, NOT_CAPABLE, UNDEFINED = "CAPABLE", "NOT CAPABLE", "UNDEFINED"
INCONCLUSIVE = "INCONCLUSIVE"


def verdict_word(capability: Any) -> str:
    """The report's point-estimate rule as a word: CAPABLE, NOT CAPABLE or UNDEFINED from
    ``capability.capable`` (True, False, None). A channel's verdict, which weighs the confidence
    bounds too, is :func:`judged_word`; this is only its fallback for an analysis without one."""
    capable = getattr(capability, "capable", None) if capability is not None else None
    if capable is True:
        return CAPABLE
    if capable is False:
        return NOT_CAPABLE
    return UNDEFINED


def overall_verdict(words: Iterable[str]) -> str:
    """The session's verdict: NOT CAPABLE if any axis is, CAPABLE if all are, INCONCLUSIVE if
    any is (and none is NOT CAPABLE), else UNDEFINED."""
    words = list(words)
    if not words:
        return UNDEFINED
    if NOT_CAPABLE in words:
        return NOT_CAPABLE
    if all(word == CAPABLE for word in words):
        return CAPABLE
    if INCONCLUSIVE in words:
        return INCONCLUSIVE
    return UNDEFINED


PROVISIONAL = "PROVISIONAL"


def judged_word(channel: Any) -> str:
    """A channel analysis' verdict word: its ``verdict`` (PROVISIONAL below the minimum count,
    see :mod:`station.analysis.verdict`), else :func:`verdict_word` of its capability."""
    verdict = getattr(channel, "verdict", None)
    if verdict is not None:
        return str(verdict.word)
    return verdict_word(getattr(channel, "capability", None))


def judged_label(channel: Any) -> str:
    """:func:`judged_word` with the count of a provisional verdict (``PROVISIONAL: 9 of 25``)."""
    verdict = getattr(channel, "verdict", None)
    return str(verdict.label) if verdict is not None else judged_word(channel)


def judged_cpk(channel: Any) -> str:
    """The Cpk as the verdict reads it: enough decimals that the shown figure and the word
    never contradict each other (``0.9996`` beside NOT CAPABLE, never ``1.00``); two decimals
    without a verdict, "-" when undefined."""
    verdict = getattr(channel, "verdict", None)
    if verdict is not None and verdict.cpk is not None:
        return str(verdict.cpk_text)
    return format_index(getattr(getattr(channel, "capability", None), "cpk", None))


def judged_count(analysis: Any) -> str:
    """How many readings the verdict rests on, and the minimum a verdict needs: ``judged on 30
    readings (a verdict needs 25)``; the fewest of the channels when they differ. Never the bare
    minimum, which read as the count judged ("final from 25 readings" on 30)."""
    counts = [
        int(getattr(getattr(c, "descriptive", None), "n", 0) or 0)
        for c in getattr(analysis, "channels", {}).values()
    ]
    n = min(counts) if counts else 0
    minimum = analysis.config.min_n
    noun = "reading" if n == 1 else "readings"
    return f"judged on {n} {noun} (a verdict needs {minimum})"


def overall_judgement(channels: Iterable[Any]) -> str:
    """The session's verdict over channel analyses: ``PROVISIONAL: k of n`` while any channel
    is below the minimum count (k its fewest readings), else :func:`overall_verdict`."""
    channels = list(channels)
    provisional = [
        c.verdict for c in channels if getattr(getattr(c, "verdict", None), "provisional", False)
    ]
    if provisional:
        fewest = min(provisional, key=lambda verdict: verdict.n)
        return f"{PROVISIONAL}: {fewest.n} of {fewest.min_n}"
    return overall_verdict(judged_word(c) for c in channels)


# -- channel maps -----------------------------------------------------------------------------


def parse_channel_map(text: str | None) -> dict[str, str]:
    """``"1=x,2=y,3=z"`` -> ``{"1": "x", "2": "y", "3": "z"}``; ``{}`` when empty.

    The strict rule of both front ends: every pair is ``DEVICE=CHANNEL``, a device channel is
    named once, and no two device channels feed one station channel."""
    if text is None or not text.strip():
        return {}
    mapping: dict[str, str] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        device, sep, channel = (piece.strip() for piece in part.partition("="))
        if not sep or not device or not channel:
            raise StationError(
                f"{part!r} is not DEVICE=CHANNEL: write pairs separated by commas, "
                "e.g. 1=x,2=y,3=z",
                field="map",
            )
        if device in mapping:
            raise StationError(f"the channel map names device channel {device} twice", field="map")
        mapping[device] = channel
    fed = [channel for channel in mapping.values()]
    doubled = sorted({channel for channel in fed if fed.count(channel) > 1})
    if doubled:
        raise StationError(
            f"the channel map feeds {', '.join(doubled)} from two device channels", field="map"
        )
    return mapping


def channel_map_text(mapping: dict[str, str]) -> str:
    """The text form of a channel map (``1=x,2=y,3=z``), the inverse of
    :func:`parse_channel_map`."""
    return ",".join(f"{device}={channel}" for device, channel in mapping.items())


# -- limits -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class TypedLimits:
    """Parsed limits: the lower and upper limit and the nominal (None when absent)."""

    lsl: float | None
    usl: float | None
    nominal: float | None


def parse_limits_text(text: str) -> TypedLimits | None:
    """``±0.001``, ``+-0.001``, ``0.001`` (a tolerance about 0), or ``LSL:USL``; None when empty.

    Raises StationError with a sentence naming the rule (``field="limits"``)."""
    text = text.strip().replace(" ", "")
    if not text:
        return None
    tolerance = re.fullmatch(rf"(?:±|\+-|\+/-)?({_NUMBER})", text)
    if tolerance and ":" not in text:
        value = float(tolerance.group(1))
        if not math.isfinite(value) or value <= 0:
            raise StationError(
                f"a tolerance must be a positive number, not {text}: {LIMIT_HELP}", field="limits"
            )
        return TypedLimits(lsl=-value, usl=value, nominal=0.0)
    both = re.fullmatch(rf"({_NUMBER})?:({_NUMBER})?", text)
    if not both or (both.group(1) is None and both.group(2) is None):
        raise StationError(f"{text!r} is not a limit: write {LIMIT_HELP}", field="limits")
    lsl = float(both.group(1)) if both.group(1) is not None else None
    usl = float(both.group(2)) if both.group(2) is not None else None
    for limit in (lsl, usl):
        if limit is not None and not math.isfinite(limit):
            raise StationError(f"{text!r}: a limit must be a finite number", field="limits")
    if lsl is not None and usl is not None and usl <= lsl:
        raise StationError(
            f"the upper limit {usl:g} is not above the lower limit {lsl:g}: swap them",
            field="limits",
        )
    nominal = 0.0 if lsl is None or usl is None else None
    return TypedLimits(lsl=lsl, usl=usl, nominal=nominal)


def parse_channel_limits(
    text: str, channels: Iterable[str] | None = None
) -> tuple[str, TypedLimits]:
    """``CH=LIMITS`` (``x=-0.001:0.001`` or ``x=±0.001``) -> the channel and its limits."""
    channel, sep, limits = (piece.strip() for piece in text.partition("="))
    if not sep or not channel:
        raise StationError(f"{text!r} is not CH=LSL:USL, e.g. x=-0.001:0.001", field="limits")
    known = tuple(channels) if channels is not None else None
    if known is not None and channel not in known:
        raise StationError(
            f"limits given for {channel}, which is not measured here (channels: "
            f"{', '.join(known)})",
            field="limits",
        )
    parsed = parse_limits_text(limits)
    if parsed is None:
        raise StationError(f"{text!r} gives no limits for {channel}", field="limits")
    return channel, parsed


def limits_text(lsl: float | None, usl: float | None, nominal: float | None = None) -> str:
    """The typed form of limits: ``±tol`` when symmetric about 0, else ``LSL:USL``."""
    if lsl is not None and usl is not None and math.isclose(-lsl, usl) and not nominal:
        return f"±{usl:g}"
    return f"{'' if lsl is None else f'{lsl:g}'}:{'' if usl is None else f'{usl:g}'}"


def zero_text(channels: Mapping[str, Any], resolution: float | None) -> str:
    """A zero event's channels in one line: ``x +0.00030 (10 readings, spread 0.00010)`` each
    (the offset subtracted from later readings; ``device`` when the gauge zeroed itself), or
    ``x +0.00030 (1 reading)`` for an old one-reading zero (the offset at
    :func:`figure_decimals`, like the spread beside it)."""
    parts = []
    for channel, spec in channels.items():
        spec = spec if isinstance(spec, Mapping) else {}
        n = spec.get("n")
        if spec.get("method") == "device":
            shown = "device zero"
        else:
            shown = format_figure(_number(spec.get("offset")), resolution)
        if isinstance(n, int) and n > 1:
            spread = format_spread(_number(spec.get("spread")), resolution)
            detail = f"{n} readings, spread {spread}"
        else:
            detail = "1 reading"
        parts.append(f"{channel} {shown} ({detail})")
    return "; ".join(parts)


def _number(value: Any) -> float | None:
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else None


def zero_taken(zeroes: Iterable[Mapping[str, Any]], resolution: float | None) -> str:
    """``Zero taken: x +0.00030 (5 readings, spread 0.00010); ...``: the zero in force per
    channel (each channel's last ``zero`` event), or '' when the session has none."""
    latest: dict[str, Any] = {}
    for event in zeroes:
        channels = event.get("channels") if isinstance(event, Mapping) else None
        for channel, spec in dict(channels or {}).items():
            latest[str(channel)] = spec
    return f"Zero taken: {zero_text(latest, resolution)}" if latest else ""
