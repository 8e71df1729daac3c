"""The checklist: the procedure's steps on the left with marks, the current step on the right.

Enter does the step: confirms a check, zeroes the indicators at a zero step, saves the typed
values at an input step. The runner decides what a step means and writes its event; when a
capture step becomes current, the app switches to the dashboard.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rich.text import Text
from textual import events, work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.screen import Screen
from textual.widgets import Footer, Label, Static

from station.errors import StationError
from station.text import format_figure
from station.tui.remedies import explained
from station.tui.screens.dialogs import ConfirmScreen, HelpScreen, TextPrompt
from station.tui.text import shown, shown_line
from station.tui.widgets.fields import (
    FIELD_MOVES,
    FieldInput,
    after_fields_take_their_keys,
    focused_field,
    mark_focused_row,
    move_between_fields,
)
from station.tui.widgets.step_list import StepList

if TYPE_CHECKING:
    from station.run import Action, RunnerState, StepView
    from station.tui.app import StationApp

ZERO_WAIT = 5.0
"""Seconds a zero waits for the gauges (a port that is down, a gauge that moves)."""
ARRIVAL_ZERO_WAIT = 30.0
"""Under the arrival trigger, seconds a zero waits for the robot on its loop to come to rest
at the fixture: a round trip or several."""

ARRIVAL_ZERO_DOES = (
    "Press Enter: the indicators are zeroed when the robot next comes to rest at the fixture "
    "(seen coming back from away; never at the plungers' stop)."
)
ENTER_DOES = {
    "confirm": "Press Enter when this is done.",
    # Every procedure's zero (a robot at a fixture, an indicator on a surface plate): its
    # step text says where; this says only what Enter does.
    "zero": "Keep everything still, then press Enter to zero the indicators.",
    "input": "Type each value: Enter or Tab goes to the next field, Enter in the last one "
    "saves them.",
}


class ChecklistScreen(Screen[None]):
    """One step at a time, with the whole list in view."""

    BINDINGS = [
        Binding("enter", "confirm", "Confirm step"),
        Binding("space", "confirm", "Confirm step", show=False),
        Binding("n", "note", "Note"),
        Binding("f1", "help", "Help"),
        Binding("q", "leave", "Leave (resumable)"),
        *FIELD_MOVES,
        # In a step's fields (then "Confirm step" is not the footer's Enter).
        Binding("enter", "field_key('enter')", "Next field, last saves", priority=True),
    ]

    app: StationApp

    def __init__(self, just_captured: Any = None) -> None:
        super().__init__()
        self._just_captured = just_captured
        """The reading set the dashboard captured before handing over (a placement's error):
        shown until the next step is done, so Space never jumps past what it recorded."""
        self._shown_step: tuple[int, str] | None = None
        self.busy = False
        """True while the runner carries out a step (keys for another step wait for it)."""

    def compose(self) -> ComposeResult:
        """Steps left, the current step right."""
        yield Static(id="run-title")
        with Horizontal(id="checklist"):
            with VerticalScroll(id="steps-box"):
                yield StepList(id="steps")
            # Scrolls, so the fields of an input step (the pendant's X, Y, Z) are brought into
            # view as they take the focus at 80×24.
            with VerticalScroll(id="step-panel"):
                yield Static(id="step-title")
                yield Static(id="step-text")
                # What Enter does and why a value was refused stay in view above the fields.
                yield Static(id="step-action")
                yield Static(id="step-message")
                yield Static(id="step-captured")
                yield Vertical(id="step-inputs")
        yield Footer()

    def on_mount(self) -> None:
        """Draw the runner's current state."""
        state = self.app.current_state()
        if state is not None:
            self.show_state(state)
        if self._just_captured is not None:
            self.query_one("#step-captured", Static).update(
                captured_text(self._just_captured, self.app.session_header)
            )

    def show_state(self, state: RunnerState) -> None:
        """Redraw from a runner snapshot (UI thread)."""
        titles = self.query("#run-title")
        if not titles:
            return  # its widgets are being taken down (the screen is leaving): nothing to draw
        titles.first(Static).update(_run_title(state))
        self.query_one(StepList).show(state.steps)
        current = state.current
        key = (current.index, current.id) if current is not None else None
        if key != self._shown_step:
            if self._shown_step is not None:
                self.query_one("#step-captured", Static).update("")
            self._shown_step = key
            self._show_step(current, state.placements, state.action)
        message = state.messages[-1] if state.messages else None
        if message is not None:
            style = {"error": "bold red", "warning": "yellow"}.get(message.level, "green")
            line = self.query_one("#step-message", Static)
            is_path = message.text == f"Session file {state.path}."
            if is_path:
                # A path has no spaces to wrap at: the folder on one line, cut with an
                # ellipsis rather than broken mid-word (the title above names the file).
                text = shown("Session file in ", style=style)
                text.append(shown_line(f"{state.path.parent}/", limit=None), style=style)
            else:
                text = shown(message.text, style=style)
            line.styles.text_wrap = "nowrap" if is_path else "wrap"
            line.styles.text_overflow = "ellipsis" if is_path else "fold"
            line.update(text)

    def _show_step(
        self, view: StepView | None, placements: int | None = None, todo: Action | None = None
    ) -> None:
        inputs = self.query_one("#step-inputs", Vertical)
        inputs.remove_children()
        if view is None:
            self.query_one("#step-title", Static).update("Every step is done.")
            self.query_one("#step-text", Static).update("")
            self.query_one("#step-action", Static).update("")
            return
        step = view.step
        placement = ""
        if view.placement:
            of = f" of {placements}" if placements else ""
            placement = f" (placement {view.placement}{of})"
        self.query_one("#step-title", Static).update(
            shown(f"Step {view.index + 1}: {shown_line(step.title)}{placement}", style="bold")
        )
        text = shown(" ".join(step.text.split()))
        asks = todo.kind if todo is not None else "confirm"
        display = self._demo_display(view) if asks == "input" else None
        if display is not None:
            text.append(f"\n\n{display.label}: ", style="bold")
            text.append(shown_line(display.text), style="bold reverse")
        self.query_one("#step-text", Static).update(text)
        action = ENTER_DOES.get(asks, "Press Enter to continue.")
        runner = self.app.runner
        if asks == "zero" and runner is not None and runner.setup.trigger == "arrival":
            action = ARRIVAL_ZERO_DOES
        if display is not None:
            action += f" (Demo: {display.hint}.)"
        elif self.app.config.demo is not None and asks != "input":
            action += " (Demo: the robot and the gauges are simulated; just press Enter.)"
        self.query_one("#step-action", Static).update(Text(action, style="bold cyan"))
        if todo is not None and todo.kind == "input":
            rows = []
            for field in todo.fields:
                unit = f" ({field.unit})" if field.unit else ""
                rows.append(
                    Horizontal(
                        Label(shown(f"{field.label}{unit}"), classes="field-label"),
                        FieldInput(
                            compact=True,
                            id=f"input-{field.name}",
                            type="number" if field.type == "number" else "text",
                        ),
                        classes="field-row",
                    )
                )
            self._mount_fields(inputs, rows)

    @work(group="step-fields", exclusive=True, exit_on_error=False)
    async def _mount_fields(self, inputs: Vertical, rows: list[Horizontal]) -> None:
        """Mount an input step's rows and, once they (and the fields inside them) are in,
        give the first field the focus: waiting for the mount itself, never a count of
        refreshes, so a loaded terminal cannot leave the focus on the step list where the
        first typed figures go nowhere."""
        await inputs.mount_all(rows)
        self._focus_first_input()

    def _demo_display(self, view: StepView) -> Any:
        """What the demo's simulated set-up shows at this step's placement (the teach
        pendant's X, Y, Z; a master's size), or None off the demo."""
        fixture = self.app.demo_fixture
        if fixture is None:
            return None
        return fixture.shows(view.placement, str(self.app.session_header.get("unit") or "in"))

    def on_descendant_focus(self, event: events.DescendantFocus) -> None:
        """Mark the focused field's row (its label in reverse video)."""
        mark_focused_row(self, event.widget)

    def _focus_first_input(self) -> None:
        fields = self._step_fields()
        if not fields or self.focused in fields:
            return  # the step moved on, or the operator is already in a field
        # The screen's own set_focus, now (a widget's focus() would wait behind queued keys).
        self.set_focus(fields[0])
        # All the fields in view at once (at 80×24 they sit below the step's text).
        self.query_one("#step-inputs").scroll_visible(animate=False)

    # -- actions --------------------------------------------------------------------------

    def _step_fields(self) -> list[FieldInput]:
        return list(self.query("#step-inputs FieldInput").results(FieldInput))

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """The field keys only while a step's field has the focus (elsewhere Enter confirms
        the step)."""
        if action == "field_key":
            return self.focused in self._step_fields()
        return True

    def action_field_key(self, key: str) -> None:
        """In a step's fields, at once (before the next key is handed on): Tab and Shift+Tab
        go round the fields, Enter goes to the next one and saves after the last, once every
        field has taken the keys typed before it."""
        fields = self._step_fields()
        field = focused_field(self)
        if field not in fields:
            return
        if key == "previous":
            move_between_fields(self, fields, -1)
        elif key == "next" or fields.index(field) + 1 < len(fields):
            move_between_fields(self, fields, 1)
        else:
            after_fields_take_their_keys(fields, self.action_confirm)

    def action_confirm(self) -> None:
        """Do the current step through the runner (in a worker: zeroing talks to the gauges)."""
        runner = self.app.runner
        state = self.app.current_state()
        if runner is None or state is None or state.current is None or self.busy:
            return
        kind = state.action.kind
        if kind == "input":
            values = {
                str(field.id).removeprefix("input-"): str(field.value)
                for field in self._step_fields()
            }
            self._do(lambda: runner.submit_input(values))
        elif kind == "zero":
            message = "Zeroing ..."
            timeout = ZERO_WAIT
            if runner.setup.trigger == "arrival":
                # The robot runs its loop: the gauges wait for it to come to rest at the
                # fixture (never at the plungers' stop), so give it a round trip or two.
                message = "Zeroing once the robot is at rest at the fixture ..."
                timeout = ARRIVAL_ZERO_WAIT
            self.query_one("#step-message", Static).update(Text(message, style="yellow"))
            self._do(lambda: runner.zero(timeout=timeout))
        else:
            self._do(runner.confirm)

    def _do(self, call: Callable[[], Any]) -> None:
        self.busy = True
        self._run_in_thread(call)

    @work(thread=True, group="runner-action", exit_on_error=False)
    def _run_in_thread(self, call: Callable[[], Any]) -> None:
        """Thread worker: the runner's call; a refusal comes back as a sentence."""
        try:
            call()
        except StationError as error:
            self.app.call_from_thread(self._refused, explained(error))
        finally:
            self.app.call_from_thread(self._done)

    def _done(self) -> None:
        self.busy = False

    def _refused(self, sentence: str) -> None:
        self.query_one("#step-message", Static).update(shown(sentence, style="bold red"))

    def action_note(self) -> None:
        """A free-text note in the session file."""

        def save(text: str | None) -> None:
            if text and self.app.runner is not None:
                self._do(lambda: self.app.runner.note(text))  # type: ignore[union-attr]

        self.app.push_screen(TextPrompt("Note", "What should the session file say?"), callback=save)

    def action_help(self) -> None:
        """The keys."""

        self.app.push_screen(HelpScreen())

    def action_leave(self) -> None:
        """Leave the session unfinished (it is marked interrupted and offered for resume)."""

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


def captured_text(record: Any, header: dict[str, Any]) -> Text:
    """``Captured (set 3): x +0.00030  y -0.00012  z +0.00020 in``: the set just recorded, as
    the session file holds it (after the zero) in the one number format."""

    resolution = header.get("resolution")
    unit = str(header.get("unit") or "")
    text = Text(f"Captured (set {record.cycle}): ", style="bold")
    values = "  ".join(
        f"{shown_line(channel, limit=20)} {format_figure(value, resolution)}"
        for channel, value in record.values.items()
    )
    text.append(f"{values} {unit}".rstrip(), style="bold")
    return text


def _run_title(state: RunnerState) -> Text:
    """The session file's name, and the status when it is not plainly running."""
    text = shown(f"Session {shown_line(state.path.name)}", style="bold")
    if state.status != "running":
        text.append(f"  [{state.status.upper()}]", style="bold yellow")
    return text
