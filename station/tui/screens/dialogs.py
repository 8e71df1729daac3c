"""Small modal dialogs: a typed sentence (reject reason, note), a yes/no question, the help."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical, VerticalScroll
from textual.screen import ModalScreen, Screen
from textual.widgets import Input, Static

from station.tui.text import shown
from station.tui.widgets.fields import FieldInput, say
from station.tui.widgets.key_footer import KeyFooter


class TextPrompt(ModalScreen[str | None]):
    """Asks for one line of text; Enter returns it (refused when empty), Escape cancels."""

    BINDINGS = [Binding("escape", "cancel", "Cancel")]

    def __init__(self, title: str, prompt: str, *, placeholder: str = "") -> None:
        super().__init__()
        self._title = title
        self._prompt = prompt
        self._placeholder = placeholder

    def compose(self) -> ComposeResult:
        """Title, question, the input, the error line."""
        with Vertical(classes="dialog"):
            yield Static(shown(self._title, style="bold"), classes="dialog-title")
            yield Static(shown(self._prompt))
            yield FieldInput(placeholder=self._placeholder, id="prompt-input")
            yield Static("", classes="field-error", id="prompt-error")
            yield Static("Enter to save · Escape to cancel", classes="dim")
        yield KeyFooter()

    def on_mount(self) -> None:
        """Focus the input."""
        self.query_one(Input).focus()

    def on_input_submitted(self, event: Input.Submitted) -> None:
        """Return the text, or say why not."""
        text = event.value.strip()
        if not text:
            say(self.query_one("#prompt-error", Static), "Type a few words first.")
            return
        self.dismiss(text)

    def action_cancel(self) -> None:
        """Close without a value."""
        self.dismiss(None)


class ConfirmScreen(ModalScreen[bool]):
    """A yes/no question: y or Enter for yes, n or Escape for no."""

    BINDINGS = [
        Binding("y", "answer(True)", "Yes"),
        Binding("enter", "answer(True)", "Yes", show=False),
        Binding("n", "answer(False)", "No"),
        Binding("escape", "answer(False)", "No", show=False),
    ]

    def __init__(self, question: str, detail: str = "") -> None:
        super().__init__()
        self._question = question
        self._detail = detail

    def compose(self) -> ComposeResult:
        """The question and the keys."""
        with Vertical(classes="dialog"):
            yield Static(shown(self._question, style="bold"), classes="dialog-title")
            if self._detail:
                yield Static(shown(self._detail))
            yield Static("y = yes · n = no", classes="dim")
        yield KeyFooter()

    def action_answer(self, answer: bool) -> None:
        """Close with the answer."""
        self.dismiss(answer)


class QuitQuestion(ConfirmScreen):
    """Ctrl+C inside a dialog: quit now? (n goes back to the dialog, its text kept)."""


HELP_TEXT = """\
[b]Home[/b]  ↑ ↓ choose · Enter open · n new session · r resume
  v review · q quit

[b]Set-up[/b]  Tab or Enter / Shift+Tab move between fields · F3 test
  connection · F2 start. Limits: ±0.001 (a tolerance about nominal 0) or
  -0.001:0.001 (LSL:USL); one side may be empty. Port: pick a detected
  port or type /dev/ttyUSB0, rfc2217://host:port or socket://host:port.

[b]Checklist[/b]  Enter confirms the step (zeroes at a zero step) · n note
  q leave (resumable). At an input step Enter or Tab goes to the next
  field and Enter in the last one saves the values typed.

[b]Capture[/b]  Space capture a cycle · r reject the last cycle (asks
  why; nothing is deleted) · n note · p pause / continue · f finish
  x y z or Tab choose the axis · q leave (resumable)
  g go on to the next step (once the step has its minimum, e.g. the
  next joint) · a the alarm list: acknowledge an alarm with a cause
  from the procedure's list, what it was and the corrective action
  m the newest message and every alarm in full (their lines here are
  cut to the width). A reading beyond a limit is marked ▲ (above the
  USL) or ▼ (below the LSL) at once; the column "out" counts them per
  axis.

[b]Strokes[/b]  (linearity) the strokes stream as the robot shuttles
  A↔B · e end the stroke now (Space streams again) · f finish
  h v or Tab choose the indicator

[b]Summary[/b]  e export the text report · c export CSV · d charts
  h home · q quit

[b]Everywhere[/b]  ? the keys of the screen · Ctrl+P every action by
  name · Ctrl+C quit (inside a dialog it asks first)

