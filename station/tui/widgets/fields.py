"""Form helpers shared by the set-up, the checklist's input steps and the dialogs."""

from __future__ import annotations

from textual.widgets import Static

from station.tui.text import shown


def say(error_line: Static, sentence: str) -> None:
    """Show a sentence on a field's error line, or hide the line when the sentence is empty."""
    error_line.update(shown(sentence))
    error_line.set_class(bool(sentence), "-shown")
