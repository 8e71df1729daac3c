"""StationApp: the terminal user interface that drives one procedure runner from set-up to verdict.

The app owns the long-lived things: the sessions folder, the procedure catalogue, the open
instruments and the :class:`~station.run.Runner`. Screens ask the app to start, resume or end a
session and receive the runner's state to draw. The runner's listener runs on whatever thread
wrote the event; it only stores the newest state and posts a coalescing :class:`RunnerChanged`, and
the app redraws at most ``REDRAW_INTERVAL`` apart on the UI thread (a burst of readings costs one
redraw, and a reading after a quiet spell is drawn at once).

SIGHUP and SIGTERM (an SSH drop, a shutdown) interrupt the runner, which writes ``interrupted`` to
the session file, then the app exits and restores the terminal; the next ``station`` offers to
resume the session. Textual installs no handler for these itself.

Only the home screen and the dialogs are imported at start; the other screens (and numpy, scipy
behind the analysis) load when first needed, so the first screen appears fast.
"""

from __future__ import annotations

import asyncio
import signal
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

from textual import events, work
from textual.app import App, SystemCommand
from textual.binding import Binding
from textual.filter import LineFilter, Monochrome, NoColor
from textual.geometry import Size
from textual.screen import ModalScreen, Screen

from station.errors import StationError
from station.plain import plain
from station.tui.autopilot import run_autopilot
from station.tui.instruments import running_fixture
from station.tui.messages import RunnerChanged
from station.tui.remedies import explained
from station.tui.screens.dialogs import (
    APP_KEYS,
    ConfirmScreen,
    HelpScreen,
    QuitQuestion,
    declared_actions,
    screen_keys,
)
from station.tui.screens.home import HomeScreen
from station.tui.theme import HIGH_CONTRAST_THEME, apply_palette, wanted_theme
from station.tui.widgets.too_small import TooSmallNotice, too_small

# Deliberately imported where first used, for start-up time (station/README.md): the other
# screens when first shown, the procedure catalogue when first asked for (about 60 ms), and the
# engine (station.run), which loads numpy, when a session starts; numpy and scipy themselves load
# on a worker thread (warm_up_analysis). So the home screen appears at once.
if TYPE_CHECKING:
    from station.procedures import ProcedureCatalog
    from station.run import Runner, RunnerNotice, RunnerState, SessionSetup

REDRAW_INTERVAL = 0.1
"""Seconds between two redraws of the live screens: at most ~10 a second, whatever the rate."""

_NO_COLOUR = NoColor()
"""The filter that takes every colour off a line (``NO_COLOR``)."""

HANGUP_EXIT_CODES = {signal.SIGHUP: 129, signal.SIGTERM: 143}

PORT_OPEN_TIMEOUT = 3.0
"""Seconds the set-up waits for the gauges' port to open before it refuses to start."""
FRAMES_TIMEOUT = 2.0
"""Seconds the set-up reads frames for, to check the gauges' unit and resolution."""


class PortNotOpen(StationError):
    """The gauges' port did not open at start: nothing was written; the set-up says why."""


@dataclass(frozen=True)
class DemoPort:
    """The simulated indicators ``station demo`` started, to pre-fill the set-up."""

    url: str
    protocol: str
    channel_map: dict[str, str]
    procedure: str = "repeatability"
    robot: str = "demo-robot"
    description: str = "simulated dial indicators (seeded)"
    trigger: str = "poll"
    count: int | None = None
    """Cycles, placements or strokes to pre-fill in the set-up (None: the procedure's)."""


@dataclass(frozen=True)
class StationConfig:
    """What the command line decided before the app starts."""

    sessions_dir: Path
    sessions_reason: str
    """Why this folder (``--sessions``, ``STATION_SESSIONS``, ``./sessions``, the data folder)."""
    procedure_dirs: tuple[Path, ...] = ()
    demo: DemoPort | None = None
    demo_lab: Any = None
    """The demo's simulators per procedure (``station.tui.instruments.DemoLab``), or None."""
    autopilot: bool = False
    autopilot_pace: float = 0.2
    """Seconds between two autopilot actions (a cycle every ``autopilot_pace`` seconds)."""
    capture_timeout: float = 5.0
    """Seconds a capture waits for every gauge before it is refused."""


