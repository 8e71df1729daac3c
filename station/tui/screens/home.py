"""The home screen: what this program does, and the choices: resume, new session, review, quit.

An unfinished session is offered first, so after an SSH drop the operator presses Enter and is
back where they were; past :data:`RESUME_OFFERED` of them the rest are one line (Enter lists
them), so New session is always in reach. The sessions folder in use is said on screen, and in
``station demo`` a banner says that the indicators are simulated.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rich.text import Text
from textual import events
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.css.scalar import Scalar
from textual.screen import Screen
from textual.widgets import OptionList, Static
from textual.widgets.option_list import Option

from station.errors import StationError
from station.session.store import find_unfinished, list_sessions
from station.tui.remedies import explained
from station.tui.screens.dialogs import HelpScreen
from station.tui.text import shown, shown_line
from station.tui.widgets.key_footer import KeyFooter

if TYPE_CHECKING:
    from station.tui.app import StationApp

INTRODUCTION = (
    "Tests a robot by the 1990 NASA/KSC method: repeatability (25–30 returns to a taught "
    "point), relative accuracy (two fixtures) or linearity (strokes along a bar), judged "
    "with mean, σ, skewness, histogram, control chart and Cp/Cpk. ↑ ↓ and Enter choose."
)


CHOICES_ROWS = 10
"""The most rows the box of choices takes (borders included) when the screen has room."""

RESUME_OFFERED = 5
"""Unfinished sessions offered on the home screen before the rest are summed up in one line:
with hundreds of them, New session would be screens away."""


class HomeScreen(Screen[None]):
    """Resume, new session per procedure, review, quit."""

    BINDINGS = [
        Binding("n", "new", "New session"),
        Binding("r", "resume", "Resume"),
        Binding("v", "review", "Review sessions"),
        Binding("question_mark", "help", "Help"),
        Binding("q", "quit", "Quit"),
    ]

    app: StationApp

    def __init__(self) -> None:
        super().__init__()
        self._unfinished: list[Any] = []
        self._session_count = 0
        self._load_error = ""
        self._all_unfinished_shown = False

    def compose(self) -> ComposeResult:
        """Title, introduction, the choices, where the sessions go."""
        config = self.app.config
        with Vertical(id="home"):
            yield Static(Text("station · robot calibration", style="bold"), id="home-title")
            yield Static(INTRODUCTION, id="home-intro")
            if config.demo is not None:
                yield Static(
                    f"DEMO: {config.demo.description} on {config.demo.url}. Nothing here "
                    "touches a real robot; follow the steps as if it did.",
                    id="home-demo",
                )
            yield OptionList(id="home-choices")
            yield Static(id="home-folder")
        yield KeyFooter()

    def on_mount(self) -> None:
        """Fill the choices from the sessions folder."""
        self.reload()

    def reload(self) -> None:
        """Read the sessions folder again and rebuild the list."""

        config = self.app.config
        try:
            self._unfinished = list(find_unfinished(config.sessions_dir))
            self._session_count = len(list_sessions(config.sessions_dir))
        except StationError as error:
            self._unfinished, self._session_count = [], 0
            self._load_error = explained(error)
        choices = self.query_one("#home-choices", OptionList)
        choices.clear_options()
        offered = len(self._unfinished)
        if not self._all_unfinished_shown:
            offered = min(offered, RESUME_OFFERED)
        for index, summary in enumerate(self._unfinished[:offered]):
            choices.add_option(
                Option(shown(_resume_label(summary), limit=300), id=f"resume:{index}")
            )
        if offered < len(self._unfinished):
            more = len(self._unfinished) - offered
            choices.add_option(
                Option(
                    f"… {more} older unfinished session{'s' if more != 1 else ''} "
                    "(Enter lists them all here)",
                    id="more-unfinished",
                )
            )
        choices.add_option(
            Option("New session (choose the procedure, robot, limits and port)", id="new")
        )
        if config.demo_lab is not None:
            from station.tui.instruments import demo_methods  # deferred: the methods load numpy

            catalog = self.app.catalog
            for method, setup in demo_methods().items():
                # The built-in procedure of each simulated method (they share its name).
                if method != config.demo.procedure and catalog.is_builtin(method):  # type: ignore[union-attr]
                    label = f"Demo {method.replace('_', ' ')} instead ({setup})"
                    choices.add_option(Option(label, id=f"demo:{method}"))
        choices.add_option(Option(f"Review saved sessions ({self._session_count})", id="review"))
        choices.add_option(Option("Quit", id="quit"))
        choices.highlighted = 0
        choices.focus()
        self.call_after_refresh(self._fit_choices)
        folder = shown(f"Sessions folder: {shown_line(config.sessions_dir)}", style="dim")
        folder.append(f"\n({shown_line(config.sessions_reason)})", style="dim")
        if self._load_error:
            folder.append(f"\n{shown_line(self._load_error, limit=None)}", style="bold red")
        self.query_one("#home-folder", Static).update(folder)

    def _fit_choices(self) -> None:
        """The choices take the rows their options need, up to :data:`CHOICES_ROWS`, and no
        more than are left above the folder sentence: at 80×24 in the demo the list scrolls
        and the folder stays in view (it was pushed off the screen, issue 26)."""
        choices = self.query_one("#home-choices", OptionList)
        rows = choices.virtual_size.height + choices.styles.gutter.height
        wanted = max(3, min(CHOICES_ROWS, rows))
        if choices.styles.max_height != Scalar.from_number(wanted):
            choices.styles.max_height = wanted

    def on_resize(self, event: events.Resize) -> None:
        """Options wrap differently at another width."""
        self.call_after_refresh(self._fit_choices)

    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        """Enter on a choice."""
        choice = event.option.id or ""
        if choice.startswith("resume:"):
            self.open_resume(self._unfinished[int(choice.split(":", 1)[1])])
        elif choice == "more-unfinished":
            self._all_unfinished_shown = True
            self.reload()
        elif choice == "new":
            self.action_new()
        elif choice.startswith("demo:"):
            self.open_new(choice.split(":", 1)[1])
        elif choice == "review":
            self.action_review()
        elif choice == "quit":
            self.app.exit(0)

    def open_new(self, procedure_id: str | None) -> None:
        """The set-up screen for a new session (of this procedure, else the default one)."""
        from station.tui.screens.setup import SetupScreen  # deferred: loads when shown

        try:
            self.app.catalog.get(procedure_id) if procedure_id else self.app.catalog.ids()[0]
        except (StationError, IndexError) as error:
            message = getattr(error, "message", "no procedure is installed")
            self.query_one("#home-folder", Static).update(shown(message, style="bold red"))
            return
        self.app.push_screen(SetupScreen(procedure_id=procedure_id))

    def open_resume(self, summary: Any) -> None:
        """The set-up screen for resuming this session (the port can be changed)."""
        from station.tui.screens.setup import SetupScreen  # deferred: loads when shown

        self.app.push_screen(SetupScreen(resume_path=summary.path))

    def action_new(self) -> None:
        """A new session; the set-up offers every installed procedure (the procedure catalogue
        loads there, not here, to keep the start fast)."""
        demo = self.app.config.demo
        self.open_new(demo.procedure if demo is not None else None)

    def action_resume(self) -> None:
        """Resume the newest unfinished session."""
        if self._unfinished:
            self.open_resume(self._unfinished[0])
        else:
            self.notify("There is no unfinished session to resume.")

    def action_review(self) -> None:
        """The list of saved sessions."""
        from station.tui.screens.review import ReviewScreen  # deferred: loads when shown

        self.app.push_screen(ReviewScreen())

    def action_help(self) -> None:
        """The keys and what the screens do."""

        self.app.push_screen(HelpScreen())

    def action_quit(self) -> None:
        """Leave the program."""
        self.app.exit(0)


def _resume_label(summary: Any) -> str:
    """``Resume: R1 repeatability (interrupted, 12 of 30 cycles, 2026-11-23 17:40)``: what the
    session counts (cycles, placements or strokes)."""
    created = str(getattr(summary, "created", ""))[:16].replace("T", " ")
    status = getattr(summary, "status", "unfinished")
    return (
        f"Resume: {getattr(summary, 'robot', '?')} {getattr(summary, 'procedure', '')}"
        f" ({status}, {summary.progress}, {created})"
    )
