"""A robot's history and a before/after comparison, from the review list: the same lines
``station history`` and ``station compare`` print, read-only, computed off the UI thread."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import VerticalScroll
from textual.screen import Screen
from textual.widgets import Static

from station.errors import StationError
from station.tui.remedies import explained
from station.tui.text import shown
from station.tui.widgets.key_footer import KeyFooter

if TYPE_CHECKING:
    from station.tui.app import StationApp


class RecordScreen(Screen[None]):
    """A titled column of text lines, made by ``make`` on a worker thread."""

    BINDINGS = [Binding("escape", "back", "Back"), Binding("q", "back", "Back", show=False)]

    app: StationApp

    def __init__(self, title: str, make: Callable[[], Sequence[str]]) -> None:
        super().__init__()
        self._title = title
        self._make = make

    def compose(self) -> ComposeResult:
        """The title, the lines, the keys."""
        yield Static(shown(self._title, style="bold", limit=200), id="record-title")
        with VerticalScroll(id="record-body"):
            yield Static(Text("Working it out ...", style="yellow"), id="record-text")
        yield KeyFooter()

    def on_mount(self) -> None:
        """Compute the lines off the UI thread (it reads and analyses session files)."""
        self._compute()

    @work(thread=True, group="record", exit_on_error=False)
    def _compute(self) -> None:
        try:
            text = shown("\n".join(self._make()), no_wrap=True)
        except StationError as error:
            text = shown(explained(error), style="bold red")
        self.app.call_from_thread(self.query_one("#record-text", Static).update, text)

    def action_back(self) -> None:
        """Back to the review list."""
        self.app.pop_screen()


def history_screen(folder: Path, robot: str) -> RecordScreen:
    """Every session of ``robot`` in ``folder`` in time order, its charts and wear trend."""
    from station.record.history import format_history, robot_history  # deferred: numpy

    return RecordScreen(
        f"History of robot {robot}", lambda: format_history(robot_history(folder, robot))
    )


def compare_screen(before: Path, after: Path) -> RecordScreen:
    """Session ``after`` against ``before``: the shift and spread per axis, in sentences."""
    from station.record.compare import compare_sessions  # deferred: it loads numpy

    def lines() -> list[str]:
        comparison = compare_sessions(before, after)
        return [
            f"A (before): {comparison.a}",
            f"B (after):  {comparison.b}",
            f"Procedure {comparison.procedure}, unit {comparison.unit}",
            "",
            *comparison.sentences,
        ]

    return RecordScreen(f"Compare {before.name} → {after.name}", lines)
