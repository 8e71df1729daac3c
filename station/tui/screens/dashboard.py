"""The capture dashboard: live statistics for every axis, the charts of the selected one.

At 80×24 three axes side by side do not fit with charts, so the statistics of x, y and z sit in
one table at the top and the histogram and control chart below show the selected axis (x, y, z
or Tab to switch). Space captures a cycle in a thread worker (the runner blocks on the gauges,
never the screen); the app hands this screen the runner's newest state at most ~10 times a
second. The same screen opens a saved session read-only (review), without the capture keys.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.screen import Screen
from textual.widgets import Static

from station.errors import StationError
from station.text import format_figure
from station.tui.messages import CaptureFinished
from station.tui.remedies import explained
from station.tui.screens.dialogs import ConfirmScreen, FullTextScreen, HelpScreen, TextPrompt
from station.tui.text import shown, shown_line
from station.tui.widgets.alarm_log import AlarmLog, alarm_lines, recorded_alarm_lines
from station.tui.widgets.control_chart import ControlChartView, chart_data
from station.tui.widgets.histogram import HistogramView, histogram_data
from station.tui.widgets.instrument_status import InstrumentStatus
from station.tui.widgets.key_footer import KeyFooter
from station.tui.widgets.stats_panel import StatsPanel, StatsRows

if TYPE_CHECKING:
    from station.run import RunnerState
    from station.tui.app import StationApp


@dataclass(frozen=True)
class DashboardView:
    """Everything the dashboard draws, from a live runner or from a saved session."""

    title: str
    progress: str
    prompt: str
    channels: tuple[str, ...]
    analyses: Mapping[str, Any] = field(default_factory=dict)
    last: Mapping[str, float] = field(default_factory=dict)
    cycle_numbers: tuple[int, ...] = ()
    """The cycle number of each accepted cycle, in order (the charts' points)."""
    ports: tuple[Any, ...] = ()
    message: Any = None
    """The runner's newest operator message (an ``OperatorMessage``), shown once when new."""
    resolution: float | None = None
    unit: str = ""
    ready_to_finish: bool = False
    flags: Mapping[str, str] = field(default_factory=dict)
    """Channel -> "above"/"below" when its last reading is beyond a specification limit."""
    alarms: tuple[Any, ...] | None = None
    """The alarms the session recorded (``RecordedAlarm``, with their acknowledgements); None:
    the log shows the chart's alarms instead (a file without alarm events)."""
    no_alarms: str = "alarms: none"
    """What the log says while there is no alarm (live: when the control limits freeze)."""
    zero: str = ""
    """The zero in force, one compact line (``zero x +0.0003 y -0.0001 (5 readings)``)."""

    @classmethod
    def from_live(
        cls, state: RunnerState, analysis: Any, header: Mapping[str, Any]
    ) -> DashboardView:
        """From the runner's snapshot, its live analysis (None before the first cycle) and the
        session header's fields (robot, channels, unit, resolution)."""
        channels = tuple(header.get("channels") or ()) or tuple(
            (analysis.channels if analysis is not None else {}).keys()
        )
        accepted = [record for record in state.cycles if record.rejected is None]
        last_cycle = state.last_cycle
        # A rejected cycle is shown as rejected: no value, and no out-of-spec flag beside it.
        last = (
            dict(last_cycle.values)
            if last_cycle is not None and last_cycle.rejected is None
            else {}
        )
        # A capture action always stands at a step; "" only keeps the line whole if not.
        step_title = state.current.step.title if state.current is not None else ""
        counted = state.progress
        rejected = len(state.cycles) - len(accepted)
        if state.action.kind == "capture" and counted is not None:
            ready = counted.complete
            progress = f"{counted.noun} {counted.done} of {counted.target}"
            if not counted.enough:
                progress += f" (at least {counted.minimum})"
            prompt = (state.action.prompt or step_title) + (
                "  The station captures each return of the robot."
                if state.action.paced_by_devices
                else "  Press Space to capture."
            )
        elif state.action.kind == "capture":
            ready = False
            progress = f"{len(accepted)} captured"
            prompt = f"{step_title}: {' '.join(state.action.prompt.split())}"
            prompt = prompt.rstrip() + "  Press Space to capture."
        else:
            ready = True
            progress = f"{len(accepted)} captured"
            prompt = ""
        if state.placement is not None and state.placements:
            progress = f"placement {state.placement} of {state.placements}, {progress}"
        if ready:
            # After the last step of a repeated block (relative accuracy) nothing counts any
            # more: what was asked for were placements, not cycles.
            placed = last_cycle is not None and last_cycle.placement is not None
            noun = counted.noun if counted is not None else "placement" if placed else "cycle"
            prompt = f"Every {noun} asked for is captured. Press f to finish and see the verdict."
        if rejected:
            progress += f", {rejected} rejected"
        if last_cycle is not None and last_cycle.rejected is not None:
            # The reading column shows no rejected value as if it were the last reading.
            progress += f" (cycle {last_cycle.cycle} rejected)"
        if state.status == "paused":
            progress += "  PAUSED"
            prompt = "Captures are paused. Press p to continue."
        message = state.messages[-1] if state.messages else None
        return cls(
            title=session_title(header),
            progress=progress,
            prompt=prompt,
            channels=channels,
            analyses=dict(analysis.channels) if analysis is not None else {},
            last=last,
            cycle_numbers=tuple(record.cycle for record in accepted),
            ports=tuple(state.instruments),
            message=message,
            resolution=header.get("resolution"),
            unit=str(header.get("unit", "")),
            ready_to_finish=ready,
            flags=out_of_spec_flags(last, header),
            alarms=tuple(state.alarm_list),
            no_alarms=no_alarms_words(header, len(accepted)),
            zero=zero_line(state.zero, header.get("resolution")),
        )


def zero_line(zero: Mapping[str, Any], resolution: float | None) -> str:
    """The zero in force in one compact line: ``zero x +0.00030 y -0.00010 z +0.00020 (5
    readings)`` (at the table's decimals); '' before any zero."""
    if not zero:
        return ""
    parts = [
        f"{channel} device"
        if spec.get("method") == "device"
        else f"{channel} {format_figure(spec.get('offset'), resolution)}"
        for channel, spec in zero.items()
    ]
    counts = {spec.get("n") for spec in zero.values()}
    n = counts.pop() if len(counts) == 1 else None
    readings = f" ({n} readings)" if isinstance(n, int) and n > 1 else ""
    return f"zero {' '.join(parts)}{readings}"


class DashboardScreen(Screen[None]):
    """Live capture (``live=True``) or a saved session read-only (``view=...``)."""

    BINDINGS = [
        Binding("space", "capture", "Capture"),
        # Shown only once the cycles step may close (it has its minimum): a cycles step inside
        # a repeat block (one joint's returns) is followed by the next joint's steps.
        Binding("g", "go_on", "Go on"),
        Binding("r", "reject", "Reject"),
        Binding("n", "note", "Note"),
        Binding("p", "pause", "Pause"),
        Binding("f", "finish", "Finish"),
        Binding("a", "alarms", "Alarms"),
        Binding("m", "full_text", "Messages"),
        Binding("tab", "next_axis", "Axis", key_display="xyz"),
        Binding("x", "axis('x')", "x", show=False),
        Binding("y", "axis('y')", "y", show=False),
        Binding("z", "axis('z')", "z", show=False),
        Binding("f1", "help", "Help"),
        Binding("question_mark", "help", "Help", show=False),
        Binding("q", "leave", "Leave"),
        Binding("escape", "back", "Back", show=False),
    ]
    LIVE_ONLY = frozenset({"capture", "reject", "note", "pause", "finish"})

    app: StationApp

    def __init__(self, *, live: bool, view: DashboardView | None = None) -> None:
        super().__init__()
        self.live = live
        self.view = view
        self.selected = ""
        self.capturing = False
        self._action_busy = False
        self._shown_message: Any = None
        self._drawn_once = False
        self._may_go_on = False

    @property
    def busy(self) -> bool:
        """True while a capture or another runner call is under way."""
        return self.capturing or self._action_busy

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Capture keys only when live; Escape only when reviewing."""
        if action in self.LIVE_ONLY:
            return self.live
        if action == "back":
            return not self.live
        if action == "go_on":
            return self.live and self._may_go_on
        return True

    def compose(self) -> ComposeResult:
        """Title and progress, prompt, statistics, charts, alarms, instruments, message."""
        yield Static(id="dash-title")
        yield Static(id="dash-prompt")
        yield StatsPanel(id="dash-stats")
        with Horizontal(id="dash-charts"):
            yield HistogramView(id="dash-histogram")
            yield ControlChartView(id="dash-chart")
        yield AlarmLog(id="dash-alarms")
        yield InstrumentStatus(id="dash-instruments")
        yield Static(id="dash-message")
        yield KeyFooter()

    def on_mount(self) -> None:
        """Draw the newest state (live) or the saved session (review)."""
        if self.live:
            state = self.app.current_state()
            if state is not None:
                self.show_state(state)
        elif self.view is not None:
            self.draw(self.view)

    # -- drawing --------------------------------------------------------------------------

    def show_state(self, state: RunnerState) -> None:
        """Redraw from a runner snapshot and the live analysis (UI thread)."""
        if not self.query(HistogramView):
            return  # its widgets are being taken down (the screen or the app is leaving)
        may_go_on = state.action.kind == "capture" and state.action.may_confirm
        if may_go_on != self._may_go_on:
            self._may_go_on = may_go_on
            self.refresh_bindings()
        self.draw(DashboardView.from_live(state, self.app.live_analysis(), self.app.session_header))

    def show_last_reading(self, state: RunnerState) -> None:
        """A reading set is on disk: paint the counters, the prompt and the last values at
        once (cheap text); the charts follow with the next coalesced redraw."""
        if not self.live or not self.is_mounted:
            return
        view = DashboardView.from_live(state, self.app.live_analysis(), self.app.session_header)
        # Repainted in place: laying the whole screen out again costs more than the paint
        # itself, and the sizes stay (a prompt that wraps differently is laid out by the
        # redraw that follows with the live analysis).
        self._draw_text(view, layout=False)

    def _draw_text(self, view: DashboardView, *, layout: bool = True) -> None:
        """The title with the counters, the prompt and the statistics (the last values);
        ``layout=False``: repaint them without laying the screen out again."""
        self.view = view
        if view.channels and self.selected not in view.channels:
            self.selected = view.channels[0]
        title = shown(view.title, style="bold", limit=200)
        title.append(f"   {view.progress}", style="bold cyan")
        # The title is one line high: its size never changes.
        self.query_one("#dash-title", Static).update(title, layout=False)
        self.query_one("#dash-prompt", Static).update(
            shown(view.prompt, style="bold green" if view.ready_to_finish else ""),
            layout=layout,
        )
        self.query_one(StatsPanel).show(
            StatsRows(
                channels=view.channels,
                analyses=view.analyses,
                last=view.last,
                resolution=view.resolution,
                unit=view.unit,
                selected=self.selected,
                flags=view.flags,
            ),
            layout=layout,
        )

    def draw(self, view: DashboardView) -> None:
        """Put ``view`` on screen."""
        self._draw_text(view)
        selected = view.analyses.get(self.selected)
        self.query_one(HistogramView).show(histogram_data(selected, view.resolution))
        self.query_one(ControlChartView).show(
            chart_data(selected, list(view.cycle_numbers), view.resolution)
        )
        log = self.query_one(AlarmLog)
        if view.alarms is not None:
            log.show(
                recorded_alarm_lines(view.alarms),
                open_count=sum(not alarm.acknowledged for alarm in view.alarms),
                more="a: the full list",
                empty=view.no_alarms,
            )
        else:
            log.show(alarm_lines(view.analyses, view.cycle_numbers))
        instruments = self.query_one(InstrumentStatus)
        if self.live:
            instruments.show(view.ports, view.zero, width=self.app.size.width - 2)
        else:
            instruments.update(Text("recorded session (read-only)", style="dim"))
        # The message line says the newest news: a capture's outcome (said by this screen) or
        # a new message of the runner (a reconnect, a refused set); an old one is not repeated.
        if view.message is not None and view.message is not self._shown_message:
            self._shown_message = view.message
            if self._drawn_once:
                style = {"error": "bold red", "warning": "yellow"}.get(view.message.level, "green")
                self._say(view.message.text, style)
        self._drawn_once = True

    def on_screen_resume(self) -> None:
        """Back from the alarm list or a dialog: draw the newest state."""
        if self.live and self.is_mounted:
            state = self.app.current_state()
            if state is not None:
                self.show_state(state)

    def _say(self, text: str, style: str = "") -> None:
        self.query_one("#dash-message", Static).update(shown(text, style=style))

    def _redraw(self) -> None:
        if self.view is not None:
            self.draw(self.view)

    # -- axis -----------------------------------------------------------------------------

    def action_axis(self, channel: str) -> None:
        """Show this axis in the charts (x, y, z)."""
        if self.view is not None and channel in self.view.channels:
            self.selected = channel
            self._redraw()

    def action_next_axis(self) -> None:
        """The next axis in the charts."""
        if self.view is None or not self.view.channels:
            return
        channels = list(self.view.channels)
        index = channels.index(self.selected) if self.selected in channels else -1
        self.selected = channels[(index + 1) % len(channels)]
        self._redraw()

    # -- capture --------------------------------------------------------------------------

    def action_capture(self) -> None:
        """Take one cycle's readings (a thread worker; the screen stays live meanwhile)."""
        if not self.live or self.capturing or self.app.runner is None:
            return
        self.capturing = True
        self._say("Capturing ...", "yellow")
        self._capture(self.app.config.capture_timeout)

    @work(thread=True, group="capture", exit_on_error=False)
    def _capture(self, timeout: float) -> None:
        """Thread worker: block on the gauges here, never on the UI thread."""
        runner = self.app.runner
        try:
            outcome = runner.capture(timeout) if runner is not None else None
            self.post_message(CaptureFinished(outcome=outcome))
        except StationError as error:
            self.post_message(CaptureFinished(error=explained(error)))

    def on_capture_finished(self, message: CaptureFinished) -> None:
        """Say what happened; the drawing follows the runner's notice."""
        self.capturing = False
        if message.error:
            self._say(message.error, "bold red")
        elif message.outcome is not None:
            outcome = message.outcome
            # A recorded cycle in the table's own format.
            said = outcome.cycle.line() if outcome.cycle is not None else None
            self._say(said or outcome.message, "green" if outcome.recorded else "bold red")

    def _in_thread(self, call: Callable[[], Any]) -> None:
        if self._action_busy:
            return
        self._action_busy = True
        self._runner_action(call)

    @work(thread=True, group="runner-action", exit_on_error=False)
    def _runner_action(self, call: Callable[[], Any]) -> None:
        """Thread worker for the runner's quick calls (each fsyncs an event)."""
        try:
            call()
        except StationError as error:
            self.app.call_from_thread(self._say, explained(error), "bold red")
        except Exception as error:  # a bug: shown, never swallowed by the worker
            self.app.call_from_thread(self._say, f"internal error: {error!r}", "bold red")
            raise
        finally:
            self.app.call_from_thread(self._action_done)

    def _action_done(self) -> None:
        self._action_busy = False

    def action_reject(self, reason: str | None = None) -> None:
        """Reject the last cycle, with a reason (the readings stay in the file). The cycle is
        named when the key is pressed: the one the dialog names is the one rejected, even if
        more cycles arrive while the reason is typed."""
        state = self.app.current_state()
        runner = self.app.runner
        if not self.live or runner is None or state is None:
            return
        last = state.last_cycle
        if last is None or last.rejected is not None:
            self._say("There is no captured cycle to reject.", "yellow")
            return
        cycle = last.cycle
        if reason is not None:
            self._in_thread(lambda: runner.reject(cycle, reason))
            return

        def reject(text: str | None) -> None:
            if text:
                self._in_thread(lambda: runner.reject(cycle, text))

        self.app.push_screen(
            TextPrompt(
                f"Reject cycle {cycle}",
                "Why? (e.g. the robot was bumped, the cube slipped). The readings stay in "
                "the file, marked rejected, and are left out of the analysis.",
            ),
            callback=reject,
        )

    def action_note(self) -> None:
        """A free-text note in the session file."""
        runner = self.app.runner
        if not self.live or runner is None:
            return

        def save(text: str | None) -> None:
            if text:
                self._in_thread(lambda: runner.note(text))

        self.app.push_screen(TextPrompt("Note", "What should the session file say?"), callback=save)

    def action_pause(self) -> None:
        """Pause captures (e.g. while the cell is entered), or continue."""
        runner = self.app.runner
        state = self.app.current_state()
        if not self.live or runner is None or state is None:
            return
        if state.status == "paused":
            self._in_thread(runner.resume_capture)
        else:
            self._in_thread(runner.pause)

    def action_go_on(self) -> None:
        """Close the cycles step (it has its minimum) and go on to the next step."""
        runner = self.app.runner
        if not self.live or self.busy or runner is None or not self._may_go_on:
            return
        self._in_thread(runner.confirm)

    def action_finish(self, force: bool = False) -> None:
        """End the captures and show the verdict (asks when fewer than the minimum cycles)."""
        state = self.app.current_state()
        if not self.live or state is None or self.capturing:
            return
        counted = state.progress
        if counted is not None and not counted.enough and not force:

            def finish(sure: bool | None) -> None:
                if sure:
                    self.action_finish(force=True)

            self.app.push_screen(
                ConfirmScreen(
                    f"Finish with {counted.done} {counted.noun}s?",
                    f"The report asks for {counted.minimum} to {counted.target}; the "
                    "verdict is weaker with fewer.",
                ),
                callback=finish,
            )
            return
        try:
            self.app.finish_session()
        except StationError as error:
            self._say(explained(error), "bold red")

    def action_alarms(self) -> None:
        """The alarm list: every alarm in full, acknowledged with a cause (live) or read."""
        from station.tui.screens.alarms import AlarmsScreen  # deferred: loads when shown

        view = self.view
        alarms = tuple(view.alarms or ()) if view is not None else ()
        runner = self.app.runner if self.live else None
        if runner is None:
            self.app.push_screen(AlarmsScreen(alarms, read_only=True))
            return

        def acknowledge(request: Any) -> None:
            runner.acknowledge(
                request.alarm, request.cause, text=request.text, action=request.action
            )

        self.app.push_screen(
            AlarmsScreen(alarms, runner.setup.procedure.causes, acknowledge, in_thread=True)
        )

    def action_help(self) -> None:
        """The keys."""

        self.app.push_screen(HelpScreen())

    def action_full_text(self) -> None:
        """``m``: the newest message and every alarm, in full (the lines here cut them)."""

        view = self.view
        lines: list[str] = []
        if view is not None:
            if view.message is not None:
                lines.append(f"Newest message: {view.message.text}")
            # The same alarms, in the same words, as the log shows them cut to a line.
            if view.alarms is not None:
                lines.extend(recorded_alarm_lines(view.alarms))
            else:
                lines.extend(alarm_lines(view.analyses, view.cycle_numbers))
        self.app.push_screen(FullTextScreen("Messages and alarms in full", lines))

    def action_back(self) -> None:
        """Reviewing: back to the summary."""
        if not self.live:
            self.app.pop_screen()

    def action_leave(self) -> None:
        """Live: leave the session resumable; reviewing: back."""
        if not self.live:
            self.app.pop_screen()
            return

        def leave(sure: bool | None) -> None:
            if sure:
                self.app.interrupt_session("operator left")
                self.app.go_home()

        self.app.push_screen(
            ConfirmScreen(
                "Leave this session?",
                "It is kept as interrupted; choose Resume on the home screen to continue.",
            ),
            callback=leave,
        )


def out_of_spec_flags(last: Mapping[str, float], header: Mapping[str, Any]) -> dict[str, str]:
    """Channel -> "above" / "below" for each last reading beyond the session's specification
    limits (flagged the moment the reading is on disk, before the analysis catches up)."""
    from station.session.header import header_limits  # deferred: it loads numpy

    flags: dict[str, str] = {}
    for channel, limits in header_limits(header).items():
        value = last.get(channel)
        if value is None:
            continue
        if limits.usl is not None and value > limits.usl:
            flags[channel] = "above"
        elif limits.lsl is not None and value < limits.lsl:
            flags[channel] = "below"
    return flags


def no_alarms_words(header: Mapping[str, Any], accepted: int) -> str:
    """The alarm log's words while there is no alarm: live alarms are judged against control
    limits that freeze after the header's ``freeze_after`` cycles (or a baseline's), so before
    that none can come, and the operator is told when they will."""
    if header.get("baseline"):
        return "alarms: none (judged against the baseline's control limits)"
    freeze = header.get("freeze_after")
    if isinstance(freeze, int) and accepted < freeze:
        return (
            f"alarms: none yet: live limits freeze after {freeze} cycles, earlier ones judged then"
        )
    return "alarms: none"


def session_title(header: Mapping[str, Any]) -> str:
    """``robot R1 · repeatability`` from a session header's fields."""
    procedure = header.get("procedure")
    name = procedure.get("id", "") if isinstance(procedure, Mapping) else str(procedure or "")
    return f"robot {shown_line(header.get('robot', '?'), limit=60)} · {shown_line(name, limit=60)}"


def review_view(
    title: str,
    channels: Sequence[str],
    analysis: Any,
    cycle_numbers: Sequence[int],
    *,
    resolution: float | None,
    unit: str,
    progress: str,
    alarms: Sequence[Any] | None = None,
) -> DashboardView:
    """The dashboard of a saved session (read-only); ``alarms``: its recorded alarms."""
    return DashboardView(
        title=title,
        progress=progress,
        prompt="Recorded session (read-only). x, y, z or Tab: axis · Escape: back.",
        channels=tuple(channels),
        analyses=dict(analysis.channels) if analysis is not None else {},
        cycle_numbers=tuple(cycle_numbers),
        resolution=resolution,
        unit=unit,
        alarms=tuple(alarms) if alarms else None,
    )
