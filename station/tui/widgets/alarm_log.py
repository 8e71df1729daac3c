"""The alarm log: each alarm with its channel, cycle and rule (in words), newest last.

On the live dashboard it shows the alarms the session recorded (phase II: they never go away)
with their acknowledgement; the full texts are on the alarm list (key ``a``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rich.text import Text
from textual.widgets import Static

from station.tui.text import shown_line
from station.tui.theme import ALARM_STYLES


def alarm_lines(
    analyses: Mapping[str, Any], cycle_numbers: Sequence[int] | None = None, label: str = "cycle"
) -> list[str]:
    """One sentence per alarm: ``cycle 17 x [report-1] <the rule's sentence>``.

    An alarm's points are 1-based positions among the accepted cycles; ``cycle_numbers`` maps
    them to cycle numbers, so the log names the cycle the operator saw even after a reject.
    ``label`` names the points (``stroke`` for the straightness chart of a linearity run).
    """
    lines: list[tuple[int, str]] = []
    for channel, analysis in analyses.items():
        for alarm in getattr(analysis, "alarms", ()) or ():
            points = [int(p) for p in getattr(alarm, "points", ())]
            last = max(points) if points else 0
            if cycle_numbers and 1 <= last <= len(cycle_numbers):
                cycle = cycle_numbers[last - 1]
            else:
                cycle = last
            rule = getattr(alarm, "rule", "?")
            text = getattr(alarm, "text", "")
            lines.append((cycle, f"{label} {cycle} {channel} [{rule}] {text}"))
    lines.sort(key=lambda item: item[0])
    return [line for _, line in lines]


def recorded_alarm_lines(alarms: Sequence[Any]) -> list[str]:
    """One line per recorded alarm (:class:`~station.session.alarms.RecordedAlarm`), oldest
    first: ``#41 y cycle 27, report rule 1 (a point beyond the control limits): <sentence>
    [not acknowledged]``."""
    lines = []
    for alarm in alarms:
        cycles = list(alarm.cycles)
        where = (
            f"cycle {cycles[-1]}"
            if len(cycles) == 1
            else f"cycles {cycles[0]}-{cycles[-1]}"
            if cycles
            else "cycle ?"
        )
        status = f"acknowledged: {alarm.acks[-1].cause}" if alarm.acks else "not acknowledged"
        lines.append(
            f"#{alarm.seq} {alarm.channel} {where}, {alarm.rule_name} [{status}]: {alarm.text}"
        )
    return lines


class AlarmLog(Static):
    """The latest alarms; says so plainly when there is none."""

    DEFAULT_CSS = """
    AlarmLog { height: auto; max-height: 4; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._lines: list[str] | None = None
        self.max_shown = 3

    def show(
        self,
        lines: list[str],
        *,
        open_count: int | None = None,
        more: str = "",
        empty: str = "alarms: none",
    ) -> None:
        """Show the newest alarms (UI thread only); ``open_count``: how many are not
        acknowledged yet; ``more``: where the full list is (``a: the full list``); ``empty``:
        what to say while there is none."""
        extra = (open_count, more, empty)
        if lines == self._lines and extra == getattr(self, "_extra", None):
            return
        self._lines = list(lines)
        self._extra = extra
        if not lines:
            self.update(Text(empty, style=ALARM_STYLES["none"]))
            return
        shown = lines[-self.max_shown :]
        counts = f"{len(lines)}"
        if open_count is not None:
            counts += f", {open_count} not acknowledged"
        if len(lines) > self.max_shown:
            counts += f", newest {len(shown)}"
        head = f"alarms ({counts})" + (f" · {more}:" if more else ":")
        text = Text(head, style=ALARM_STYLES["head"], no_wrap=True, overflow="ellipsis")
        for line in shown:
            text.append("\n⚠ " + shown_line(line), style=ALARM_STYLES["line"])
        self.update(text)
