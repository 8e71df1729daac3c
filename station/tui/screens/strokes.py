"""The linearity dashboard: the robot shuttles along the bar while h, v and s stream.

A thread worker runs the runner's :meth:`~station.run.Runner.stream_strokes`, which records
every point and splits the strokes by the scale's travel; each whole stroke comes back (its
points on disk) and is analysed there, off the UI thread, with the same
:func:`~station.analysis.linearity.analyze_linearity` as ``station analyze``. The screen shows,
redrawn at most ~10 times a second whatever the stream rate: stroke k of N and the points of the
stroke under way; the deviation versus position of that stroke over the earlier ones; the
straightness of each stroke (minimum zone) as a statistics table and a control chart with its
alarms; and the verdict. Keys: h / v choose the indicator, e ends the stroke under way (streaming
stops; Space streams again), f finishes.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.message import Message
from textual.screen import Screen
from textual.widgets import Static

from station.analysis.linearity import least_squares_line
from station.errors import StationError
from station.text import overall_judgement
from station.tui.remedies import explained
from station.tui.screens.dashboard import session_title
from station.tui.screens.dialogs import ConfirmScreen, HelpScreen, TextPrompt
from station.tui.text import shown
from station.tui.theme import VERDICT_STYLES
from station.tui.widgets.alarm_log import AlarmLog, alarm_lines
from station.tui.widgets.control_chart import ControlChartView, chart_data
from station.tui.widgets.deviation_plot import DeviationData, DeviationPlot, trace
from station.tui.widgets.instrument_status import InstrumentStatus
from station.tui.widgets.key_footer import KeyFooter
from station.tui.widgets.stats_panel import StatsPanel, StatsRows

if TYPE_CHECKING:
    from station.run import RunnerState
    from station.tui.app import StationApp

EARLIER_SHOWN = 8
"""Earlier strokes drawn under the newest (more only blur the plot)."""
STREAM_TIMEOUT = 1.0
"""Seconds the stream waits for a reading set before it looks at the stop signal again."""


@dataclass
class StreamEnded(Message):
    """The stream worker returned: the step has its strokes, the operator ended it, or the
    session stopped; ``error`` says why when it failed."""

    error: str = ""


class LiveStroke:
    """The points of the stroke under way, from the runner's ``samples`` events (any thread)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._number: int | None = None
        self._rows: list[list[float]] = []
        self._channels: list[str] = []

    def add(self, event: Mapping[str, Any]) -> None:
        """A ``samples`` event: its rows extend the stroke of its number (a new one restarts)."""
        with self._lock:
            if event.get("stroke") != self._number:
                self._number, self._rows = event.get("stroke"), []
            self._channels = list(event.get("channels") or ())
            self._rows.extend(event.get("values") or ())
            if event.get("end"):
                self._number, self._rows = None, []

    def points(self, channel: str, position: str = "s") -> tuple[list[float], list[float]]:
        """Positions and readings of ``channel`` so far in the stroke under way."""
        with self._lock:
            if channel not in self._channels or position not in self._channels:
                return [], []
            c, p = self._channels.index(channel), self._channels.index(position)
            return [row[p] for row in self._rows], [row[c] for row in self._rows]


def _deviations(s: list[float], d: list[float]) -> list[float]:
    """Deviations from the least-squares line of the points so far (the analysis' line)."""

    if len(s) < 3 or max(s) - min(s) <= 0:
        return []
    a, b = least_squares_line(s, d)
    return [value - (a + b * position) for position, value in zip(s, d, strict=True)]


