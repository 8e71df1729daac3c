"""The alarms a session writes and their acknowledgements.

Alarms of the live analysis are written as ``alarm`` events when they first appear (an alarm is
new unless it flags a cycle an alarm of the same rule and channel already flagged: a run growing
by a point is one alarm); :meth:`AlarmJournal.acknowledge` writes an ``ack`` event with a cause
from the procedure's list. :class:`AlarmJournal` is a part of
:class:`~station.run.engine.Runner` (its attributes are set up there).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from station.analysis.rules import rule_name
from station.errors import StationError
from station.session.alarms import (
    RecordedAlarm,
    ack_fields,
    acknowledgement,
    recorded_alarm,
)

if TYPE_CHECKING:
    pass


class AlarmJournal:
    """The engine's alarm and acknowledgement events (a part of the Runner)."""

    def acknowledge(
        self,
        alarm_ref: int,
        cause: str,
        text: str | None = None,
        action: str | None = None,
        by: str = "operator",
    ) -> RecordedAlarm:
        """Acknowledge the alarm event whose ``seq`` is ``alarm_ref`` with ``cause`` (one of
        the procedure's causes; "other" needs ``text``) and the corrective ``action``: an
        ``ack`` event, fsynced. Returns the alarm with its acknowledgements. StationError for
        an unknown alarm or cause, or a closed file."""
        with self.lock:
            self.ensure_open()
            index = next(
                (i for i, alarm in enumerate(self._alarm_list) if alarm.seq == alarm_ref), None
            )
            if index is None:
                known = ", ".join(f"#{alarm.seq}" for alarm in self._alarm_list) or "none yet"
                raise StationError(
                    f"there is no alarm #{alarm_ref} in this session (alarms: {known})"
                )
            fields = ack_fields(
                alarm_ref,
                cause,
                causes=self.setup.procedure.causes,
                text=text or "",
                action=action or "",
                by=by,
            )
            event = self.append("ack", **fields)
            alarm = self._alarm_list[index]
            acknowledged = replace(alarm, acks=(*alarm.acks, acknowledgement(event)))
            alarms = list(self._alarm_list)
            alarms[index] = acknowledged
            self._alarm_list = tuple(alarms)
            self.say(
                "info", f"Alarm #{alarm_ref} acknowledged: {acknowledged.acks[-1].describe()}."
            )
            return acknowledged

    def _record_alarms(self, updates: Mapping[str, Any], raised_at: int) -> None:
        """Write ``alarm`` events for the alarms cycle ``raised_at`` raised (the windows it
        completes, O(1))."""
        for channel, update in updates.items():
            for alarm in update.alarms:
                self._record_alarm(channel, alarm, raised_at)

    def _record_alarm(self, channel: str, alarm: Any, raised_at: int) -> None:
        # The live analysis is fed each set with its cycle number: its alarms name cycles.
        cycles = list(alarm.cycles)
        if not cycles:
            return
        flagged = self._alarm_flagged.setdefault((channel, alarm.rule), set())
        known = not flagged.isdisjoint(cycles)
        flagged.update(cycles)
        if known:
            return
        # The fields of LiveAlarm.event_fields: what a replay of the file gives back.
        event = self.append(
            "alarm",
            channel=channel,
            rule=alarm.rule,
            rule_name=rule_name(alarm.rule),
            points=list(alarm.points),
            cycles=cycles,
            text=alarm.text,
            raised_at=raised_at,
            live=True,
        )
        self._alarm_list = (*self._alarm_list, recorded_alarm(event))
        self.say("warning", f"{channel}: {rule_name(alarm.rule)}: {alarm.text}")
