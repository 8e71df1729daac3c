"""Export a session as tidy CSV: one row per cycle and channel, rejected cycles marked."""

from __future__ import annotations

import csv
from typing import TextIO

from station.plain import PlainStream
from station.session.model import Session

CSV_COLUMNS: tuple[str, ...] = (
    "cycle",
    "channel",
    "value",
    "unit",
    "status",
    "time",
    "raw_value",
    "zero",
    "placement",
)
"""The first six are the tidy core; raw value, zero offset and placement follow."""


def _number(value: float | None) -> str:
    # repr keeps every digit the session holds (no rounding on the way out).
    return "" if value is None else repr(float(value))


def export_csv(session: Session, out: TextIO) -> int:
    """Write the session's cycles to ``out`` as CSV (header row first); return the data rows.

    ``status`` is ``ok`` or ``rejected: <reason>`` (readings are never deleted, so rejected
    cycles stay in the export, marked); ``time`` is the event's ISO-8601 UTC time. A channel
    name or a unit is text from outside: its control characters are written visible
    (``\\x1b``), as a terminal shows them, so a spreadsheet or ``cat`` of the file is safe.
    """
    writer = csv.writer(PlainStream(out), lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    rows = 0
    for number in sorted(session.cycles):
        cycle = session.cycles[number]
        reason = session.rejected.get(number)
        # One line per row: a reason typed with a line break must not split the row for a
        # reader that takes the file line by line (``station analyze`` does).
        status = "ok" if reason is None else f"rejected: {one_line(reason)}"
        for channel in (*session.channels, *sorted(set(cycle.readings) - set(session.channels))):
            reading = cycle.readings.get(channel)
            if reading is None:
                continue
            writer.writerow(
                (
                    number,
                    channel,
                    _number(reading.value),
                    reading.unit,
                    status,
                    cycle.t,
                    _number(reading.raw_value),
                    _number(reading.zero),
                    "" if cycle.placement is None else cycle.placement,
                )
            )
            rows += 1
    return rows


def one_line(text: object) -> str:
    """``text`` on one line: every line break or other non-printable character becomes a
    space (a CSV row or a ``#`` comment must not be split by a reason typed with Enter)."""
    return " ".join("".join(c if c.isprintable() else " " for c in str(text)).split())
