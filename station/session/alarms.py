"""The alarms a session recorded, their acknowledgements, and the replay of its live alarms.

* An ``alarm`` event is what the live analysis raised while capturing (``live`` true, judged
  against the frozen phase II limits; files from before the phase II limits have no ``live``
  field and were raised live too, against moving limits).
* An ``ack`` event acknowledges one: ``alarm`` (the alarm event's ``seq``), ``cause`` (one of the
  procedure's ``causes``), ``text`` (required for "other"), ``action`` (the corrective action,
  optional), ``by`` (optional). :func:`ack_fields` checks them before the engine writes them.
* :func:`live_events` turns a session's readings and rejections (in journal order) into the
  input of :func:`station.analysis.monitor.replay_live_alarms`: a replay gives the recorded live
  alarms (same channel, rule, points, cycles and text, in the same order).
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from station.analysis.monitor import ReadingSet, Rejection
from station.analysis.rules import rule_name
from station.errors import StationError
from station.plain import plain
from station.procedures import DEFAULT_CAUSES, OTHER_CAUSE

if TYPE_CHECKING:
    from station.session.model import Session


@dataclass(frozen=True)
class Acknowledgement:
    """One ``ack`` event: the alarm's seq, the cause, what it was, the corrective action."""

    seq: int
    alarm: int
    cause: str
    text: str = ""
    action: str = ""
    by: str = ""
    t: str = ""

    def describe(self) -> str:
        """``temperature (the cell door was open); action: waited 30 min`` (plain text)."""
        words = self.cause + (f" ({self.text})" if self.text else "")
        if self.action:
            words += f"; corrective action: {self.action}"
        if self.by:
            words += f"; by {self.by}"
        return words


@dataclass(frozen=True)
class RecordedAlarm:
    """One ``alarm`` event and the acknowledgements that name it (the last one counts)."""

    seq: int
    channel: str
    rule: str
    rule_name: str
    text: str
    cycles: tuple[int, ...]
    live: bool
    t: str
    acks: tuple[Acknowledgement, ...] = ()

    @property
    def acknowledged(self) -> bool:
        """True once an ``ack`` names the alarm."""
        return bool(self.acks)


@dataclass(frozen=True)
class AckRequest:
    """What an operator asked for in the alarm list: acknowledge alarm event ``alarm`` (its
    seq) with ``cause``, ``text`` and the corrective ``action``. The engine turns it into an
    ``ack`` event with :meth:`fields`."""

    alarm: int
    cause: str
    text: str = ""
    action: str = ""

    def fields(self, causes: Sequence[str] = DEFAULT_CAUSES, by: str = "") -> dict[str, Any]:
        """The checked fields of the ``ack`` event (see :func:`ack_fields`)."""
        return ack_fields(
            self.alarm, self.cause, causes=causes, text=self.text, action=self.action, by=by
        )


def ack_fields(
    alarm_seq: int,
    cause: str,
    *,
    causes: Sequence[str] = DEFAULT_CAUSES,
    text: str = "",
    action: str = "",
    by: str = "",
) -> dict[str, Any]:
    """The fields of an ``ack`` event, checked: the cause is one of ``causes`` (the procedure's),
    "other" needs a ``text``. StationError with a sentence otherwise."""
    cause = cause.strip()
    if cause not in causes:
        raise StationError(
            f"{cause!r} is not one of the procedure's causes ({', '.join(causes)}): pick one, "
            f"or '{OTHER_CAUSE}' and say what it was."
        )
    text, action, by = text.strip(), action.strip(), by.strip()
    if cause == OTHER_CAUSE and not text:
        raise StationError("say what the cause was: 'other' needs a short text.")
    fields: dict[str, Any] = {"alarm": int(alarm_seq), "cause": cause}
    if text:
        fields["text"] = text
    if action:
        fields["action"] = action
    if by:
        fields["by"] = by
    return fields


