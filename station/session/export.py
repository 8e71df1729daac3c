"""Export a session as tidy CSV: one row per cycle and channel, rejected cycles marked."""

from __future__ import annotations

import csv
from typing import TextIO

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
    cycles stay in the export, marked); ``time`` is the event's ISO-8601 UTC time.
    """
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    rows = 0
    for number in sorted(session.cycles):
        cycle = session.cycles[number]
        reason = session.rejected.get(number)
        # One line per row: a reason typed with a line break must not split the row for a
        # reader that takes the file line by line (``station analyze`` does).
        status = "ok" if reason is None else f"rejected: {_one_line(reason)}"
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


LINEARITY_COLUMNS: tuple[str, ...] = ("stroke", "s", "h", "v")
"""A linearity session's streamed points, one row each: what ``analyze --procedure linearity``
reads."""
ACCURACY_COLUMNS: tuple[str, ...] = ("cycle", "placement", "x", "y", "z")
PENDANT_COLUMNS: tuple[str, ...] = ("px", "py", "pz")
LAYOUTS = ("tidy", "wide")


def _one_line(text: object) -> str:
    # A comment line must stay one line: any line break or control character becomes a space.
    return " ".join("".join(c if c.isprintable() else " " for c in str(text)).split())


def _comments(session: Session, out: TextIO) -> None:
    """``#`` lines naming the session and its rejected cycles (readers skip them)."""
    name, procedure, unit = (
        _one_line(v) for v in (session.path.name, session.procedure_id, session.unit)
    )
    out.write(
        f"# station export of {name}: procedure {procedure}, "
        f"unit {unit}, last line hash {session.last_hash}\n"
    )
    for number, reason in sorted(session.rejected.items()):
        out.write(f"# rejected cycle {number} (left out): {_one_line(reason)}\n")


def whole_stroke_batches(session: Session) -> list:
    """The ``samples`` events of the whole strokes, as the session's analysis takes them:
    batches with s, h and v; where the runner marked stroke ends (``end``), only the strokes
    that ended (a lead-in or a stroke cut short is left out)."""
    batches = [b for b in session.samples if {"s", "h", "v"} <= set(b.channels)]
    ended = {event["seq"] for event in session.events if event.get("end")}
    if ended:
        whole = {b.stroke for b in batches if b.seq in ended}
        batches = [b for b in batches if b.stroke in whole]
    return batches


def export_linearity_csv(session: Session, out: TextIO) -> int:
    """Write a linearity session's whole strokes as ``stroke,s,h,v`` (one row per streamed
    point, in the order recorded); return the data rows. Points streamed without a stroke
    number are one recorded stroke, numbered 1 (the analysis splits it by the scale)."""
    _comments(session, out)
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(LINEARITY_COLUMNS)
    rows = 0
    for batch in whole_stroke_batches(session):
        columns = batch.as_arrays()
        stroke = 1 if batch.stroke is None else batch.stroke
        for s, h, v in zip(columns["s"], columns["h"], columns["v"], strict=True):
            writer.writerow((stroke, _number(s), _number(h), _number(v)))
            rows += 1
    return rows


def export_accuracy_csv(session: Session, out: TextIO) -> int:
    """Write a relative-accuracy session's accepted readings at fixture placements as
    ``cycle,placement,x,y,z`` and, when every placement has them, the teach pendant's
    ``px,py,pz``; return the data rows. Rejected cycles are named in ``#`` lines."""
    pendant: dict[int, tuple[float, ...]] = {}
    for event in session.input_events:
        values, placement = event.get("values") or {}, event.get("placement")
        if isinstance(placement, int) and all(
            isinstance(values.get(axis), int | float) for axis in ("x", "y", "z")
        ):
            pendant[placement] = tuple(float(values[axis]) for axis in ("x", "y", "z"))
    numbers = [
        n
        for n in session.accepted_cycles
        if session.cycles[n].placement is not None
        and all(axis in session.cycles[n].readings for axis in ("x", "y", "z"))
    ]
    with_pendant = bool(numbers) and all(session.cycles[n].placement in pendant for n in numbers)
    _comments(session, out)
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(ACCURACY_COLUMNS + (PENDANT_COLUMNS if with_pendant else ()))
    for number in numbers:
        cycle = session.cycles[number]
        row = [number, cycle.placement]
        row += [_number(cycle.readings[axis].value) for axis in ("x", "y", "z")]
        if with_pendant:
            row += [_number(v) for v in pendant[cycle.placement]]  # type: ignore[index]
        writer.writerow(row)
    return len(numbers)


def export_table(session: Session, out: TextIO, layout: str = "tidy", kind: str = "") -> int:
    """Write the session as CSV in ``layout``: ``tidy`` (:func:`export_csv`, every cycle and
    channel) or ``wide``, the table its analysis kind reads back (``stroke,s,h,v`` for
    linearity, ``cycle,placement,x,y,z,px,py,pz`` for relative accuracy, ``cycle,x,y,z`` of the
    accepted cycles otherwise). ``kind`` is the session's analysis kind."""
    if layout == "tidy":
        return export_csv(session, out)
    if layout != "wide":
        raise ValueError(f"unknown CSV layout {layout!r}")
    if kind == "linearity":
        return export_linearity_csv(session, out)
    if kind == "relative_accuracy":
        return export_accuracy_csv(session, out)
    _comments(session, out)
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(("cycle", *session.channels))
    rows = 0
    for number in session.accepted_cycles:
        readings = session.cycles[number].readings
        if all(channel in readings for channel in session.channels):
            writer.writerow((number, *(_number(readings[c].value) for c in session.channels)))
            rows += 1
    return rows
