"""The set-up screen: who, what, the limits, the port; a live "test connection"; then start.

Every field is checked when the operator starts, and a refused value gets a sentence right under
its field (the runner's :class:`~station.run.SessionSetup` and the analysis'
:class:`~station.analysis.capability.SpecLimits` do the checking; this screen only turns the
typed text into their arguments). When resuming, the recorded set-up is shown and only the
instrument line can change (the port may have moved).
"""

from __future__ import annotations

import getpass
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.text import Text
from textual import events, work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.screen import Screen
from textual.widgets import Button, Footer, Input, Label, Select, Static

from station.errors import StationError
from station.plain import plain
from station.record.baseline import header_baseline
from station.tui.app import PortNotOpen
from station.tui.messages import ConnectionTested
from station.tui.remedies import explained
from station.tui.text import shown
from station.tui.widgets.fields import mark_focused_row, say

if TYPE_CHECKING:
    from station.procedures import Procedure
    from station.tui.app import StationApp

TRIGGER_CHOICES = (
    ("poll: the station asks the gauges at each capture", "poll"),
    ("push: the gauges send (DATA button, foot switch)", "push"),
    ("stable: take the set once the readings settle", "stable"),
    ("arrival: a set each time the robot returns and is still", "arrival"),
)
TYPED_PORT = "__typed__"
DEMO_LIMITS = "±0.001"
"""The report's example tolerance, offered in the demo when a procedure has no default limits."""
DEMO_TRIAL_MINIMUM = 2
"""The fewest cycles, placements or strokes a demo's trial run may ask for."""
KEPT_ON_PROCEDURE_CHANGE = ("robot", "operator", "port", "protocol", "map", "trigger")
LIMIT_HELP = "±0.001 or LSL:USL, e.g. -0.001:0.0015 (one side may be empty)"
STROKE_LIMITS_HELP = (
    "Strokes: the limits about the bar's line make a straightness tolerance of USL − LSL "
    "(±0.001 → 0.002); each stroke's straightness (never below 0) is judged one-sided "
    "against it: Cpk = (tolerance − X̄)/3σ, Cp is not defined."
)
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


@dataclass(frozen=True)
class TypedLimits:
    """A parsed limits field: the lower and upper limit and the nominal (None when absent)."""

    lsl: float | None
    usl: float | None
    nominal: float | None


def parse_limits_text(text: str) -> TypedLimits | None:
    """``±0.001``, ``+-0.001``, ``0.001`` (a tolerance about 0), or ``LSL:USL``; None when empty.

    Raises StationError with the sentence shown under the field.
    """
    text = text.strip().replace(" ", "")
    if not text:
        return None
    tolerance = re.fullmatch(rf"(?:±|\+-|\+/-)?({_NUMBER})", text)
    if tolerance and ":" not in text:
        value = float(tolerance.group(1))
        if not math.isfinite(value) or value <= 0:
            raise StationError(f"a tolerance must be a positive number, not {text}: {LIMIT_HELP}")
        return TypedLimits(lsl=-value, usl=value, nominal=0.0)
    both = re.fullmatch(rf"({_NUMBER})?:({_NUMBER})?", text)
    if not both or (both.group(1) is None and both.group(2) is None):
        raise StationError(f"{text!r} is not a limit: write {LIMIT_HELP}")
    lsl = float(both.group(1)) if both.group(1) is not None else None
    usl = float(both.group(2)) if both.group(2) is not None else None
    if lsl is not None and usl is not None and usl <= lsl:
        raise StationError(
            f"the upper limit {usl:g} is not above the lower limit {lsl:g}: swap them"
        )
    nominal = 0.0 if lsl is None or usl is None else None
    return TypedLimits(lsl=lsl, usl=usl, nominal=nominal)


def limits_text(lsl: float | None, usl: float | None, nominal: float | None = None) -> str:
    """The field text for recorded limits: ``±tol`` when symmetric about 0, else ``LSL:USL``."""
    if lsl is not None and usl is not None and math.isclose(-lsl, usl) and not nominal:
        return f"±{usl:g}"
    return f"{'' if lsl is None else f'{lsl:g}'}:{'' if usl is None else f'{usl:g}'}"