def acknowledgement(event: Any) -> Acknowledgement:
    """One ``ack`` event (a journal line's mapping) as an :class:`Acknowledgement`."""
    return Acknowledgement(
        seq=int(event["seq"]),
        alarm=int(event["alarm"]),
        cause=str(event["cause"]),
        text=str(event.get("text") or ""),
        action=str(event.get("action") or ""),
        by=str(event.get("by") or ""),
        t=str(event.get("t") or ""),
    )


def recorded_alarm(event: Any, acks: Sequence[Acknowledgement] = ()) -> RecordedAlarm:
    """One ``alarm`` event (a journal line's mapping) with the acknowledgements naming it."""
    rule = str(event.get("rule") or "")
    return RecordedAlarm(
        seq=int(event["seq"]),
        channel=str(event.get("channel") or ""),
        rule=rule,
        rule_name=str(event.get("rule_name") or rule_name(rule)),
        text=str(event.get("text") or ""),
        cycles=tuple(int(c) for c in event.get("cycles") or () if isinstance(c, int)),
        live=bool(event.get("live", True)),
        t=str(event.get("t") or ""),
        acks=tuple(acks),
    )


def recorded_alarms(session: Session) -> tuple[RecordedAlarm, ...]:
    """Every alarm event of the session in order, with its acknowledgements."""
    acks: dict[int, list[Acknowledgement]] = {}
    for event in session.acks:
        ack = acknowledgement(event)
        acks.setdefault(ack.alarm, []).append(ack)
    return tuple(recorded_alarm(event, acks.get(int(event["seq"]), ())) for event in session.alarms)


def live_events(session: Session) -> list[ReadingSet | Rejection]:
    """The session's readings and rejections in journal order, as the live analysis saw them."""
    events: list[ReadingSet | Rejection] = []
    for event in session.events:
        if event["type"] == "reading":
            cycle = session.cycles[event["cycle"]]
            values = {channel: r.value for channel, r in cycle.readings.items()}
            times = {channel: r.t_wall for channel, r in cycle.readings.items()}
            known = None if None in times.values() else times
            events.append(ReadingSet(cycle.number, values, known))  # type: ignore[arg-type]
        elif event["type"] == "reject":
            events.append(Rejection(int(event["cycle"])))
    return events


def format_recorded_alarms(alarms: Sequence[RecordedAlarm], width: int = 80) -> list[str]:
    """The report block of the alarms recorded while capturing, each with its acknowledgement
    (plain text: the operator's words are shown as they were typed, one line each)."""
    lines = ["ALARMS RECORDED DURING THE SESSION (live), WITH THEIR CAUSES"]
    if not alarms:
        return [*lines, "  none"]

    def wrap(text: str, indent: str) -> list[str]:
        return textwrap.wrap(
            text, width=width, initial_indent=indent, subsequent_indent=indent + "  "
        ) or [indent]

    for alarm in alarms:
        where = "live" if alarm.live else "retrospective"
        lines += wrap(
            f"#{alarm.seq} {plain(alarm.channel)}, {alarm.rule_name} [{where}]: "
            f"{plain(alarm.text)}",
            "  ",
        )
        if alarm.acks:
            lines += wrap(f"acknowledged: {plain(alarm.acks[-1].describe())}", "    ")
        else:
            lines.append("    not acknowledged")
    return lines


def recorded_alarms_json(alarms: Sequence[RecordedAlarm]) -> list[dict[str, Any]]:
    """The ``recorded_alarms`` of a session's JSON document."""
    return [
        {
            "seq": alarm.seq,
            "channel": alarm.channel,
            "rule": alarm.rule,
            "rule_name": alarm.rule_name,
            "cycles": list(alarm.cycles),
            "text": alarm.text,
            "live": alarm.live,
            "acks": [
                {
                    "seq": ack.seq,
                    "cause": ack.cause,
                    "text": ack.text,
                    "action": ack.action,
                    "by": ack.by,
                    "t": ack.t,
                }
                for ack in alarm.acks
            ],
        }
        for alarm in alarms
    ]
