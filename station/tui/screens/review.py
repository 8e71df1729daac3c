"""Review: the saved sessions by robot and date; Enter opens one read-only (summary, charts).

Each row says the verdict of a finished session (worked out on a thread, filled in as it
comes), and the state of an unfinished one: ``interrupted``, ``running now`` (a live station
holds its lock) or ``stopped without a word (crashed?)`` (marked running, but no writer is
left). ``/`` shows one robot's sessions.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.cells import cell_len
from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.screen import Screen
from textual.widgets import DataTable, Static

from station.errors import StationError
from station.session.store import list_sessions, status_words
from station.tui.remedies import explained
from station.tui.screens.dialogs import HelpScreen, TextPrompt
from station.tui.screens.summary import SummaryScreen, SummaryView
from station.tui.text import shown, shown_line
from station.tui.theme import VERDICT_STYLES
from station.tui.widgets.key_footer import KeyFooter

if TYPE_CHECKING:
    from station.tui.app import StationApp


COLUMNS = (
    ("robot", "robot"),
    ("created (UTC)", "created"),
    ("verdict / state", "verdict"),
    ("procedure", "procedure"),
    ("done", "cycles"),
)
"""The list's columns: label and key."""
COLUMN_GUTTER = 2
"""Cells a column takes beside its text (the table's padding, one on each side)."""
SCROLLBAR = 2
"""Cells kept for the list's scroll bar."""
VERDICT_ROOM = max(map(cell_len, VERDICT_STYLES))
"""The verdict column is wide enough for any verdict word (they are filled in later)."""
NARROWEST_ROBOT = 12
"""The fewest cells the robot column keeps when the columns are too wide together."""


def column_widths(rows: Sequence[Sequence[Text]], room: int) -> list[int]:
    """Each column's width: its widest cell or label; then, while they take more than
    ``room`` cells together, narrowed in turn where wrapping reads best: the robot (free text)
    down to :data:`NARROWEST_ROBOT`, the verdict or state down to its label, what was done
    down to its label, the procedure (one word) last; the date never."""
    widths = [cell_len(label) for label, _key in COLUMNS]
    for cells in rows:
        for index, cell in enumerate(cells):
            widths[index] = max(widths[index], cell.cell_len)
    widths[2] = max(widths[2], VERDICT_ROOM)
    floors = {0: NARROWEST_ROBOT, 2: cell_len(COLUMNS[2][0]), 4: 8, 3: cell_len(COLUMNS[3][0])}
    for index, floor in floors.items():
        excess = sum(widths) - room
        if excess <= 0:
            break
        widths[index] = max(min(floor, widths[index]), widths[index] - excess)
    return widths


