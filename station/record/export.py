"""A session as the CSV table its analysis kind reads back (``station export --layout wide``).

The tidy layout (every cycle and channel, rejected ones marked) is
:func:`station.session.export.export_csv`. The wide layout is the table ``station analyze
--procedure KIND`` reads, with exactly the readings the session's own analysis takes:

* linearity: ``stroke,s,h,v``, the points of the whole strokes as the analysis splits and trims
  them (:func:`station.verdicts.session_stroke_profiles`), one row per point;
* relative accuracy: ``cycle,placement,x,y,z`` of the accepted readings at a fixture placement,
  and ``px,py,pz`` (the teach pendant's coordinates) when every placement has them;
* otherwise ``cycle`` and one column per channel of the accepted cycles.

``#`` lines name the session, its last hash and each rejected cycle with its reason (``station
analyze`` lists those cycles as excluded).
"""

from __future__ import annotations

import csv
from typing import TextIO

from station.session.export import export_csv, one_line
from station.session.model import Session, event_seconds
from station.verdicts import session_accuracy_inputs, session_stroke_profiles

LINEARITY_COLUMNS: tuple[str, ...] = ("stroke", "s", "h", "v")
ACCURACY_COLUMNS: tuple[str, ...] = ("cycle", "placement", "x", "y", "z")
PENDANT_COLUMNS: tuple[str, ...] = ("px", "py", "pz")
LAYOUTS = ("tidy", "wide")
AXES = ("x", "y", "z")


def _number(value: float) -> str:
    # repr keeps every digit the session holds (no rounding on the way out).
    return repr(float(value))


def _comments(session: Session, out: TextIO) -> None:
    """``#`` lines naming the session and its rejected cycles (readers skip them)."""
    name, procedure, unit = (
        one_line(v) for v in (session.path.name, session.procedure_id, session.unit)
    )
    out.write(
        f"# station export of {name}: procedure {procedure}, unit {unit}, "
        f"last line hash {session.last_hash}\n"
    )
    for number, reason in sorted(session.rejected.items()):
        out.write(f"# rejected cycle {number} (left out): {one_line(reason)}\n")


def export_linearity_csv(session: Session, out: TextIO) -> int:
    """Write the whole strokes of a linearity session as ``stroke,s,h,v`` (one row per point,
    strokes numbered as the analysis numbers them); return the data rows."""
    _comments(session, out)
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(LINEARITY_COLUMNS)
    rows = 0
    for profile in session_stroke_profiles(session):
        h, v = profile.channels["h"], profile.channels["v"]
        for s, dh, dv in zip(profile.s, h, v, strict=True):
            writer.writerow((profile.number, _number(s), _number(dh), _number(dv)))
            rows += 1
    return rows


def export_accuracy_csv(session: Session, out: TextIO) -> int:
    """Write a relative-accuracy session's accepted readings at fixture placements as
    ``cycle,placement,x,y,z`` and, when every placement has them, the teach pendant's
    ``px,py,pz``; return the data rows."""
    _, _, pendant = session_accuracy_inputs(session)
    numbers = [
        n
        for n in session.accepted_cycles
        if session.cycles[n].placement is not None
        and all(axis in session.cycles[n].readings for axis in AXES)
    ]
    with_pendant = bool(numbers) and all(session.cycles[n].placement in pendant for n in numbers)
    _comments(session, out)
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(ACCURACY_COLUMNS + (PENDANT_COLUMNS if with_pendant else ()))
    for number in numbers:
        cycle = session.cycles[number]
        row = [number, cycle.placement, *(_number(cycle.readings[a].value) for a in AXES)]
        if with_pendant:
            row += [_number(v) for v in pendant[cycle.placement]]  # type: ignore[index]
        writer.writerow(row)
    return len(numbers)


def export_table(session: Session, out: TextIO, layout: str = "tidy", kind: str = "") -> int:
    """Write ``session`` as CSV in ``layout`` (``tidy`` or ``wide``, see the module) for its
    analysis kind ``kind``; return the data rows."""
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
    # ``t``: the cycle's time in seconds (the drift's trend reads it back).
    writer.writerow(("cycle", "t", *session.channels))
    rows = 0
    for number in session.accepted_cycles:
        cycle = session.cycles[number]
        readings = cycle.readings
        if all(channel in readings for channel in session.channels):
            values = (_number(readings[c].value) for c in session.channels)
            writer.writerow((number, repr(event_seconds(cycle.t)), *values))
            rows += 1
    return rows