Every reading is on disk (fsynced) before it is shown as captured.
If the link drops, the session is marked interrupted; run `station`
again and choose Resume. Verdicts: CAPABLE when Cpk's 95% lower
bound (Bissell) reaches the threshold (1.00 by default), NOT CAPABLE
when its upper bound is below it, INCONCLUSIVE between (with the
readings that would settle it; the report's rule Cpk ≥ 1 is shown
beside it), UNDEFINED when there are no limits or too few readings.
PROVISIONAL: 9 of 25 while fewer readings than the procedure's
minimum are in. The Cpk is shown with as many decimals as it takes
to sit on the same side of the threshold. Alarms: report rule 1 = a
point beyond the control limits; rule 2 = seven points in a row going
up or down; rule 3 = fifteen points alternating up and down; rule 4 =
two of three points beyond 2 sigma on one side; drift = the EWMA of
the mean beyond its limits. Live alarms are judged against control
limits frozen after the first cycles, so an alarm never goes away.
"""


APP_KEYS = ("quit_station", "command_palette")
"""The app's own keys listed beside a screen's (Textual's built-in ones are left out)."""

TEXTUAL_SCREEN_ACTIONS = frozenset(
    binding.action for binding in Screen.BINDINGS if isinstance(binding, Binding)
)
"""What every Textual screen binds (Tab's focus moves, ``super+c`` copy): not this program's
keys, whichever class declares them."""


def declared_actions(screen: Screen[object]) -> frozenset[str]:
    """The actions this program's own classes bind on ``screen`` (Textual's base classes,
    ``Screen`` and ``ModalScreen``, are not this program's)."""
    actions: set[str] = set()
    for cls in type(screen).__mro__:
        if cls.__module__.split(".")[0] == "textual":
            continue
        for binding in vars(cls).get("BINDINGS", ()):
            action = binding.action if isinstance(binding, Binding) else binding[1]
            actions.add(action)
    return frozenset(actions - TEXTUAL_SCREEN_ACTIONS)


def screen_keys(screen: Screen[object]) -> list[tuple[str, str]]:
    """The keys ``screen`` answers now: its own first, in the footer's order, then Ctrl+C;
    a list's or a field's own movement keys are left out (they are the same everywhere), as
    are keys without a description (they repeat one that has it, e.g. ``x`` beside Tab) and
    Textual's own keys of every screen (focus moves, copy)."""
    app = screen.app
    declared = declared_actions(screen)
    own: list[tuple[str, str]] = []
    general: list[tuple[str, str]] = []
    seen: set[str] = set()
    for active in screen.active_bindings.values():
        binding = active.binding
        if not binding.description or binding.action in seen or not active.enabled:
            continue
        if active.node is screen and binding.action in declared:
            own.append((app.get_key_display(binding), binding.description))
        elif active.node is app and binding.action in APP_KEYS:
            general.append((app.get_key_display(binding), binding.description))
        else:
            continue
        seen.add(binding.action)
    return own + general


class HelpScreen(ModalScreen[None]):
    """Every key of every screen, and what the verdict words mean."""

    BINDINGS = [
        Binding("escape", "close", "Close"),
        Binding("q", "close", "Close", show=False),
        Binding("question_mark", "close", "Close", show=False),
    ]

    def compose(self) -> ComposeResult:
        """The keys of the screen underneath first, then the help text, in a scrolling box."""
        with VerticalScroll(classes="dialog help"):
            underneath = [screen for screen in self.app.screen_stack if screen is not self]
            keys = screen_keys(underneath[-1]) if underneath else []
            if keys:
                text = Text("Keys of this screen\n", style="bold")
                for key, description in keys:
                    text.append(f"  {key:<12}", style="bold")
                    text.append(f" {description}\n")
                if not any(description == "palette" for _, description in keys):
                    text.append("  ^p           every action of this screen by name\n")
                yield Static(text, id="help-keys")
            yield Static(HELP_TEXT)
        yield KeyFooter()

    def action_close(self) -> None:
        """Back to the screen underneath."""
        self.dismiss(None)


class FullTextScreen(ModalScreen[None]):
    """A long text in full (the alarm log and the message line cut theirs to one line each):
    wrapped, scrollable, closed with Escape."""

    BINDINGS = [
        Binding("escape", "close", "Close"),
        Binding("q", "close", "Close", show=False),
    ]

    def __init__(self, title: str, lines: list[str]) -> None:
        super().__init__()
        self._title = title
        self._lines = lines

    def compose(self) -> ComposeResult:
        """The title and each line in full, in a scrolling box."""
        with VerticalScroll(classes="dialog help"):
            yield Static(shown(self._title, style="bold"), classes="dialog-title")
            body = "\n\n".join(self._lines) if self._lines else "Nothing to show yet."
            yield Static(shown(body), id="full-text")
        yield KeyFooter()

    def action_close(self) -> None:
        """Back to the screen underneath."""
        self.dismiss(None)