class StationApp(App[int]):
    """The station's TUI. ``run()`` returns the exit code (129/143 after SIGHUP/SIGTERM)."""

    CSS_PATH = Path(__file__).with_name("station.tcss")
    TITLE = "station"
    COMMAND_PALETTE_BINDING = "ctrl+p"
    BINDINGS = [
        Binding("ctrl+c", "quit_station", "Quit", show=False, priority=True),
        Binding("question_mark", "keys", "Keys", show=False),
    ]

    def __init__(self, config: StationConfig) -> None:
        super().__init__()
        self.config = config
        # Verdicts and alarms by text attributes; without colour they name no colour at all.
        self.register_theme(HIGH_CONTRAST_THEME)
        theme = wanted_theme()
        if theme is not None:
            self.theme = theme
        apply_palette(colour=not self.no_color and theme is None)
        self.runner: Runner | None = None
        self.session_header: dict[str, Any] = {}
        """The running session's header fields (robot, procedure, channels, unit, limits)."""
        self.gauges: Any = None
        self._catalog: ProcedureCatalog | None = None
        self._latest_state: RunnerState | None = None
        self._latest_analysis: Any = None
        self._latest_result: Any = None
        self._finishing = False
        self._state_lock = threading.Lock()
        self._last_redraw = 0.0
        self._redraw_pending = False
        self._oldest_pending = 0.0
        self._analysis_due = False
        self.redraw_hooks: list[Callable[[float], None]] = []
        """Called after each redraw with the oldest pending event's stamp (for the benchmark)."""
        self.reading_hooks: list[Callable[[], None]] = []
        """Called after a reading's line is painted (for the benchmark)."""
        self._signals_installed: list[int] = []
        self._warmed_up = False
        self.demo_fixture: Any = None
        """The demo's simulator the running session talks to (its pendant), or None."""
        self.sample_sink: Callable[[Any], None] | None = None
        """Hears each ``samples`` event on the writing thread (the stroke dashboard's buffer of
        the stroke under way); it must only store, never draw."""

    def get_line_filters(self) -> Sequence[LineFilter]:
        """Under ``NO_COLOR``, no colour at all: Textual's own filter turns every colour into
        a grey of the same luminance, which still reaches the terminal as 256-colour or
        truecolour escapes (issue 26). The station says everything by words and attributes
        (bold, reverse video, underline), so each line takes the terminal's own foreground
        and background instead."""
        filters = super().get_line_filters()
        if not self.no_color:
            return filters
        return [_NO_COLOUR if isinstance(each, Monochrome) else each for each in filters]

    # ---------------------------------------------------------------------------------------
    # Start and stop

    def on_mount(self) -> None:
        """Install the hang-up handlers and show the home screen (or start the autopilot)."""
        loop = asyncio.get_running_loop()
        for signum in (signal.SIGHUP, signal.SIGTERM):
            try:
                loop.add_signal_handler(signum, self.hang_up, signum)
                self._signals_installed.append(signum)
            except (NotImplementedError, RuntimeError, ValueError):
                pass  # not the main thread (some test harnesses): nothing to restore then
        self.screen_change_signal.subscribe(self, lambda _screen: self.fit_to_terminal())
        self.push_screen(HomeScreen())
        if self.config.autopilot:
            self.run_worker(run_autopilot(self), group="autopilot", exclusive=True)

    def on_resize(self, event: events.Resize) -> None:
        """Show the "terminal too small" notice, or take it away (this runs before Textual's
        own handler stores the new size, so the size comes from the event)."""
        self.fit_to_terminal(event.size)

    def fit_to_terminal(self, size: Size | None = None) -> None:
        """Below the smallest size the screens are laid out for, the current screen shows one
        sentence (``TooSmallNotice``) instead of tables that lost their names and values."""
        size = size or self.size
        small = too_small(size)
        if small != self.has_class("-too-small"):
            self.set_class(small, "-too-small")
            # Textual restyles only the top screen on an app class change; the screens below
            # are laid out at the new size too, and must not lay out their tables in 6 columns.
            for screen in self.screen_stack:
                screen.update_node_styles(animate=False)
        if not small:
            return
        screen = self.screen
        notices = screen.query(TooSmallNotice)
        if notices:
            notices.first().show_size(size)
        else:
            notice = TooSmallNotice()
            screen.mount(notice)
            notice.show_size(size)

    def on_unmount(self) -> None:
        """Remove the signal handlers and stop the instruments."""
        loop = asyncio.get_running_loop()
        for signum in self._signals_installed:
            loop.remove_signal_handler(signum)
        self.close_instruments()

    def hang_up(self, signum: int) -> None:
        """SIGHUP or SIGTERM: write ``interrupted`` (the session stays resumable), then exit."""
        name = signal.Signals(signum).name
        self.interrupt_session(name)
        # Textual's signature is exit(result, return_code): the code must go by name, or it
        # becomes the result and the process exits 0.
        code = HANGUP_EXIT_CODES.get(signal.Signals(signum), 1)
        self.exit(code, return_code=code)

    def interrupt_session(self, reason: str) -> None:
        """Leave the running session resumable: the runner writes an ``interrupted`` event."""
        runner = self.runner
        if runner is None:
            return
        status = runner.state().status
        if status in ("running", "paused"):
            try:
                runner.interrupt(reason)
            except StationError as error:
                self.notify(plain(explained(error)), severity="error", markup=False)
        self.close_instruments()

    def close_instruments(self) -> None:
        """Stop the gauge readers (returns promptly)."""
        gauges, self.gauges = self.gauges, None
        if gauges is not None:
            gauges.stop()

    async def action_quit_station(self) -> None:
        """Ctrl+C: leave an unfinished session resumable, then quit. Inside a dialog (a note
        being typed, a question) it asks first, naming any half-typed text, so a stray Ctrl+C
        does not throw the text away; a second Ctrl+C on that question quits."""
        screen = self.screen
        if isinstance(screen, QuitQuestion):
            self._quit_now()
            return
        if isinstance(screen, ModalScreen):
            unsaved = ""
            for widget in screen.query("Input"):
                value = str(getattr(widget, "value", "")).strip()
                if value:
                    unsaved = value
                    break
            detail = "The session stays resumable."
            if unsaved:
                detail = (
                    f"What you typed is not saved: “{plain(unsaved)}”. Press n to go back and "
                    "finish it (Enter saves it). " + detail
                )
            question: ConfirmScreen = QuitQuestion("Quit station now?", detail)

            def answered(yes: bool | None) -> None:
                if yes:
                    self._quit_now()

            self.push_screen(question, answered)
            return
        self._quit_now()

    def _quit_now(self) -> None:
        self.interrupt_session("quit")
        self.exit(0)

    def get_system_commands(self, screen: Screen[Any]) -> Iterable[SystemCommand]:
        """The command palette (Ctrl+P): every action of the current screen by name, with its
        key, then Ctrl+C's Quit (unless the screen has a Quit of its own: one is enough), the
        theme and this screen's keys. Textual's own entries (quit without writing
        ``interrupted``, screenshots, its focus and copy keys, a list's cursor keys) are left
        out on purpose: they are not this program's."""
        declared = declared_actions(screen)
        own: list[tuple[Binding, Any]] = []
        general: list[tuple[Binding, Any]] = []
        for active in screen.active_bindings.values():
            binding = active.binding
            if not binding.description or not active.enabled:
                continue
            if active.node is screen and binding.action in declared:
                own.append((binding, active.node))
            elif active.node is self and binding.action in APP_KEYS:
                general.append((binding, active.node))
        seen: set[str] = set()
        named: set[str] = set()
        for binding, node in own + general:
            action, description = binding.action, binding.description
            if action in seen or action in ("command_palette", "keys") or description in named:
                continue
            seen.add(action)
            named.add(description)
            yield SystemCommand(
                description,
                f"key {self.get_key_display(binding)}",
                partial(self._run_from_palette, action, node),
            )
        yield SystemCommand(
            "Theme",
            "Change the colours (station-high-contrast: black and white, for a bright workshop)",
            self.action_change_theme,
        )
        if screen_keys(screen):
            yield SystemCommand("Keys of this screen", "key ?", self.action_keys)

    async def _run_from_palette(self, action: str, node: Any) -> None:
        await self.run_action(action, node)

    def action_keys(self) -> None:
        """``?``: the keys of the current screen (and the help)."""
        if not isinstance(self.screen, HelpScreen):
            self.push_screen(HelpScreen())

    def warm_up_analysis(self) -> None:
        """Load the analysis (numpy, scipy: about half a second) on a thread, early, so that
        the first captured cycle is not drawn late. Kept off the start path on purpose."""
        if not self._warmed_up:
            self._warmed_up = True
            self.run_worker(_import_analysis, thread=True, group="warm-up", exit_on_error=False)

    # ---------------------------------------------------------------------------------------
    # Procedures and sessions

    @property
    def catalog(self) -> ProcedureCatalog:
        """The installed procedures (built-in plus ``--procedures`` folders), loaded once."""
        if self._catalog is None:
            # Deferred: start-up time. The methods first: procedure files name them.
            import station.methods  # noqa: F401
            from station.procedures import discover_procedures

            self._catalog = discover_procedures(self.config.procedure_dirs)
        return self._catalog

    def demo_port(self, procedure_id: str | None) -> DemoPort | None:
        """The demo's simulated set-up for ``procedure_id`` (each procedure has its own
        simulator: two fixtures and a pendant, a bar, one fixture), or None outside the demo."""
        demo = self.config.demo
        lab = self.config.demo_lab
        if demo is None or lab is None or procedure_id in (None, demo.procedure):
            return demo
        fixture = lab.fixture(self.catalog.get(procedure_id).analysis)
        return DemoPort(
            url=fixture.url,
            protocol=fixture.protocol,
            channel_map=dict(fixture.channel_map),
            procedure=str(procedure_id),
            robot=demo.robot,
            description=fixture.description,
            trigger=fixture.trigger,
            count=demo.count,
        )

    def _simulator_at(self, url: str) -> Any:
        """The simulated set-up this process runs on ``url`` (the demo's), or None."""
        lab = self.config.demo_lab
        return lab.by_url(url) if lab is not None else running_fixture(url)

    def _find_demo_fixture(self, setup: SessionSetup) -> None:
        found = [self._simulator_at(port.url) for port in setup.ports]
        self.demo_fixture = next((f for f in found if f is not None), None)

    def start_session(self, setup: SessionSetup) -> None:
        """Open the instruments and start a new session; raises StationError with a sentence."""
        from station.run import Runner  # deferred: the engine loads numpy

        self.warm_up_analysis()
        self._find_demo_fixture(setup)
        self._open_instruments(setup)
        try:
            self.runner = Runner.start(
                setup, self.gauges, self.config.sessions_dir, listener=self._runner_listener
            )
        except BaseException:
            self.close_instruments()
            raise
        self.session_header = setup.header_fields()
        self._show_runner_screen(self.runner.state())

    def _open_instruments(self, setup: SessionSetup) -> None:
        """Open the gauges and wait for the line, so a wrong port is refused before a session
        file exists (PortNotOpen with the reader's own sentence)."""
        from station.run import open_gauges  # deferred: the engine loads numpy

        self.close_instruments()
        self.gauges = open_gauges(setup)
        if not self.gauges.wait_connected(PORT_OPEN_TIMEOUT):
            down = [
                f"{reader.url}: {reader.last_message or reader.state}"
                for reader in self.gauges.readers
                if reader.state != "connected"
            ]
            self.close_instruments()
            raise PortNotOpen(
                f"the port did not open within {PORT_OPEN_TIMEOUT:g} s ({'; '.join(down)}); "
                "correct it and press F2 again (F3 tests the line)"
            )
        # What the gauges send must be what the session says, before any file exists.
        problem = self.gauges.check_frames(
            setup.resolved_unit,
            setup.resolved_resolution,
            readings=1,  # one reading set: its frames show the decimals and a stated unit
            timeout=FRAMES_TIMEOUT,
            channels=setup.channels,
        )
        if problem:
            self.close_instruments()
            raise StationError(
                f"{problem[0].upper()}{problem[1:]}: set the unit and resolution to the "
                "gauges' (or the gauges to the session's); nothing was written",
                field="unit",
            )

    def resume_session(self, path: Path, ports: Any) -> None:
        """Reopen the instruments (``ports``: the line as the set-up screen now says) and
        continue an unfinished session file."""
        from station.run import Runner, resume_setup  # deferred: the engine loads numpy

        # The demo's own simulators are its line, whatever pseudo-terminal number they got.
        own = [port.url for port in ports or () if self._simulator_at(port.url) is not None]
        setup = resume_setup(
            path, procedures_dirs=self.config.procedure_dirs, ports=ports, own_simulators=own
        )
        self.warm_up_analysis()
        self._find_demo_fixture(setup)
        self._open_instruments(setup)
        try:
            self.runner = Runner.resume(
                path, self.gauges, setup=setup, listener=self._runner_listener
            )
        except BaseException:
            self.close_instruments()
            raise
        self.session_header = setup.header_fields()
        self._show_runner_screen(self.runner.state())

    def finish_session(self) -> None:
        """Write ``finish`` (the engine closes the current step where it has its minimum) and
        show the summary. The write and the session's report run on a worker thread: the UI
        never waits on the disk or the analysis."""
        runner = self.runner
        if runner is None or self._finishing:
            return
        self._finishing = True
        self._finish_in_thread(runner)

    @work(thread=True, group="finish", exit_on_error=False)
    def _finish_in_thread(self, runner: Runner) -> None:
        from station.tui.screens.summary import SummaryView  # deferred: a screen loads when shown

        try:
            analysis = runner.finish()
            view = SummaryView.from_live(runner.state(), analysis, self.session_header)
        except StationError as error:
            self.call_from_thread(self._finish_refused, explained(error))
            return
        self.call_from_thread(self._show_summary, view)

    def _finish_refused(self, sentence: str) -> None:
        self._finishing = False
        self.notify(sentence, severity="error", markup=False)

    def _show_summary(self, view: Any) -> None:
        from station.tui.screens.summary import SummaryScreen  # deferred: a screen loads when shown

        self._finishing = False
        self.close_instruments()
        self._replace_run_screen(SummaryScreen(view))

    # ---------------------------------------------------------------------------------------
    # Runner -> screen

    def _runner_listener(self, notice: RunnerNotice) -> None:
        """Called on the thread that produced the event: store the state, post a message."""
        with self._state_lock:
            self._latest_state = notice.state
            if notice.analysis is not None:
                self._latest_analysis = notice.analysis
                self._latest_result = notice.result
        fixture = self.demo_fixture
        if fixture is not None:
            # The simulated robot goes where the procedure says (its pendant follows).
            fixture.follow(notice.state)
        event_type = str((notice.event or {}).get("type", "")) if notice.event else ""
        sink = self.sample_sink
        if sink is not None and event_type == "samples":
            sink(notice.event)
        reading = event_type == "reading"
        self.post_message(
            RunnerChanged(
                event_type=event_type,
                posted_at=time.monotonic(),
                reading=reading,
                # A reading's figures and charts come with the live analysis the engine sends
                # next: its own notice changes only the last-reading line.
                redraw=not reading,
                analysis=notice.analysis is not None or notice.result is not None,
            )
        )

    def on_runner_changed(self, message: RunnerChanged) -> None:
        """A reading on disk is painted at once as one cheap line (the counters and last
        values); anything else (the live analysis that follows it, a step, an alarm) redraws
        the whole screen now if the last redraw is old enough, else once when it is (at most
        ~10 a second, whatever the rate)."""
        if message.reading:
            self._paint_last_reading()
            self._analysis_due = True
        if not message.redraw:
            return
        if not self._oldest_pending or message.posted_at < self._oldest_pending:
            self._oldest_pending = message.posted_at
        if message.analysis:
            # The engine sends its live analysis at most ~10 times a second already: drawn at
            # once, the charts are never a redraw budget behind the figures.
            self._analysis_due = False
            self.redraw_live()
            return
        if self._redraw_pending:
            return
        wait = self._last_redraw + REDRAW_INTERVAL - time.monotonic()
        if self._analysis_due:
            # The analysis a reading brings redraws the screen soon: what changed with it (an
            # alarm, a message) is drawn then, unless it takes longer than a redraw budget.
            wait = REDRAW_INTERVAL
        if wait <= 0:
            self.redraw_live()
        else:
            self._redraw_pending = True
            self.set_timer(wait, self._redraw_when_due)

    def _redraw_when_due(self) -> None:
        """The coalesced redraw, unless one since drew everything it waited for."""
        self._redraw_pending = False
        if self._oldest_pending:
            self.redraw_live()

    def _paint_last_reading(self) -> None:
        if not self.screen_stack:
            return  # the app is closing: no screen to paint
        with self._state_lock:
            state = self._latest_state
        screen = self.screen
        paint = getattr(screen, "show_last_reading", None)
        if state is None or paint is None or not screen.is_mounted:
            return
        paint(state)
        for hook in self.reading_hooks:
            hook()

    def redraw_live(self) -> None:
        """Hand the newest runner state to the screen showing it; switch screens on step kind."""
        self._last_redraw = time.monotonic()
        oldest, self._oldest_pending = self._oldest_pending, 0.0
        with self._state_lock:
            state = self._latest_state
        if state is None or self.runner is None or not self.screen_stack:
            return  # nothing to show, or the app is closing (a redraw timer outlived it)
        if not self._show_runner_screen(state):
            screen = self.screen
            show = getattr(screen, "show_state", None)
            # A screen still being mounted draws the newest state itself in on_mount.
            if show is not None and screen.is_mounted:
                show(state)
        for hook in self.redraw_hooks:
            hook(oldest)

    def current_state(self) -> RunnerState | None:
        """The newest runner state (from the listener, else asked)."""
        with self._state_lock:
            state = self._latest_state
        if state is None and self.runner is not None:
            state = self.runner.state()
        return state

    def live_analysis(self) -> Any:
        """The newest live analysis the engine's notices carried, or None before there is
        one (the UI never takes the engine's lock for it)."""
        with self._state_lock:
            return self._latest_analysis

    def live_result(self) -> Any:
        """The method's own live result (per-stroke straightness...), or None."""
        with self._state_lock:
            return self._latest_result

    def _show_runner_screen(self, state: RunnerState) -> bool:
        """Put up the checklist or the dashboard for the current step; True when it switched."""
        # Deferred: a screen loads when first shown.
        from station.tui.screens.checklist import ChecklistScreen
        from station.tui.screens.dashboard import DashboardScreen

        if state.status in ("finished", "interrupted", "failed"):
            return False
        screen = self._run_screen()
        action = state.action.kind
        if action == "stream":
            from station.tui.screens.strokes import StrokeDashboardScreen  # deferred: as above

            if not isinstance(screen, StrokeDashboardScreen):
                self._replace_run_screen(StrokeDashboardScreen())
                return True
            return False
        # Capturing and finishing happen on the dashboard; confirm, input and zero on the
        # checklist.
        wants_dashboard = action in ("capture", "finish", "done")
        if wants_dashboard and not isinstance(screen, DashboardScreen):
            self._replace_run_screen(DashboardScreen(live=True))
            return True
        if not wants_dashboard and not isinstance(screen, ChecklistScreen):
            # From a capture back to the checklist: show what Space just recorded.
            captured = state.last_cycle if isinstance(screen, DashboardScreen) else None
            self._replace_run_screen(ChecklistScreen(just_captured=captured))
            return True
        return False

    def _run_screen(self) -> Any:
        """The screen the session runs on, under any dialog or the alarm list opened over it
        (those stay open while the run screen is still the right one)."""
        from station.tui.screens.alarms import AlarmsScreen  # deferred: loads when shown

        for screen in reversed(self.screen_stack):
            if not isinstance(screen, ModalScreen | AlarmsScreen):
                return screen
        return self.screen

    def _replace_run_screen(self, screen: Any) -> None:
        """Swap the set-up, checklist or dashboard for ``screen`` (modals are closed first)."""
        from station.tui.screens.alarms import AlarmsScreen  # deferred: loads when shown

        while isinstance(self.screen, ModalScreen | AlarmsScreen):
            self.pop_screen()
        self.switch_screen(screen)

    def go_home(self) -> None:
        """Back to a fresh home screen (after a summary or a review)."""
        self.runner = None
        with self._state_lock:
            self._latest_state = None
            self._latest_analysis = None
            self._latest_result = None
        while len(self.screen_stack) > 2:
            self.pop_screen()
        self.switch_screen(HomeScreen())


def _import_analysis() -> None:
    """What the first live analysis would otherwise import on the UI thread (scipy through
    the one importer the engine waits on too)."""
    from station.analysis.diagnostics import import_scipy

    import_scipy()
    import station.analysis.summary  # noqa: F401