class ReviewScreen(Screen[None]):
    """A table of the sessions folder; nothing here changes a file."""

    BINDINGS = [
        Binding("o", "open", "Open", key_display="enter/o"),
        Binding("h", "history", "Robot history"),
        Binding("m", "mark", "Mark for compare"),
        Binding("c", "compare", "Compare with mark"),
        Binding("slash", "filter", "Robot filter", key_display="/"),
        Binding("escape", "back", "Back"),
        Binding("f1", "help", "Help"),
        Binding("q", "back", "Back", show=False),
    ]

    app: StationApp

    def __init__(self) -> None:
        super().__init__()
        self._sessions: list[Any] = []
        self._marked: Any = None
        self._all: list[Any] = []
        self._robot_filter = ""
        self._verdicts: dict[Path, str] = {}

    def compose(self) -> ComposeResult:
        """Title, the table, the folder."""
        yield Static(Text("Saved sessions, by robot and date", style="bold"), id="review-title")
        yield DataTable(id="review-table", cursor_type="row", zebra_stripes=True)
        yield Static(id="review-folder")
        yield KeyFooter()

    def on_mount(self) -> None:
        """List the folder."""

        folder = self.app.config.sessions_dir
        self._all = list(list_sessions(folder))
        table = self.query_one(DataTable)
        self._fill()
        table.focus()
        finished = [s.path for s in self._all if not s.error and s.status == "finished"]
        if finished:
            self._work_out_verdicts(finished)

    def _fill(self) -> None:
        """The rows of the sessions the robot filter lets through."""

        table = self.query_one(DataTable)
        row = table.cursor_row
        wanted = self._robot_filter.casefold()
        self._sessions = [
            s for s in self._all if not wanted or wanted in (s.robot or "").casefold()
        ]
        rows: list[tuple[Text, ...]] = []
        for summary in self._sessions:
            if summary.error:
                blank = Text("")
                name = shown(summary.path.name, limit=120)
                rows.append((name, blank, Text("unreadable"), blank, blank))
                continue
            cycles = summary.progress_brief
            if summary.rejected:
                cycles += f" ({summary.rejected} rej.)"
            rows.append(
                (
                    shown(summary.robot, limit=60),
                    shown(summary.created[:16].replace("T", " ")),
                    self._verdict_cell(summary),
                    shown(summary.procedure, limit=60),
                    Text(cycles),
                )
            )
        table.clear(columns=True)
        # A finished session's verdict and an unfinished one's state share a column: one of
        # them is all a row has. Columns too wide for the terminal together are narrowed and
        # their cells wrap, so the last one is never cut off at the screen's edge.
        room = self.app.size.width - COLUMN_GUTTER * len(COLUMNS) - SCROLLBAR
        widths = column_widths(rows, room)
        for (label, key), width in zip(COLUMNS, widths, strict=True):
            table.add_column(label, key=key, width=width)
        # A robot (or a file name) of 60 characters in a narrowed column would be a row of
        # five lines and push the others off the screen: two lines' worth, then an ellipsis.
        most = 2 * widths[0]
        for index, cells in enumerate(rows):
            first = cells[0]
            if first.cell_len > most:
                first = first[: most - 1] + Text("…")
            table.add_row(first, *cells[1:], key=str(index), height=None)
        if 0 <= row < len(rows):
            table.move_cursor(row=row)
        folder = self.app.config.sessions_dir
        note = f"{len(self._all)} session(s) in {folder}"
        if self._robot_filter:
            note = (
                f"{len(self._sessions)} of {len(self._all)} session(s), robot "
                f"“{self._robot_filter}” (/ to change), in {folder}"
            )
        if not self._all:
            note = f"No session files in {folder} yet."
        self.query_one("#review-folder", Static).update(shown(note, style="dim"))

    def on_resize(self, event: Any) -> None:
        """Another width: the columns are fitted to it again."""
        if self._all:
            self._fill()

    def _verdict_cell(self, summary: Any) -> Text:

        if summary.error or summary.status != "finished":
            return shown(status_words(summary))
        word = self._verdicts.get(summary.path)
        if word is None:
            return Text("…")
        return Text(word, style=VERDICT_STYLES.get(word, ""))

    @work(thread=True, group="review-verdicts", exclusive=True, exit_on_error=False)
    def _work_out_verdicts(self, paths: list[Path]) -> None:
        """Thread worker: each finished session's overall verdict, as the summary says it."""

        for path in paths:
            try:
                # The summary's own judgement, its first word in the narrow column (a session
                # below the minimum count is PROVISIONAL here too, never CAPABLE).
                word = SummaryView.from_file(path).verdict_word
            except (StationError, OSError, ValueError, AttributeError):
                word = "—"
            self.app.call_from_thread(self._show_verdict, path, word)

    def _show_verdict(self, path: Path, word: str) -> None:
        self._verdicts[path] = word
        table = self.query_one(DataTable)
        for index, summary in enumerate(self._sessions):
            if summary.path == path:
                table.update_cell(str(index), "verdict", self._verdict_cell(summary))

    def action_filter(self) -> None:
        """``/``: show one robot's sessions (part of the name, any case; empty shows all)."""

        def chosen(text: str | None) -> None:
            if text is None:
                return
            self._robot_filter = "" if text.strip() in ("", "*") else text.strip()
            self._fill()

        self.app.push_screen(
            TextPrompt(
                "Robot filter",
                "Show the sessions of the robot named (part of the name is enough; * for all).",
                placeholder="robot name or asset number",
            ),
            chosen,
        )

    def on_data_table_row_selected(self, event: DataTable.RowSelected) -> None:
        """Enter on a row."""
        self.action_open()

    def action_open(self) -> None:
        """The summary of the highlighted session (read-only)."""

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
        from station.tui.screens.record import history_screen  # deferred: loads when shown

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
        from station.tui.screens.record import compare_screen  # deferred: loads when shown

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

        self.app.push_screen(HelpScreen())
