"""Form helpers shared by the set-up, the checklist's input steps and the dialogs: the field
every form types into, the keys that move between fields, the error line under a field.

Keys in a burst (a fast typist, a paste over SSH) must land, in order, in the field they were
typed for. Textual (8.2) does not promise that by itself, in two ways:

* The app hands each key to the widget focused *when the app takes the key*, into that widget's
  own queue. A key that moves the focus (Tab, Enter to the next field) takes effect only once
  the field has seen it and it has bubbled back up to the app; by then the keys typed after it
  were already handed to the old field. ``26.650 Tab 20.062 Tab -32.068`` filled X alone.
* A field inserts a typed character at once, in its own queue, but runs a bound key (Backspace
  is bound to ``delete_left``) only when the key has bubbled up to the app, after the
  characters typed after it: ``25 ⌫ ⌫ 30`` gave ``25`` (Textual issue 6605).

So :class:`FieldInput` runs its own bindings as it takes a key, and a form moves the focus with
priority bindings (:data:`FIELD_KEYS`), which the app runs as it takes the key, before it hands
on the next one, and with the screen's own ``set_focus`` (a widget's ``focus()`` waits its turn
in the app's queue, behind the keys typed after it). Whatever reads the fields after such a key
waits until they have taken the keys already handed to them
(:func:`after_fields_take_their_keys`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from textual import events
from textual.binding import Binding
from textual.dom import DOMNode
from textual.screen import Screen
from textual.widget import Widget
from textual.widgets import Input, Static

from station.tui.text import shown

FIELD_MOVES = [
    Binding("tab", "field_key('next')", show=False, priority=True),
    Binding("shift+tab", "field_key('previous')", show=False, priority=True),
    # A screen's own binding of a key replaces its base class's: Screen's moves of the focus
    # stay, for Tab on a drop-down or a button.
    Binding("tab", "app.focus_next", "Focus Next", show=False),
    Binding("shift+tab", "app.focus_previous", "Focus Previous", show=False),
]
"""Tab and Shift+Tab of a screen with fields, run as the app takes the key."""
FIELD_KEYS = [*FIELD_MOVES, Binding("enter", "field_key('enter')", show=False, priority=True)]
"""Tab, Shift+Tab and Enter of a screen with fields: the screen's ``action_field_key(key)``
moves the focus at once while a :class:`FieldInput` has it; its ``check_action`` makes the
binding inactive otherwise (:func:`field_key_active`), so the key does what it does elsewhere
(Enter confirms a checklist step, opens a drop-down, presses a button) and the footer shows
that. No description: the keys of a form are the same everywhere, and the help lists them."""


def field_key_active(screen: Screen, action: str) -> bool | None:
    """A screen's ``check_action`` for :data:`FIELD_KEYS`: ``field_key`` only while a field
    has the focus; True for every other action."""
    return action != "field_key" or focused_field(screen) is not None


class FieldInput(Input):
    """A one-line field whose editing keys (Backspace, Delete, the arrows, Home, End, Enter)
    take effect in the order they were typed, among the characters around them."""

    async def _on_key(self, event: events.Key) -> None:
        if not event.is_printable and await self._run_own_binding(event.key):
            # Done here, in order: the app must not run it again when the key reaches it.
            event.stop()
            event.prevent_default()
        await super()._on_key(event)

    async def _run_own_binding(self, key: str) -> bool:
        """Run this field's own (non-priority) binding of ``key``, as the app would once the
        key had bubbled up to it; True when one ran."""
        for binding in self._bindings.key_to_bindings.get(key, ()):
            if not binding.priority and await self.app.run_action(binding.action, self):
                return True
        return False


def focused_field(screen: Screen) -> FieldInput | None:
    """The field that has the focus on ``screen``, or None (a button, a list, nothing)."""
    focused = screen.focused
    return focused if isinstance(focused, FieldInput) else None


def move_between_fields(screen: Screen, fields: Sequence[FieldInput], step: int) -> None:
    """Focus the field ``step`` places from the focused one among ``fields``, now, wrapping
    round (Tab past the last field comes back to the first: a key typed then is never lost on
    a widget that takes no text)."""
    # The screen's own record of the focus, and its set_focus: a field learns it has the focus
    # (has_focus) and a widget's focus() takes effect only in their turn, behind the keys
    # typed after this one.
    focused = screen.focused
    if focused in fields:
        index = list(fields).index(focused)  # type: ignore[arg-type]
        screen.set_focus(fields[(index + step) % len(fields)])


def after_fields_take_their_keys(fields: Sequence[Widget], then: Callable[[], object]) -> None:
    """Call ``then`` once every one of ``fields`` has taken the keys already handed to it (each
    field takes its keys in its own queue): what reads the fields reads every key typed."""
    remaining = list(fields)
    if not remaining:
        then()
        return
    first, rest = remaining[0], remaining[1:]
    if not first.call_later(after_fields_take_their_keys, rest, then):
        after_fields_take_their_keys(rest, then)  # a field already removed takes no keys


def say(error_line: Static, sentence: str) -> None:
    """Show a sentence on a field's error line, or hide the line when the sentence is empty."""
    error_line.update(shown(sentence))
    error_line.set_class(bool(sentence), "-shown")


def mark_focused_row(screen: DOMNode, focused: DOMNode | None) -> None:
    """Give the ``.field-row`` holding ``focused`` the class ``-has-focus`` (its label is then
    drawn in reverse video) and take it from the others: focus shown by an attribute, not a
    shade, in every theme and under NO_COLOR."""
    holding = set(focused.ancestors_with_self) if focused is not None else set()
    for row in screen.query(".field-row"):
        row.set_class(row in holding, "-has-focus")
