"""Form helpers shared by the set-up, the checklist's input steps and the dialogs."""

from __future__ import annotations

from textual.dom import DOMNode
from textual.widgets import Static

from station.tui.text import shown


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
