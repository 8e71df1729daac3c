"""The procedure's steps with their marks: ✓ done, ▶ current, · pending."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rich.table import Table
from rich.text import Text
from textual.widgets import Static

from station.tui.text import shown_line

MARKS = {"done": ("✓", "green"), "current": ("▶", "bold"), "pending": ("·", "dim")}


def steps_text(steps: Sequence[Any]) -> Text:
    """One line per step (a runner ``StepView``): the mark, the number and the title."""
    text = Text(no_wrap=True, overflow="ellipsis")
    for index, view in enumerate(steps):
        mark, style = MARKS.get(getattr(view, "mark", "pending"), ("·", "dim"))
        title = getattr(view.step, "title", view.id)
        placement = getattr(view, "placement", None)
        if placement:
            title = f"{title} ({placement})"
        if index:
            text.append("\n")
        text.append(f"{mark} {index + 1:>2} {shown_line(title)}", style=style)
    return text


def steps_table(steps: Sequence[Any]) -> Table:
    """The steps as :func:`steps_text` says them, each title wrapped under itself beside its
    mark and number (a long title was cut at the list's edge, issue 26)."""
    table = Table.grid(padding=(0, 1))
    table.add_column(no_wrap=True)
    table.add_column(ratio=1, overflow="fold")
    for line in steps_text(steps).split("\n"):
        style = line.spans[0].style if line.spans else ""
        head, title = line[:4], line[5:]
        table.add_row(Text(head.plain, style=style), Text(title.plain, style=style))
    return table


class StepList(Static):
    """The step list on the checklist's left; :meth:`show` replaces it."""

    def show(self, steps: Sequence[Any]) -> None:
        """Redraw from a runner state's ``steps`` (UI thread only)."""
        self.update(steps_table(steps))
