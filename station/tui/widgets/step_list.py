"""The procedure's steps with their marks: ✓ done, ▶ current, · pending."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

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


class StepList(Static):
    """The step list on the checklist's left; :meth:`show` replaces it."""

    def show(self, steps: Sequence[Any]) -> None:
        """Redraw from a runner state's ``steps`` (UI thread only)."""
        self.update(steps_text(steps))
