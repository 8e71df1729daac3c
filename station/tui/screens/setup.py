"""The set-up screen: who, what, the limits, the port; a live "test connection"; then start.

Every field is checked when the operator starts, and a refused value gets a sentence right under
its field (:mod:`~station.tui.screens.setup_checks` turns the typed text into the engine's
``SessionSetup`` with the rules the command line uses too). When resuming, the recorded set-up is
shown and only the instrument line can change (the port may have moved). The form's rows and
defaults are in :mod:`~station.tui.screens.setup_form`, F3's test of the line in
:mod:`~station.tui.screens.setup_connection`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.text import Text
from textual import events
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.widget import Widget
from textual.widgets import Button, Input, Select, Static

from station.errors import StationError
from station.plain import plain
from station.session.remembered import RememberedSetup, load_remembered, save_remembered
from station.text import channel_map_text
from station.tui.app import PortNotOpen
from station.tui.remedies import explained
from station.tui.screens.dialogs import ConfirmScreen, HelpScreen
from station.tui.screens.setup_checks import (
    implausible,
    limits_key,
    read_ports,
    read_setup,
)
from station.tui.screens.setup_connection import ConnectionTestScreen
from station.tui.screens.setup_form import (
    KEPT_ON_PROCEDURE_CHANGE,
    TYPED_PORT,
    FormStart,
    fits_procedure,
    form_rows,
    login_name,
    read_header,
)
from station.tui.text import shown
from station.tui.widgets.fields import FIELD_KEYS, field_key_active, mark_focused_row, say
from station.tui.widgets.key_footer import KeyFooter

if TYPE_CHECKING:
    from station.procedures import Procedure
    from station.tui.app import StationApp


class SetupScreen(ConnectionTestScreen):
    """Robot, operator, procedure, unit, resolution, limits, cycles, port, protocol, trigger."""

    BINDINGS = [
        Binding("f2", "start", "Start"),
        Binding("f3", "test_connection", "Test connection"),
        Binding("escape", "back", "Back"),
        Binding("f1", "help", "Help"),
        Binding("space", "press_focused", show=False),
        *FIELD_KEYS,
    ]

    app: StationApp

    def __init__(
        self,
        procedure_id: str | None = None,
        resume_path: Path | None = None,
        *,
        typed: dict[str, str] | None = None,
    ) -> None:
        super().__init__()
        self.procedure_id = procedure_id
        self.resume_path = resume_path
        self._typed = dict(typed or {})
        """Values the operator already typed (kept when the procedure is changed)."""
        self._header: dict[str, Any] = {}
        self._initial: dict[str, str] = {}
        self._confirmed_limits: tuple[Any, ...] | None = None
        """The limits and resolution the operator confirmed despite an implausible ratio."""
        self._refused_values: dict[str, str] = {}

    # -- layout ---------------------------------------------------------------------------

    def compose(self) -> ComposeResult:
        """The form (scrolls at 80×24), the connection test's output, the footer."""
        catalog = self.app.catalog
        if self.resume_path is not None:
            self._header = read_header(self.resume_path)
            self.procedure_id = self._header.get("procedure", {}).get("id", self.procedure_id)
        if self.procedure_id is None:
            ids = catalog.ids()
            # The default method's own procedure (they share its name), else the first.
            from station.methods import names  # loaded with the catalog

            default = names()[0]
            self.procedure_id = default if default in ids else ids[0]
        procedure = catalog.get(self.procedure_id)
        self.procedure_id = procedure.id
        # In the demo each procedure has its own simulated set-up (and port).
        demo = self.app.demo_port(procedure.id)
        resuming = self.resume_path is not None
        # The last set-up, offered (never applied to a resume, never over the demo's line).
        last = {} if resuming or demo is not None else self._remembered()

        title = (
            f"Resume {self.resume_path.name}"
            if self.resume_path is not None
            else f"New session: {procedure.title} (report §{procedure.report_section})"
        )
        yield Static(shown(title, style="bold", limit=300), id="setup-title")
        hint = "Tab / Shift+Tab move between fields · F3 tests the line · F2 starts"
        if demo is not None and not resuming:
            hint = "Pre-filled for the demo: press F2 to start (F3 shows live readings first)"
        elif demo is not None:
            hint = "The demo resumes on its own running simulator (the line below): press F2"
        if last:
            hint = "Pre-filled from your last session: check robot and line · F2 starts"
        yield Static(Text(hint, style="bold cyan"), id="setup-hint")
        start = FormStart(
            procedure=procedure,
            procedures=tuple(catalog.procedures),
            header=self._header,
            demo=demo,
            last=last,
            resuming=resuming,
        )
        with VerticalScroll(id="setup-form"):
            yield from form_rows(start, self._select)
            yield Static("", id="test-output")
        # Outside the scrolling form, so the buttons and the form's verdict stay in view.
        yield Static("", classes="field-error", id="setup-error")
        with Horizontal(id="setup-buttons"):
            yield Button("Test connection (F3)", id="test", compact=True)
            yield Button(
                "Resume (F2)" if resuming else "Start (F2)",
                id="start",
                variant="primary",
                compact=True,
            )
        yield KeyFooter()

    def _select(self, field_id: str, options: Any, value: str, **options_kw: Any) -> Select:
        """A compact Select that remembers its initial value (see :meth:`_value`)."""
        self._initial[field_id] = value
        return Select(
            options, compact=True, value=value, allow_blank=False, id=field_id, **options_kw
        )

    def on_mount(self) -> None:
        """Focus the first field the operator can change; load the analysis (numpy, scipy) in
        the background meanwhile, so the first captured cycle does not wait for it."""
        self.app.warm_up_analysis()
        for field_id, value in self._typed.items():
            widget = self.query_one(f"#{field_id}")
            if isinstance(widget, Input):
                widget.value = value
            elif value:
                widget.value = value  # type: ignore[attr-defined]
                self._initial[field_id] = value
        if self.app.config.demo is not None and self.resume_path is None:
            # Everything is pre-filled: Enter or Space starts at once (the button is in view
            # below the form, which opens at its top).
            self.query_one("#start", Button).focus(scroll_visible=False)
        else:
            first = "#port" if self.resume_path is not None else "#robot"
            self.query_one(first, Input).focus()
        form = self.query_one("#setup-form", VerticalScroll)
        if self.resume_path is None:
            self.call_after_refresh(lambda: form.scroll_home(animate=False))

    def _remembered(self) -> dict[str, str]:
        """The last set-up from the settings file, by field name (empty when there is none
        or it could not be read; the reason is said as a notification)."""
        remembered, problem = load_remembered()
        if problem:
            self.app.notify(plain(problem), severity="warning", markup=False)
        return remembered.filled()

    def remember(self, setup: Any) -> None:
        """Keep this set-up's names and line for the next new session (not in the demo: its
        simulated port means nothing tomorrow). A file that cannot be written is said, not
        fatal."""
        if self.app.config.demo is not None or not setup.ports:
            return
        port = setup.ports[0]
        try:
            save_remembered(
                RememberedSetup(
                    robot=setup.robot,
                    operator=setup.operator,
                    port=port.url,
                    protocol=port.protocol,
                    channel_map=channel_map_text(port.channel_map),
                    trigger=str(setup.trigger),
                )
            )
        except (OSError, StationError) as error:
            self.app.notify(
                plain(f"the set-up was not remembered: {error}"), severity="warning", markup=False
            )

    # -- events ---------------------------------------------------------------------------

    def on_select_changed(self, event: Select.Changed) -> None:
        """A detected port fills the port field; another procedure rebuilds the form for its
        channels and defaults, keeping what was typed about the robot and the line."""
        self._clear_stale(event.select.id)
        if event.select.id == "detected" and event.value not in (TYPED_PORT, Select.NULL):
            self.query_one("#port", Input).value = str(event.value)
        elif (
            event.select.id == "procedure"
            and event.value not in (Select.NULL, self.procedure_id)
            and self.resume_path is None
        ):
            # The demo's line belongs to the procedure's own simulator: not kept.
            keys = (
                KEPT_ON_PROCEDURE_CHANGE[:2] if self.app.config.demo else KEPT_ON_PROCEDURE_CHANGE
            )
            procedure = self.app.catalog.get(str(event.value))
            kept = fits_procedure({key: self.form_value(key) for key in keys}, procedure)
            self.app.switch_screen(SetupScreen(procedure_id=str(event.value), typed=kept))

    def on_descendant_focus(self, event: events.DescendantFocus) -> None:
        """Mark the focused field's row (its label in reverse video)."""
        mark_focused_row(self, event.widget)

    def on_input_changed(self, event: Input.Changed) -> None:
        """A field the operator corrects loses its old error sentence at once (it is checked
        again at F2)."""
        self._clear_stale(event.input.id)

    def _clear_stale(self, field_id: str | None) -> None:
        if not field_id:
            return
        # A change event can arrive after the refusal it preceded (the field and the screen
        # have queues of their own): only a value other than the refused one is a correction.
        if self._refused_values.get(field_id) == self.form_value(field_id):
            return
        errors = self.query(f"#{field_id}-error")
        if errors and errors.first().has_class("-shown"):
            say(errors.first(), "")  # type: ignore[arg-type]
            if field_id == "port":
                # The port's sentence may come from the line that did not open.
                say(self.query_one("#setup-error", Static), "")
        self._confirmed_limits = None

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """The field keys only while a field has the focus (on a drop-down or a button, Enter
        and Tab do what they do there)."""
        return field_key_active(self, action)

    def action_field_key(self, key: str) -> None:
        """In a field, at once (before the next key is handed on): Enter and Tab move to the
        next field, as in a paper form, Shift+Tab to the one before."""
        if key == "previous":
            self.focus_previous()
        else:
            self.focus_next()

    def on_button_pressed(self, event: Button.Pressed) -> None:
        """The two buttons do what F3 and F2 do."""
        if event.button.id == "test":
            self.action_test_connection()
        elif event.button.id == "start":
            self.action_start()

    def action_press_focused(self) -> None:
        """Space presses a focused button, as Enter does (fields take their spaces first)."""
        if isinstance(self.focused, Button):
            self.focused.press()

    def action_back(self) -> None:
        """Back to the home screen; nothing was written."""
        self.app.pop_screen()

    def action_help(self) -> None:
        """The keys and the field formats."""
        self.app.push_screen(HelpScreen())

    # -- reading the form -----------------------------------------------------------------

    def form_value(self, field_id: str) -> str:
        widget = self.query_one(f"#{field_id}")
        value = widget.value  # type: ignore[attr-defined]
        if value is Select.NULL:
            # A Select applies its initial value a moment after mounting; a key pressed in
            # that moment still gets the value the form was built with.
            return self._initial.get(field_id, "")
        return str(value).strip()

    def _say(self, field_id: str, sentence: str) -> None:
        say(self.query_one(f"#{field_id}-error", Static), sentence)
        if field_id == "setup" and not self.query(".field-error.-shown").exclude("#setup-error"):
            self.call_after_refresh(self.show_buttons)

    def show_buttons(self) -> None:
        self.query_one("#test-output").scroll_visible(animate=False)

    def refuse(self, errors: dict[str, str]) -> None:
        """Put each sentence under its field, and take the operator to the first one."""
        for field_id, sentence in errors.items():
            self._say(field_id, sentence)
            if self.query(f"#{field_id}"):
                self._refused_values[field_id] = self.form_value(field_id)
        self._say("setup", f"{len(errors)} field(s) to correct above.")
        first_id = next(iter(errors))
        field = self.query_one(f"#{first_id}")
        first_sentence = self.query_one(f"#{first_id}-error")
        field.focus(scroll_visible=False)

        def show_first() -> None:
            # Once the error lines are laid out: the field's whole row and its sentence.
            form = self.query_one("#setup-form", VerticalScroll)
            row = field.parent if isinstance(field.parent, Widget) else field
            top = min(row.virtual_region.y, first_sentence.virtual_region.y)
            bottom = first_sentence.virtual_region.bottom
            if (
                top < form.scroll_y
                or bottom > form.scroll_y + form.scrollable_content_region.height
            ):
                form.scroll_to(y=max(0, top - 1), animate=False, immediate=True)

        self.call_after_refresh(show_first)

    def clear_errors(self) -> None:
        for error in self.query(".field-error"):
            say(error, "")  # type: ignore[arg-type]

    def _procedure(self) -> Procedure:
        return self.app.catalog.get(self.form_value("procedure") or str(self.procedure_id))

    # -- actions --------------------------------------------------------------------------

    def action_start(self) -> None:
        """Check the form, open the instruments, start (or resume) the session."""
        if self.resume_path is not None:
            self.clear_errors()
            errors: dict[str, str] = {}
            ports = read_ports(self.form_value, errors)
            if errors:
                self.refuse(errors)
                return
            try:
                self.app.resume_session(self.resume_path, ports)
            except PortNotOpen as error:
                self.refuse({"port": explained(error)})
            except StationError as error:
                if error.field == "port":  # e.g. another program's pseudo-terminal now
                    self.refuse({"port": explained(error)})
                else:
                    self._say("setup", explained(error))
            return
        setup = self._read_setup()
        if setup is None:
            return
        doubts = implausible(setup)
        if doubts and self._confirmed_limits != limits_key(setup):

            def answered(yes: bool | None) -> None:
                if yes:
                    self._confirmed_limits = limits_key(setup)
                    self.action_start()
                else:
                    first = next(iter(doubts))
                    self.query_one(f"#limits-{first}", Input).focus()

            self.app.push_screen(
                ConfirmScreen(
                    "Start with these limits?",
                    " ".join(doubts.values()) + " y starts anyway; n goes back to the limits.",
                ),
                answered,
            )
            return
        try:
            self.app.start_session(setup)
        except PortNotOpen as error:
            self.refuse({"port": explained(error)})
            return
        except StationError as error:
            self._say("setup", explained(error))
            return
        self.remember(setup)

    def _read_setup(self) -> Any | None:
        """A validated ``SessionSetup``, or None after putting each fault next to its field."""
        self.clear_errors()
        errors: dict[str, str] = {}
        try:
            setup = read_setup(
                self.form_value,
                self._procedure(),
                operator=login_name(),
                errors=errors,
            )
        except StationError as error:
            self._say("setup", explained(error))
            return None
        if errors:
            self.refuse(errors)
        return setup
