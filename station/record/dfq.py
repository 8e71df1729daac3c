"""A session as a Q-DAS AQDEF transfer file (DFQ), the format SPC software reads.

A DFQ file is text, one ``Kxxxx[/i] value`` field per line (``i``: the characteristic). The
station writes one part (the robot) and one characteristic per channel, then every reading of
every cycle, rejected ones included and marked:

* ``K0100``: the number of characteristics;
* ``K1001/1`` part number: the robot; ``K1002/1`` part title: the procedure and the session;
* per channel ``i``: ``K2001/i`` characteristic number (the channel), ``K2002/i`` its
  description, ``K2022/i`` the decimals a figure is shown with (one beyond the gauge step, as
  every figure of the station), ``K2101/i`` nominal, ``K2110/i`` / ``K2111/i`` lower / upper
  limit, ``K2142/i`` unit;
* per reading: ``K0001/i`` the value the session file holds (every digit, plain decimals:
  AQDEF has no ``1e-05``), ``K0002/i`` its attribute (``0``; ``255``, a deactivated value that
  the evaluation leaves out, for a cycle the operator rejected), ``K0004/i`` the reading's date
  and time (``dd.mm.yyyy/hh:mm:ss``, UTC as every time in the session file), ``K0012/i`` the
  gauge id the session names for the channel (left out when it names none).

Text from outside (robot, procedure title, gauge ids, channel names) is written on one line
with control characters made visible (:func:`station.plain.plain`): a line break in a robot's
name would otherwise start a field of its own.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from datetime import datetime
from decimal import Decimal
from typing import Any, TextIO

from station.errors import StationError
from station.plain import plain
from station.session.gauge_register import session_gauges
from station.session.model import Session
from station.text import figure_decimals

DEACTIVATED = 255
"""K0002 of a value the evaluation leaves out: the station's rejected cycle."""
VALID = 0
"""K0002 of a value that counts."""


def dfq_number(value: float) -> str:
    """``value`` with every digit the session file holds, in plain decimals (``0.00002``, never
    ``2e-05``, which an AQDEF reader does not take for a number)."""
    if value == 0:
        return "0"  # never "-0.0"
    return format(Decimal(repr(float(value))), "f")


def dfq_time(moment: str) -> str:
    """An event time (ISO-8601, ``Z``) as AQDEF writes it, ``dd.mm.yyyy/hh:mm:ss``."""
    try:
        parsed = datetime.fromisoformat(str(moment).replace("Z", "+00:00"))
    except ValueError:
        raise StationError(f"a reading's time {moment!r} is not a date and time.") from None
    return parsed.strftime("%d.%m.%Y/%H:%M:%S")


def _text(value: object) -> str:
    return plain(value).strip() or "-"


def _limits(header: Mapping[str, Any], channel: str) -> Mapping[str, Any]:
    limits = (header.get("limits") or {}).get(channel)
    return limits if isinstance(limits, Mapping) else {}


def _finite(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


def write_dfq(session: Session, out: TextIO) -> int:
    """Write ``session`` to ``out`` as a DFQ file (see the module); return how many values it
    holds. StationError when the session has no cycle of readings (a linearity run streams
    points, which ``station export --csv`` writes)."""
    cycles = session.cycles.values()
    channels = [c for c in session.channels if any(c in cycle.readings for cycle in cycles)]
    if not channels:
        raise StationError(
            f"{session.path.name} has no cycles of readings to export as DFQ (a linearity "
            "run's streamed points: use --csv)."
        )
    header = session.header
    recorded = header.get("resolution")
    resolution = float(recorded) if isinstance(recorded, int | float) and recorded > 0 else None
    version = (header.get("procedure") or {}).get("version") or "-"
    gauges = session_gauges(header)
    lines = [
        f"K0100 {len(channels)}",
        f"K1001/1 {_text(session.robot)}",
        f"K1002/1 {_text(session.procedure_id)} version {_text(version)}, session "
        f"{_text(session.session_id)}",
    ]
    for index, channel in enumerate(channels, start=1):
        limits = _limits(header, channel)
        lines += [
            f"K2001/{index} {_text(channel)}",
            f"K2002/{index} {_text(channel)} ({_text(session.procedure_id)})",
            f"K2022/{index} {figure_decimals(resolution)}",
        ]
        for field, key in (("K2101", "nominal"), ("K2110", "lsl"), ("K2111", "usl")):
            value = _finite(limits.get(key))
            if value is not None:
                lines.append(f"{field}/{index} {dfq_number(value)}")
        lines.append(f"K2142/{index} {_text(session.unit)}")
    values = 0
    for number in sorted(session.cycles):
        cycle = session.cycles[number]
        attribute = DEACTIVATED if number in session.rejected else VALID
        when = dfq_time(cycle.t)
        for index, channel in enumerate(channels, start=1):
            reading = cycle.readings.get(channel)
            if reading is None:
                continue
            lines += [
                f"K0001/{index} {dfq_number(reading.value)}",
                f"K0002/{index} {attribute}",
                f"K0004/{index} {when}",
            ]
            if channel in gauges:
                lines.append(f"K0012/{index} {_text(gauges[channel])}")
            values += 1
    out.write("\n".join(lines) + "\n")
    return values
