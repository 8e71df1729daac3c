"""Review: the saved sessions by robot and date; Enter opens one read-only (summary, charts)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.screen import Screen
from textual.widgets import DataTable, Footer, Static

from station.errors import StationError
from station.tui.remedies import explained
from station.tui.text import shown, shown_line

if TYPE_CHECKING:
    from station.tui.app import StationApp


class ReviewScreen(Screen[None]):
    """A table of the sessions folder; nothing here changes a file."""

    BINDINGS = [
        Binding("o", "open", "Open", key_display="enter/o"),
        Binding("h", "history", "Robot history"),
        Binding("m", "mark", "Mark for compare"),
        Binding("c", "compare", "Compare with mark"),
        Binding("escape", "back", "Back"),
        Binding("f1", "help", "Help"),
        Binding("q", "back", "Back", show=False),
    ]

    app: StationApp

    def __init__(self) -> None:
        super().__init__()
        self._sessions: list[Any] = []
        self._marked: Any = None

    def compose(self) -> ComposeResult:
        """Title, the table, the folder."""
        yield Static(Text("Saved sessions, by robot and date", style="bold"), id="review-title")
        yield DataTable(id="review-table", cursor_type="row", zebra_stripes=True)
        yield Static(id="review-folder")
        yield Footer()

    def on_mount(self) -> None:
        """List the folder."""
        from station.session.store import list_sessions

        folder = self.app.config.sessions_dir
        self._sessions = list(list_sessions(folder))
        table = self.query_one(DataTable)
        table.add_columns("robot", "created (UTC)", "procedure", "status", "cycles")
        for index, summary in enumerate(self._sessions):
            if summary.error:
                table.add_row(
                    shown(summary.path.name, limit=120), "", "", "unreadable", "", key=str(index)
                )
                continue
            cycles = f"{summary.cycles}"
            if summary.cycles_target:
                cycles += f"/{summary.cycles_target}"
            if summary.rejected:
                cycles += f" ({summary.rejected} rej.)"
            table.add_row(
                shown(summary.robot, limit=60),
                shown(summary.created[:19].replace("T", " ")),
                shown(summary.procedure, limit=60),
                shown(summary.status or ""),
                cycles,
                key=str(index),
            )
        note = f"{len(self._sessions)} session(s) in {folder}"
        if not self._sessions:
            note = f"No session files in {folder} yet."
        self.query_one("#review-folder", Static).update(shown(note, style="dim"))
        table.focus()

    def on_data_table_row_selected(self, event: DataTable.RowSelected) -> None:
        """Enter on a row."""
        self.action_open()

    def action_open(self) -> None:
        """The summary of the highlighted session (read-only)."""
        from station.tui.screens.summary import SummaryScreen, SummaryView

        table = self.query_one(DataTable)
        if not self._sessions or table.cursor_row < 0:
            return
        summary = self._sessions[table.cursor_row]
        if summary.error:
            self.notify(shown_line(summary.error, limit=None), severity="error", markup=False)
            return
        try:
            view = SummaryView.from_file(summary.path)
        except StationError as error:
            self.notify(shown_line(explained(error), limit=None), severity="error", markup=False)
            return
        self.app.push_screen(SummaryScreen(view, reviewing=True))

    def _highlighted(self) -> Any:
        table = self.query_one(DataTable)
        if not self._sessions or table.cursor_row < 0:
            return None
        summary = self._sessions[table.cursor_row]
        if summary.error:
            self.notify(shown_line(summary.error, limit=None), severity="error", markup=False)
            return None
        return summary

    def action_history(self) -> None:
        """The highlighted robot's history: every session, its charts and wear trend."""
        from station.tui.screens.record import history_screen

        summary = self._highlighted()
        if summary is not None:
            self.app.push_screen(history_screen(self.app.config.sessions_dir, summary.robot))

    def action_mark(self) -> None:
        """Mark the highlighted session as the "before" of a comparison."""
        summary = self._highlighted()
        if summary is not None:
            self._marked = summary
            self.notify(
                shown_line(
                    f"{summary.path.name} marked: highlight another and press c", limit=None
                ),
                markup=False,
            )

    def action_compare(self) -> None:
        """Compare the highlighted session with the marked one (before → after)."""
        from station.tui.screens.record import compare_screen

        summary = self._highlighted()
        if summary is None:
            return
        if self._marked is None or self._marked.path == summary.path:
            self.notify("Mark a session with m first, then highlight another.", markup=False)
            return
        self.app.push_screen(compare_screen(self._marked.path, summary.path))

    def action_back(self) -> None:
        """Back to the home screen."""
        self.app.pop_screen()

    def action_help(self) -> None:
        """The keys."""
        from station.tui.screens.dialogs import HelpScreen

        self.app.push_screen(HelpScreen())
