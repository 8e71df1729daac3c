"""The alarm log: each control-chart alarm with its channel, cycle and rule, newest last."""

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


class AlarmLog(Static):
    """The latest alarms; says so plainly when there is none."""

    DEFAULT_CSS = """
    AlarmLog { height: auto; max-height: 4; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._lines: list[str] | None = None
        self.max_shown = 3

    def show(self, lines: list[str]) -> None:
        """Show the newest alarms (UI thread only)."""
        if lines == self._lines:
            return
        self._lines = list(lines)
        if not lines:
            self.update(Text("alarms: none", style=ALARM_STYLES["none"]))
            return
        shown = lines[-self.max_shown :]
        head = (
            f"alarms ({len(lines)}):"
            if len(lines) <= self.max_shown
            else (f"alarms ({len(lines)}, newest {len(shown)}):")
        )
        text = Text(head, style=ALARM_STYLES["head"], no_wrap=True, overflow="ellipsis")
        for line in shown:
            text.append("\n⚠ " + shown_line(line), style=ALARM_STYLES["line"])
        self.update(text)
