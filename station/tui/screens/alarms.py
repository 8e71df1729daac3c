"""The alarm list: every alarm of the session in full, scrollable, and acknowledging one with a
cause from the procedure's list.

The screen holds no session: it shows the :class:`~station.session.alarms.RecordedAlarm` list
it is given and hands each acknowledgement to the ``on_acknowledge`` callback as an
:class:`~station.session.alarms.AckRequest` (the engine writes the ``ack`` event). A callback
that refuses (a StationError) leaves the alarm unacknowledged and its sentence is shown.
:meth:`AlarmsScreen.set_alarms` replaces the list (new alarms, acks from the journal); on the
live dashboard the app hands the screen each new runner state (:meth:`AlarmsScreen.show_state`),
and ``in_thread`` runs the callback (the engine's fsynced write) off the UI thread.

Keys: ↑ ↓ choose, ``a`` acknowledge, Escape back. In the dialog: ↑ ↓ and Enter pick the cause,
then type what it was (needed for "other") and the corrective action; Enter on the action saves.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen, Screen
from textual.widgets import Input, ListItem, ListView, OptionList, Static

from station.errors import StationError
from station.procedures import DEFAULT_CAUSES, OTHER_CAUSE
from station.session.alarms import (
    Acknowledgement,
    AckRequest,
    RecordedAlarm,
    ack_fields,
    plain,
)
from station.tui.widgets.fields import (
    FIELD_KEYS,
    FieldInput,
    after_fields_take_their_keys,
    field_key_active,
    focused_field,
)
from station.tui.widgets.key_footer import KeyFooter


def alarm_text(alarm: RecordedAlarm, *, hint: bool = True) -> Text:
    """The full text of one alarm (no markup: every part is plain text): where, the rule in
    words, live or retrospective, the sentence, and its acknowledgement."""
    where = "live" if alarm.live else "retrospective"
    text = Text()
    text.append(
        f"#{alarm.seq} {plain(alarm.channel)} · {plain(alarm.rule_name)} [{where}]\n", style="bold"
    )
    text.append(plain(alarm.text))
    if alarm.acks:
        text.append(f"\nacknowledged: {plain(alarm.acks[-1].describe())}", style="green")
    else:
        text.append("\nnot acknowledged" + (": press a" if hint else ""), style="yellow")
    return text


class AlarmItem(ListItem):
    """One alarm of the list."""

    def __init__(self, alarm: RecordedAlarm, *, hint: bool = True) -> None:
        super().__init__(Static(alarm_text(alarm, hint=hint), classes="alarm-text"))
        self.alarm = alarm


class AckDialog(ModalScreen[AckRequest | None]):
    """Acknowledge one alarm: the cause (from the procedure's list), what it was, and the
    corrective action. Enter on the action saves; Escape cancels."""

    BINDINGS = [Binding("escape", "cancel", "Cancel"), *FIELD_KEYS]
    DEFAULT_CSS = """
    AckDialog { align: center middle; }
    AckDialog > Vertical { width: 76; max-width: 100%; height: auto; max-height: 100%;
                           border: round $accent; padding: 0 1; background: $surface; }
    AckDialog OptionList { height: auto; max-height: 8; }
    AckDialog #ack-error { color: $error; }
    """

    def __init__(self, alarm: RecordedAlarm, causes: Sequence[str]) -> None:
        super().__init__()
        self.alarm = alarm
        self.causes = tuple(causes)

    def compose(self) -> ComposeResult:
        """The alarm, the causes, the two texts, the error line."""
        with Vertical():
            yield Static(Text(f"Acknowledge alarm #{self.alarm.seq}", style="bold"))
            yield Static(Text(plain(self.alarm.text)))
            yield Static("Cause:")
            yield OptionList(*[Text(plain(cause)) for cause in self.causes], id="ack-cause")
            yield FieldInput(placeholder="what it was (needed for 'other')", id="ack-text")
            yield FieldInput(placeholder="corrective action (optional)", id="ack-action")
            yield Static("", id="ack-error")
            yield Static("Enter on the action saves · Escape cancels", classes="dim")
        yield KeyFooter()

    def on_mount(self) -> None:
        """Start on the first cause."""
        causes = self.query_one("#ack-cause", OptionList)
        causes.highlighted = 0
        causes.focus()

    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        """A cause picked: type what it was next."""
        event.stop()
        self.query_one("#ack-text", Input).focus()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """The field keys only while a text has the focus (in the cause list, Enter picks the
        cause)."""
        return field_key_active(self, action)

    def action_field_key(self, key: str) -> None:
        """In a text, at once (before the next key is handed on): Enter on the text goes to
        the action, Enter on the action saves once both have taken the keys typed before it;
        Tab and Shift+Tab move on and back."""
        field = focused_field(self)
        if key == "previous":
            self.focus_previous()
        elif key == "next" or (field is not None and field.id == "ack-text"):
            self.focus_next()
        else:
            texts = list(self.query(FieldInput).results(FieldInput))
            after_fields_take_their_keys(texts, self.action_save)

    def action_save(self) -> None:
        """Check the acknowledgement and return it, or say what is missing."""
        index = self.query_one("#ack-cause", OptionList).highlighted
        error = self.query_one("#ack-error", Static)
        if index is None:
            error.update("Pick a cause first.")
            return
        request = AckRequest(
            self.alarm.seq,
            self.causes[index],
            self.query_one("#ack-text", Input).value.strip(),
            self.query_one("#ack-action", Input).value.strip(),
        )
        try:
            ack_fields(request.alarm, request.cause, causes=self.causes, text=request.text)
        except StationError as problem:
            error.update(Text(problem.message))
            if request.cause == OTHER_CAUSE:
                self.query_one("#ack-text", Input).focus()
            return
        self.dismiss(request)

    def action_cancel(self) -> None:
        """Close without acknowledging."""
        self.dismiss(None)


class AlarmsScreen(Screen[None]):
    """The session's alarms in full (scrollable) with their acknowledgements."""

    BINDINGS = [
        Binding("a", "acknowledge", "Acknowledge"),
        Binding("escape", "close", "Back"),
    ]
    DEFAULT_CSS = """
    AlarmsScreen #alarm-list { height: 1fr; }
    AlarmsScreen AlarmItem { padding: 0 1; border-bottom: solid $panel; height: auto; }
    AlarmsScreen .alarm-text { width: 100%; }
    """

    def __init__(
        self,
        alarms: Sequence[RecordedAlarm],
        causes: Sequence[str] = DEFAULT_CAUSES,
        on_acknowledge: Callable[[AckRequest], None] | None = None,
        *,
        read_only: bool = False,
        in_thread: bool = False,
    ) -> None:
        super().__init__()
        self.alarms: list[RecordedAlarm] = list(alarms)
        self.causes = tuple(causes)
        self.on_acknowledge = on_acknowledge
        self.read_only = read_only
        """A recorded session: the alarms are shown, nothing is acknowledged."""
        self.in_thread = in_thread
        self._sent: tuple[RecordedAlarm, ...] | None = None

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """No acknowledging in a recorded session."""
        if action == "acknowledge":
            return not self.read_only
        return True

    def compose(self) -> ComposeResult:
        """Title, the list, the keys."""
        yield Static(self._title(), id="alarm-title")
        yield ListView(
            *[AlarmItem(alarm, hint=not self.read_only) for alarm in self.alarms], id="alarm-list"
        )
        yield KeyFooter()

    def _title(self) -> Text:
        open_count = sum(not alarm.acknowledged for alarm in self.alarms)
        return Text(
            f"Alarms: {len(self.alarms)}, {open_count} not acknowledged"
            if self.alarms
            else "Alarms: none",
            style="bold",
        )

    def on_mount(self) -> None:
        """Focus the list."""
        self.query_one(ListView).focus()

    def show_state(self, state: object) -> None:
        """A new runner state: show its alarms when they changed (new ones, acknowledgements)."""
        alarms = tuple(getattr(state, "alarm_list", ()) or ())
        if alarms != self._sent:
            self._sent = alarms
            if list(alarms) != self.alarms:
                self.set_alarms(alarms)

    def set_alarms(self, alarms: Sequence[RecordedAlarm]) -> None:
        """Show this list instead (new alarms, acknowledgements read back from the journal)."""
        self.alarms = list(alarms)
        view = self.query_one(ListView)
        index = view.index
        view.clear()
        view.extend(AlarmItem(alarm, hint=not self.read_only) for alarm in self.alarms)
        if self.alarms:
            view.index = min(index or 0, len(self.alarms) - 1)
        self.query_one("#alarm-title", Static).update(self._title())

    @property
    def selected(self) -> RecordedAlarm | None:
        """The highlighted alarm."""
        index = self.query_one(ListView).index
        return None if index is None or not self.alarms else self.alarms[index]

    def action_acknowledge(self) -> None:
        """Ask for the cause of the highlighted alarm."""
        alarm = self.selected
        if alarm is None:
            self.notify("There is no alarm to acknowledge.")
            return
        self.app.push_screen(AckDialog(alarm, self.causes), self._acknowledged)

    def _acknowledged(self, request: AckRequest | None) -> None:
        if request is None:
            return
        if self.on_acknowledge is not None and self.in_thread:
            self._send(request)
            return
        if self.on_acknowledge is not None:
            try:
                self.on_acknowledge(request)
            except StationError as problem:
                self.notify(problem.message, severity="error")
                return
        self._show_acknowledged(request)

    @work(thread=True, group="acknowledge", exit_on_error=False)
    def _send(self, request: AckRequest) -> None:
        """Thread worker: the callback writes (and fsyncs) the ``ack`` event."""
        assert self.on_acknowledge is not None
        try:
            self.on_acknowledge(request)
        except StationError as problem:
            self.app.call_from_thread(
                self.notify, plain(problem.message), severity="error", markup=False
            )
            return
        self.app.call_from_thread(self._show_acknowledged, request)

    def _show_acknowledged(self, request: AckRequest) -> None:
        if not self.is_mounted:
            return
        for alarm in self.alarms:
            if alarm.seq == request.alarm and any(
                (ack.cause, ack.text, ack.action) == (request.cause, request.text, request.action)
                for ack in alarm.acks
            ):
                return  # the runner's new state already shows it
        ack = Acknowledgement(
            seq=0,
            alarm=request.alarm,
            cause=request.cause,
            text=request.text,
            action=request.action,
        )
        self.set_alarms(
            [
                replace(alarm, acks=(*alarm.acks, ack)) if alarm.seq == request.alarm else alarm
                for alarm in self.alarms
            ]
        )

    def action_close(self) -> None:
        """Back to the screen below."""
        self.app.pop_screen()
