"""The one error type a user ever sees: a sentence that says what is wrong and what to do."""

from __future__ import annotations


class StationError(Exception):
    """A problem the user can fix, worded as one line for the terminal.

    Domain code raises it (or a subclass) for bad input: a missing port, a torn session file, a
    wrong procedure file, impossible limits. The command line prints ``station: <message>`` on
    stderr and exits with ``exit_code``; the TUI shows the same sentence. Never raise it for a
    programming error.
    """

    exit_code: int = 2

    def __init__(self, message: str, *, exit_code: int | None = None) -> None:
        super().__init__(message)
        if exit_code is not None:
            self.exit_code = exit_code

    @property
    def message(self) -> str:
        """The one-line sentence shown to the user."""
        return str(self.args[0]) if self.args else ""