class StrokeDashboardScreen(Screen[None]):
    """Streams the stroke step and shows each stroke's straightness as it comes."""

    BINDINGS = [
        Binding("space", "stream", "Stream"),
        Binding("e", "end_stroke", "End stroke"),
        Binding("f", "finish", "Finish"),
        Binding("tab", "next_channel", "Indicator", key_display="h/v"),
        Binding("h", "channel('h')", "h", show=False),
        Binding("v", "channel('v')", "v", show=False),
        Binding("n", "note", "Note"),
        Binding("f1", "help", "Help"),
        Binding("q", "leave", "Leave"),
    ]

    app: StationApp

    def __init__(self) -> None:
        super().__init__()
        self.streaming = False
        self.selected = ""
        self.result: Any = None
        """The newest ``LinearityAnalysis`` of the whole strokes (None before the first)."""
        self.live = LiveStroke()
        self._profiles: list[Any] = []
        self._finish_when_ended = False
        self._shown_message: Any = None

    @property
    def busy(self) -> bool:
        """True while the stream worker runs."""
        return self.streaming

    def compose(self) -> ComposeResult:
        """Title and progress, prompt, straightness table, the two plots, alarms, status."""
        yield Static(id="dash-title")
        yield Static(id="dash-prompt")
        yield StatsPanel(id="dash-stats")
        with Horizontal(id="dash-charts"):
            yield DeviationPlot(id="stroke-plot")
            yield ControlChartView(id="stroke-chart")
        yield AlarmLog(id="dash-alarms")
        yield InstrumentStatus(id="dash-instruments")
        yield Static(id="dash-message")
        yield KeyFooter()

    def on_mount(self) -> None:
        """Hear the stream's points, draw, and start streaming."""
        self.app.sample_sink = self.live.add
        state = self.app.current_state()
        if state is not None:
            self.show_state(state)
        self.action_stream()

    def on_unmount(self) -> None:
        """Stop hearing points; a stream still running is ended (its points are written)."""
        if self.app.sample_sink == self.live.add:
            self.app.sample_sink = None
        if self.streaming and self.app.runner is not None:
            self.app.runner.end_stroke()

    # -- drawing --------------------------------------------------------------------------

    def _channels(self) -> tuple[str, ...]:
        if self.result is not None:
            return tuple(self.result.channels)
        header_channels = self.app.session_header.get("channels") or ()
        return tuple(c for c in header_channels if c != "s") or ("h", "v")

    def show_state(self, state: RunnerState) -> None:
        """Redraw from a runner snapshot and the newest stroke analysis (UI thread)."""
        if not self.query("#dash-title"):
            return  # its widgets are being taken down (the screen or the app is leaving)
        header = self.app.session_header
        resolution = header.get("resolution")
        unit = str(header.get("unit", ""))
        channels = self._channels()
        if self.selected not in channels:
            self.selected = channels[0]

        title = Text(session_title(header), style="bold")
        counted = state.progress
        done, target = (counted.done, counted.target) if counted is not None else (0, 0)
        progress = f"   {done} of {target} strokes done"
        if self.streaming and counted is not None:
            progress += f" · {counted.under_way} points now"
        # The engine's live linearity analysis: the numbers the report will show.
        so_far = self.app.live_result()
        if so_far is not None:
            self.result, self._profiles = so_far.analysis, list(so_far.profiles)
        title.append(progress, style="bold cyan")
        self.query_one("#dash-title", Static).update(title)
        self.query_one("#dash-prompt", Static).update(self._prompt(state))
        judged = dict(self.result.judged) if self.result is not None else {}
        numbers = [r.number for r in self.result.strokes] if self.result is not None else []
        last = (
            {c: self.result.strokes[-1].straightness[c].mz for c in channels}
            if self.result is not None and self.result.strokes
            else {}
        )
        self.query_one(StatsPanel).show(
            StatsRows(
                channels=channels,
                analyses=judged,
                last=last,
                resolution=resolution,
                unit=unit,
                selected=self.selected,
            )
        )
        self.query_one(DeviationPlot).show(self._deviation_data(resolution, unit))
        self.query_one(ControlChartView).show(
            chart_data(judged.get(self.selected), numbers, resolution, label="stroke")
        )
        self.query_one(AlarmLog).show(alarm_lines(judged, numbers, label="stroke"))
        self.query_one(InstrumentStatus).show(tuple(state.instruments))
        # The runner's newest message (a stroke done, a reconnect), once; this screen's own
        # sentences stay until the runner has news.
        message = state.messages[-1] if state.messages else None
        if message is not None and message is not self._shown_message:
            self._shown_message = message
            style = {"error": "bold red", "warning": "yellow"}.get(message.level, "green")
            self._say(message.text, style)

    def _prompt(self, state: RunnerState) -> Text:
        counted = state.progress
        if counted is not None and counted.complete and not self.streaming:
            return Text(
                f"All {counted.target} strokes are recorded. Press f to finish and see "
                "the verdict.",
                style="bold green",
            )
        text = Text()
        if self.result is not None:
            # The table's own judgement (PROVISIONAL below the minimum count), not a bare
            # CAPABLE beside rows that say PROVISIONAL.
            overall = overall_judgement(self.result.judged.values())
            text.append("Verdict so far: ", style="bold")
            text.append(overall, style=VERDICT_STYLES.get(overall.partition(":")[0], ""))
            text.append(" (straightness per stroke, minimum zone).  ")
        if self.streaming:
            text.append("Let the robot shuttle A↔B; e ends the stroke now, f finishes.")
        else:
            text.append("Streaming is stopped. Space streams again; f finishes.")
        return text

    def _deviation_data(self, resolution: float | None, unit: str) -> DeviationData:
        channel = self.selected
        earlier: list[Any] = []
        newest = None
        if self.result is not None and self.result.strokes:
            shown = list(zip(self._profiles, self.result.strokes, strict=False))
            traces = [
                trace(profile.s, stroke.straightness[channel].residuals_ls)
                for profile, stroke in shown[-(EARLIER_SHOWN + 1) :]
            ]
            earlier, newest = traces[:-1], traces[-1]
        s, d = self.live.points(channel)
        deviations = _deviations(s, d)
        current = trace(s, deviations) if deviations else None
        return DeviationData(
            channel=channel,
            earlier=tuple(earlier),
            newest=newest,
            current=current,
            resolution=resolution,
            unit=unit,
        )

    def _redraw(self) -> None:
        state = self.app.current_state()
        if state is not None:
            self.show_state(state)

    def _say(self, text: str, style: str = "") -> None:
        self.query_one("#dash-message", Static).update(shown(text, style=style))

    # -- streaming ------------------------------------------------------------------------

    def action_stream(self) -> None:
        """Stream the stroke step (a thread worker: the runner blocks on the gauges)."""
        runner = self.app.runner
        state = self.app.current_state()
        if runner is None or state is None or self.streaming:
            return
        if state.action.kind != "stream" or state.status != "running":
            return
        if state.progress is not None and state.progress.complete:
            self._say(f"All {state.progress.target} strokes are recorded: press f to finish.")
            return
        self.streaming = True
        self._say("Streaming h, v and s: run the robot between A and B.", "yellow")
        self._stream()

    @work(thread=True, group="stroke", exit_on_error=False)
    def _stream(self) -> None:
        """Thread worker: stream until the target (the engine splits and analyses the
        strokes; its notices carry the analysis)."""
        runner = self.app.runner
        if runner is None:
            self.post_message(StreamEnded())
            return
        try:
            runner.stream_strokes(STREAM_TIMEOUT)
            self.post_message(StreamEnded())
        except StationError as error:
            self.post_message(StreamEnded(error=explained(error)))

    def on_stream_ended(self, message: StreamEnded) -> None:
        """The stream stopped: say why, and finish if the operator asked for it."""
        self.streaming = False
        if message.error:
            self._say(message.error, "bold red")
        if self._finish_when_ended:
            self._finish_when_ended = False
            self._finish()
            return
        self._redraw()

    def action_end_stroke(self) -> None:
        """End the stroke under way now: streaming stops (a stroke cut short is left out of
        the analysis); Space streams again."""
        if self.streaming and self.app.runner is not None:
            self.app.runner.end_stroke()
            self._say("Ending the stroke under way ...", "yellow")

    def action_finish(self, force: bool = False) -> None:
        """Finish: stop streaming first; asks when fewer strokes than the minimum."""
        state = self.app.current_state()
        if state is None:
            return
        counted = state.progress
        if counted is not None and not counted.enough and not force:

            def finish(sure: bool | None) -> None:
                if sure:
                    self.action_finish(force=True)

            self.app.push_screen(
                ConfirmScreen(
                    f"Finish with {counted.done} strokes?",
                    f"The report asks for {counted.minimum} to {counted.target}; the session "
                    "is then marked incomplete.",
                ),
                callback=finish,
            )
            return
        if self.streaming:
            self._finish_when_ended = True
            self.action_end_stroke()
            return
        self._finish()

    def _finish(self) -> None:
        try:
            self.app.finish_session()
        except StationError as error:
            self._say(explained(error), "bold red")

    # -- the rest -------------------------------------------------------------------------

    def action_channel(self, channel: str) -> None:
        """Show this indicator in the plots (h, v)."""
        if channel in self._channels():
            self.selected = channel
            self._redraw()

    def action_next_channel(self) -> None:
        """The other indicator."""
        channels = list(self._channels())
        index = channels.index(self.selected) if self.selected in channels else -1
        self.selected = channels[(index + 1) % len(channels)]
        self._redraw()

    def action_note(self) -> None:
        """A free-text note in the session file."""
        runner = self.app.runner
        if runner is None:
            return

        def save(text: str | None) -> None:
            if text:
                try:
                    runner.note(text)
                except StationError as error:
                    self._say(explained(error), "bold red")

        self.app.push_screen(TextPrompt("Note", "What should the session file say?"), callback=save)

    def action_help(self) -> None:
        """The keys."""

        self.app.push_screen(HelpScreen())

    def action_leave(self) -> None:
        """Leave the session resumable (the stroke under way is cut short)."""

        def leave(sure: bool | None) -> None:
            if sure:
                self.action_end_stroke()
                self.app.interrupt_session("operator left")
                self.app.go_home()

        self.app.push_screen(
            ConfirmScreen(
                "Leave this session?",
                "It is kept as interrupted; choose Resume on the home screen to continue.",
            ),
            callback=leave,
        )