def parse_channel_map(text: str) -> dict[str, str]:
    """``1=x,2=y,3=z`` → ``{"1": "x", "2": "y", "3": "z"}``; StationError when malformed."""
    mapping: dict[str, str] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        device, sep, channel = part.partition("=")
        if not sep or not device.strip() or not channel.strip():
            raise StationError(f"{part!r} is not DEVICE=CHANNEL: write e.g. 1=x,2=y,3=z")
        mapping[device.strip()] = channel.strip()
    if not mapping:
        raise StationError("say which device channel feeds which axis, e.g. 1=x,2=y,3=z")
    return mapping


def _field(label: str, widget: Any, field_id: str, hint: str = "") -> ComposeResult:
    """One labelled row, an optional hint, and the error line under it."""
    with Horizontal(classes="field-row"):
        yield Label(shown(label), classes="field-label")
        yield widget
    if hint:
        yield Static(shown(hint), classes="field-hint")
    yield Static("", classes="field-error", id=f"{field_id}-error")


class SetupScreen(Screen[None]):
    """Robot, operator, procedure, unit, resolution, limits, cycles, port, protocol, trigger."""

    BINDINGS = [
        Binding("f2", "start", "Start"),
        Binding("f3", "test_connection", "Test connection"),
        Binding("escape", "back", "Back"),
        Binding("f1", "help", "Help"),
        Binding("space", "press_focused", show=False),
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
        self._testing = False
        self._initial: dict[str, str] = {}
        self._confirmed_limits: tuple[Any, ...] | None = None
        self._refused_values: dict[str, str] = {}
        """The limits and resolution the operator confirmed despite an implausible ratio."""

    # -- layout ---------------------------------------------------------------------------

    def compose(self) -> ComposeResult:
        """The form (scrolls at 80×24), the connection test's output, the footer."""
        from station.instruments.protocols import protocol_names
        from station.instruments.transport import list_ports

        catalog = self.app.catalog
        if self.resume_path is not None:
            self._header = _read_header(self.resume_path)
            self.procedure_id = self._header.get("procedure", {}).get("id", self.procedure_id)
        if self.procedure_id is None:
            ids = catalog.ids()
            self.procedure_id = "repeatability" if "repeatability" in ids else ids[0]
        procedure = catalog.get(self.procedure_id)
        self.procedure_id = procedure.id
        # In the demo each procedure has its own simulated set-up (and port).
        demo = self.app.demo_port(procedure.id)
        count = count_field(procedure)
        header = self._header
        recorded_port = (header.get("instruments", {}).get("ports") or [{}])[0]
        resuming = self.resume_path is not None
        # The last set-up, offered (never applied to a resume, never over the demo's line).
        last = {} if resuming or demo is not None else self._remembered()

        title = (
            f"Resume {self.resume_path.name}"
            if resuming
            else f"New session: {procedure.title} (report §{procedure.report_section})"
        )
        yield Static(shown(title, style="bold", limit=300), id="setup-title")
        hint = "Tab / Shift+Tab move between fields · F3 tests the line · F2 starts"
        if demo is not None and not resuming:
            hint = "Pre-filled for the demo: press F2 to start (F3 shows live readings first)"
        if last:
            hint = "Pre-filled from your last session: check robot and line · F2 starts"
        yield Static(Text(hint, style="bold cyan"), id="setup-hint")
        with VerticalScroll(id="setup-form"):
            if resuming:
                yield Static(_recorded_summary(header), id="setup-recorded")
            yield from _field(
                "Robot",
                Input(
                    compact=True,
                    value=plain(
                        header.get("robot") or (demo.robot if demo else last.get("robot", ""))
                    ),
                    placeholder="name or asset number of the robot under test",
                    id="robot",
                    disabled=resuming,
                ),
                "robot",
            )
            yield from _field(
                "Operator",
                Input(
                    compact=True,
                    value=plain(header.get("operator") or last.get("operator") or _login_name()),
                    id="operator",
                    disabled=resuming,
                ),
                "operator",
            )
            yield from _field(
                "Procedure",
                self._select(
                    "procedure",
                    [(shown(f"{p.title} ({p.id})", limit=120), p.id) for p in catalog.procedures],
                    procedure.id,
                    disabled=resuming,
                ),
                "procedure",
            )
            yield from _field(
                "Unit",
                self._select(
                    "unit",
                    [("inch (in)", "in"), ("millimetre (mm)", "mm")],
                    header.get("unit") or procedure.unit,
                    disabled=resuming,
                ),
                "unit",
            )
            yield from _field(
                "Resolution",
                Input(
                    compact=True,
                    value=f"{header.get('resolution') or procedure.resolution:g}",
                    id="resolution",
                    disabled=resuming,
                ),
                "resolution",
                "the gauge's smallest step, in the unit above",
            )
            recorded_limits = header.get("limits") or {}
            for channel in judged_channels(procedure):
                limit = recorded_limits.get(channel) or procedure.limits.get(channel)
                value = DEMO_LIMITS if demo is not None and limit is None else ""
                if isinstance(limit, dict):
                    value = limits_text(limit.get("lsl"), limit.get("usl"), limit.get("nominal"))
                elif limit is not None:
                    value = limits_text(limit.lsl, limit.usl, limit.nominal)
                yield from _field(
                    f"Limits {channel}",
                    Input(
                        compact=True,
                        value=value,
                        placeholder=LIMIT_HELP,
                        id=f"limits-{channel}",
                        disabled=resuming,
                    ),
                    f"limits-{channel}",
                )
            yield Static(LIMIT_HELP, classes="field-hint")
            if any(step.kind == "stroke" for step in procedure.steps):
                # Streamed strokes are judged by their straightness, not by these limits
                # directly: say how, here, and not only in the procedure file.
                yield Static(STROKE_LIMITS_HELP, classes="field-hint")
            yield from _field(
                count.label,
                Input(
                    compact=True,
                    value=str(
                        header.get(count.header_key)
                        or (demo.count if demo else None)
                        or count.target
                    ),
                    id="cycles",
                    disabled=resuming,
                ),
                "cycles",
                count.hint,
            )
            detected = [(f"{p.device}  {p.description}", p.device) for p in list_ports()]
            port_value = recorded_port.get("url") or (demo.url if demo else last.get("port", ""))
            yield from _field(
                "Detected",
                self._select(
                    "detected", [*detected, ("(type the port below)", TYPED_PORT)], TYPED_PORT
                ),
                "detected",
                "serial ports this computer lists"
                + ("" if detected else ": none found (network and /dev/pts ports are not listed)"),
            )
            yield from _field(
                "Port",
                Input(
                    compact=True,
                    value=port_value,
                    placeholder="/dev/ttyUSB0, /dev/pts/N, rfc2217://host:port, socket://host:port",
                    id="port",
                ),
                "port",
            )
            protocols = protocol_names()
            protocol = recorded_port.get("protocol") or (
                demo.protocol if demo else last.get("protocol", protocols[0])
            )
            if protocol not in protocols:
                protocol = protocols[0]
            yield from _field(
                "Protocol",
                self._select("protocol", [(name, name) for name in protocols], protocol),
                "protocol",
            )
            channel_map = recorded_port.get("map") or (
                demo.channel_map
                if demo
                else {str(i + 1): ch for i, ch in enumerate(procedure.channels)}
            )
            map_text = ",".join(f"{k}={v}" for k, v in channel_map.items())
            if last.get("channel_map") and not recorded_port.get("map"):
                map_text = last["channel_map"]
            yield from _field(
                "Channel map",
                Input(compact=True, value=map_text, id="map"),
                "map",
                "device channel = axis, e.g. 1=x,2=y,3=z",
            )
            # The procedure's own trigger (repeatability: arrival, the robot paces the cycles)
            # unless the demo's simulated set-up or the resumed session says otherwise.
            trigger = header.get("instruments", {}).get("trigger") or (
                demo.trigger if demo else last.get("trigger") or procedure.trigger or "poll"
            )
            if trigger not in {value for _, value in TRIGGER_CHOICES}:
                trigger = "poll"
            yield from _field(
                "Trigger",
                self._select("trigger", TRIGGER_CHOICES, trigger, disabled=resuming),
                "trigger",
            )
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
        yield Footer()

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
        from station.session.remembered import load_remembered

        remembered, problem = load_remembered()
        if problem:
            self.app.notify(plain(problem), severity="warning", markup=False)
        return remembered.filled()

    def remember(self, setup: Any) -> None:
        """Keep this set-up's names and line for the next new session (not in the demo: its
        simulated port means nothing tomorrow). A file that cannot be written is said, not
        fatal."""
        from station.session.remembered import RememberedSetup, save_remembered

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
                    channel_map=",".join(f"{k}={v}" for k, v in port.channel_map.items()),
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
            kept = {key: self._value(key) for key in keys}
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
        if self._refused_values.get(field_id) == self._value(field_id):
            return
        errors = self.query(f"#{field_id}-error")
        if errors and errors.first().has_class("-shown"):
            say(errors.first(), "")  # type: ignore[arg-type]
            if field_id == "port":
                # The port's sentence may come from the line that did not open.
                say(self.query_one("#setup-error", Static), "")
        self._confirmed_limits = None

    def on_input_submitted(self, event: Input.Submitted) -> None:
        """Enter in a field moves to the next one, as in a paper form."""
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
        from station.tui.screens.dialogs import HelpScreen

        self.app.push_screen(HelpScreen())

    # -- reading the form -----------------------------------------------------------------

    def _value(self, field_id: str) -> str:
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
            self.call_after_refresh(self._show_buttons)

    def _show_buttons(self) -> None:
        self.query_one("#test-output").scroll_visible(animate=False)

    def _refuse(self, errors: dict[str, str]) -> None:
        """Put each sentence under its field, and take the operator to the first one."""
        for field_id, sentence in errors.items():
            self._say(field_id, sentence)
            if self.query(f"#{field_id}"):
                self._refused_values[field_id] = self._value(field_id)
        self._say("setup", f"{len(errors)} field(s) to correct above.")
        first_id = next(iter(errors))
        field = self.query_one(f"#{first_id}")
        sentence = self.query_one(f"#{first_id}-error")
        field.focus(scroll_visible=False)

        def show_first() -> None:
            # Once the error lines are laid out: the field's whole row and its sentence.
            form = self.query_one("#setup-form", VerticalScroll)
            row = field.parent if field.parent is not None else field
            top = min(row.virtual_region.y, sentence.virtual_region.y)
            bottom = sentence.virtual_region.bottom
            if (
                top < form.scroll_y
                or bottom > form.scroll_y + form.scrollable_content_region.height
            ):
                form.scroll_to(y=max(0, top - 1), animate=False, immediate=True)

        self.call_after_refresh(show_first)

    def _clear_errors(self) -> None:
        for error in self.query(".field-error"):
            say(error, "")  # type: ignore[arg-type]

    def _procedure(self) -> Procedure:
        return self.app.catalog.get(self._value("procedure") or str(self.procedure_id))

    def read_ports(self, errors: dict[str, str]) -> tuple[Any, ...]:
        """The instrument line as the runner's ``PortSetup``; faults go into ``errors``."""
        from station.instruments.protocols import get_protocol
        from station.instruments.transport import refuse_own_terminal, url_scheme
        from station.run import PortSetup

        url = self._value("port")
        if not url:
            errors["port"] = "Name the port of the indicators (or pick a detected one above)."
        elif url_scheme(url) is None:
            try:
                refuse_own_terminal(url)
            except StationError as error:
                errors["port"] = explained(error)
        try:
            protocol = get_protocol(self._value("protocol"))
        except StationError as error:
            errors["protocol"] = explained(error)
            protocol = None
        try:
            channel_map = parse_channel_map(self._value("map"))
        except StationError as error:
            errors["map"] = explained(error)
            channel_map = {}
        if errors.keys() & {"port", "protocol", "map"} or protocol is None:
            return ()
        return (
            PortSetup(
                url=url,
                protocol=self._value("protocol"),
                channel_map=channel_map,
                settings=protocol.settings,
            ),
        )

    def read_setup(self) -> Any | None:
        """A validated ``SessionSetup``, or None after putting each fault next to its field."""
        from station.analysis.capability import SpecLimits
        from station.run import SessionSetup

        self._clear_errors()
        errors: dict[str, str] = {}
        procedure = self._procedure()
        robot = self._value("robot")
        if not robot:
            errors["robot"] = "Name the robot under test (its name or asset number)."
        resolution: float | None = None
        try:
            resolution = float(self._value("resolution"))
            if not (math.isfinite(resolution) and resolution > 0):
                raise ValueError
        except ValueError:
            errors["resolution"] = (
                f"The resolution must be a positive number such as {procedure.resolution:g}."
            )
        limits: dict[str, Any] = {}
        for channel in judged_channels(procedure):
            try:
                typed = parse_limits_text(self._value(f"limits-{channel}"))
                if typed is None:
                    raise StationError(
                        f"Give the limits of {channel}: {LIMIT_HELP}. The verdict needs them."
                    )
                limits[channel] = SpecLimits(lsl=typed.lsl, usl=typed.usl, nominal=typed.nominal)
            except StationError as error:
                errors[f"limits-{channel}"] = explained(error)
        count = count_field(procedure)
        cycles: int | None = None
        try:
            cycles = int(self._value("cycles"))
            # The demo allows a short trial run (``station demo --count 5``): its verdict comes
            # with the wide confidence bound on Cpk that so few readings give.
            trial = self.app.config.demo is not None and cycles >= DEMO_TRIAL_MINIMUM
            if cycles < count.minimum and not trial:
                errors["cycles"] = count.too_few
        except ValueError:
            errors["cycles"] = f"Give a whole number of {count.noun}, e.g. {count.target}."
        ports = self.read_ports(errors)
        if errors:
            self._refuse(errors)
            return None
        try:
            return SessionSetup(
                procedure=procedure,
                robot=robot,
                operator=self._value("operator") or _login_name(),
                ports=ports,
                trigger=self._value("trigger"),  # type: ignore[arg-type]
                unit=self._value("unit"),
                resolution=resolution,
                limits=limits,
                **{count.setup_key: cycles},
                # Live alarms test against the robot's baseline for this procedure and unit.
                baseline=header_baseline(
                    robot, procedure.id, self._value("unit") or procedure.unit
                ),
            )
        except StationError as error:
            self._say("setup", explained(error))
            return None

    # -- actions --------------------------------------------------------------------------

    def action_start(self) -> None:
        """Check the form, open the instruments, start (or resume) the session."""
        if self.resume_path is not None:
            self._clear_errors()
            errors: dict[str, str] = {}
            ports = self.read_ports(errors)
            if errors:
                self._refuse(errors)
                return
            try:
                self.app.resume_session(self.resume_path, ports)
            except PortNotOpen as error:
                self._refuse({"port": explained(error)})
            except StationError as error:
                self._say("setup", explained(error))
            return
        setup = self.read_setup()
        if setup is None:
            return
        doubts = self._implausible(setup)
        if doubts and self._confirmed_limits != self._limits_key(setup):
            from station.tui.screens.dialogs import ConfirmScreen

            def answered(yes: bool | None) -> None:
                if yes:
                    self._confirmed_limits = self._limits_key(setup)
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
            self._refuse({"port": explained(error)})
            return
        except StationError as error:
            self._say("setup", explained(error))
            return
        self.remember(setup)

    @staticmethod
    def _limits_key(setup: Any) -> tuple[Any, ...]:
        return (
            setup.resolution,
            tuple(sorted((c, lim.lsl, lim.usl, lim.nominal) for c, lim in setup.limits.items())),
        )

    def _implausible(self, setup: Any) -> dict[str, str]:
        """Channel -> a sentence for each tolerance under 10 or over 100,000 gauge steps."""
        from station.analysis.tolerance import implausible_tolerance

        doubts: dict[str, str] = {}
        for channel, limits in setup.limits.items():
            sentence = implausible_tolerance(
                channel, limits.lsl, limits.usl, limits.nominal, setup.resolution, setup.unit
            )
            if sentence:
                doubts[channel] = sentence
        return doubts

    def action_test_connection(self) -> None:
        """Open the port and show a few readings; nothing is recorded."""
        errors: dict[str, str] = {}
        self._clear_errors()
        ports = self.read_ports(errors)
        if errors:
            self._refuse(errors)
            return
        if self._testing:
            return
        self._testing = True
        self.query_one("#test-output", Static).update(
            shown(f"Opening {ports[0].url} ...", style="yellow")
        )
        unit, resolution = self._unit_and_resolution()
        self._test_connection(ports, self._value("trigger"), unit, resolution)

    def _unit_and_resolution(self) -> tuple[str | None, float | None]:
        """The unit and resolution the form says now (None for one it cannot read yet)."""
        try:
            resolution: float | None = float(self._value("resolution"))
        except ValueError:
            resolution = None
        if resolution is not None and not resolution > 0:
            resolution = None
        return self._value("unit") or None, resolution

    @work(thread=True, group="test-connection", exclusive=True, exit_on_error=False)
    def _test_connection(
        self,
        ports: tuple[Any, ...],
        trigger: str,
        unit: str | None = None,
        resolution: float | None = None,
    ) -> None:
        """Thread worker: a few captures through the real reader, posted line by line, then
        the frames judged against the form's unit and resolution."""
        from station.tui.instruments import test_connection

        try:
            for lines in test_connection(ports, trigger, unit=unit, resolution=resolution):
                self.post_message(ConnectionTested(lines=lines))
            self.post_message(ConnectionTested(done=True))
        except StationError as error:
            self.post_message(ConnectionTested(error=explained(error), done=True))

    def on_connection_tested(self, message: ConnectionTested) -> None:
        """Show the readings (or why there are none)."""
        output = self.query_one("#test-output", Static)
        if message.error:
            output.update(shown(message.error, style="bold red"))
        elif message.lines:
            output.update(shown("\n".join(message.lines), style="green"))
        # Keep the readings and the buttons under them in view (once laid out).
        self.call_after_refresh(self._show_buttons)
        if message.done:
            self._testing = False


@dataclass(frozen=True)
class CountField:
    """What the set-up's count field asks for: cycles (repeatability), placements (a
    ``repeat`` block, relative accuracy) or strokes (a ``stroke`` step, linearity)."""

    label: str
    noun: str
    setup_key: str
    """The ``SessionSetup`` argument it fills: ``cycles``, ``placements`` or ``strokes``."""
    header_key: str
    target: int
    minimum: int
    hint: str
    too_few: str


def count_field(procedure: Procedure) -> CountField:
    """The count field of ``procedure``'s set-up (see :class:`CountField`)."""
    steps = list(procedure.steps)
    stroke = next((s for s in steps if s.kind == "stroke"), None)
    repeat = next((s for s in steps if s.kind == "repeat"), None)
    if stroke is not None:
        target = int(stroke.count_target or procedure.cycles_target)
        low = int(stroke.count_min or target)
        # Fewer strokes are allowed (a short trial run); the report's range is said.
        return CountField(
            "Strokes",
            "strokes",
            "strokes",
            "strokes_target",
            target,
            2,
            f"A↔B strokes; the report asks for {low} to {target}",
            f"Give at least 2 strokes (one each way); the report asks for {low} to {target}.",
        )
    if repeat is not None:
        target = int(repeat.count_target or 1)
        low = int(repeat.count_min or target)
        return CountField(
            "Placements",
            "placements",
            "placements",
            "placements_target",
            target,
            1,
            f"fixture placements over the envelope; the report asks for a few ({low} to {target})",
            "Give at least 1 fixture placement.",
        )
    # Fewer cycles are allowed (a short trial run, e.g. the demo's --count 5): the verdict says
    # it is provisional below the report's minimum.
    return CountField(
        "Cycles",
        "cycles",
        "cycles",
        "cycles_target",
        procedure.cycles_target,
        2,
        f"the report asks for {procedure.cycles_min} to {procedure.cycles_target}",
        f"Give at least 2 cycles; the report asks for {procedure.cycles_min} to "
        f"{procedure.cycles_target}.",
    )


def judged_channels(procedure: Procedure) -> list[str]:
    """The channels that take limits: all but a stroke step's position channel (the linear
    scale measures where along the bar, not an error); none when the procedure's analysis
    kind judges no spec limits (a gauge check, a gain schedule)."""
    from station.procedures import analysis_needs

    if not analysis_needs(procedure.analysis).limits:
        return []
    positions = {s.direction_channel for s in procedure.steps if s.kind == "stroke"}
    return [c for c in procedure.channels if c not in positions]


def _login_name() -> str:
    try:
        return getpass.getuser()
    except (KeyError, OSError):
        return ""


def _read_header(path: Path) -> dict[str, Any]:
    """The recorded set-up of a session file (read-only)."""
    from station.session.model import load_session

    session = load_session(path, recover=False)
    header = getattr(session, "header", {})
    return dict(header) if isinstance(header, dict) else dict(vars(header))


def _recorded_summary(header: dict[str, Any]) -> Text:
    """What the file recorded, for the operator to check before resuming."""
    procedure = header.get("procedure", {})
    text = Text("Recorded set-up (kept as it was):\n", style="bold")
    text.append(
        f"robot {plain(header.get('robot'), limit=80)}, operator "
        f"{plain(header.get('operator'), limit=80)}, procedure "
        f"{procedure.get('id')} {procedure.get('version')}, unit {header.get('unit')}, "
        f"resolution {header.get('resolution')}, {header.get('cycles_target')} cycles.\n"
        "Check the instrument line below (the port may have changed), then press F2."
    )
    return text
