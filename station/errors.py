"""The one error type a user ever sees: a sentence that says what is wrong and what to do.

A domain error names what failed and, where the user can act, a *remedy*: a short code from
:data:`REMEDIES`, never an option name or a key. Each front end words the remedy in its own
terms (the command line names an option, the TUI a key or a field): see
``station/commands/_remedies.py`` and ``station/tui/remedies.py``. ``field`` names the input
that was wrong (``robot``, ``map``, ``limits``...), so a form can show the sentence beside it.
"""

from __future__ import annotations

REMEDIES: dict[str, str] = {
    "map_channel": "feed every channel the procedure measures from a device channel",
    "give_limits": "give specification limits",
    "give_tolerance": "give a straightness tolerance",
    "resume_session": "resume the session",
    "list_ports": "see which serial ports this machine has",
    "serial_settings": "set the line's serial settings",
    "choose_sessions_folder": "choose another sessions folder",
    "choose_link_path": "choose another link path",
    "split_channels": "give the simulator fewer channels per port",
    "choose_procedures_folder": "name an existing procedures folder",
}
"""Every remedy code a domain error may carry, with a front-end-neutral wording (the fallback
when a front end has no phrasing of its own)."""


class StationError(Exception):
    """A problem the user can fix, worded as one line for the terminal.

    Domain code raises it (or a subclass) for bad input: a missing port, a torn session file, a
    wrong procedure file, impossible limits. The command line prints ``station: <message>`` on
    stderr and exits with ``exit_code``; the TUI shows the same sentence. Never raise it for a
    programming error.

    ``remedy`` (a key of :data:`REMEDIES`) and ``field`` are for the front ends: a message
    raised below them never names an option or a key; the front end adds its own wording of
    the remedy (:meth:`worded`).
    """

    exit_code: int = 2

    def __init__(
        self,
        message: str,
        *,
        exit_code: int | None = None,
        remedy: str | None = None,
        field: str | None = None,
        subject: str | None = None,
    ) -> None:
        super().__init__(message)
        if exit_code is not None:
            self.exit_code = exit_code
        if remedy is not None and remedy not in REMEDIES:
            raise ValueError(f"unknown remedy code {remedy!r}")
        self.remedy = remedy
        self.field = field
        self.subject = subject
        """What the remedy applies to (a session file's path, a channel list...)."""

    @property
    def message(self) -> str:
        """The one-line sentence shown to the user (without the front end's remedy)."""
        return str(self.args[0]) if self.args else ""

    def worded(self, phrasing: dict[str, str]) -> str:
        """The message with the remedy in a front end's words: ``phrasing`` maps remedy codes
        to text (``{subject}`` is filled in); a code it lacks falls back to :data:`REMEDIES`."""
        if self.remedy is None:
            return self.message
        template = phrasing.get(self.remedy, REMEDIES[self.remedy])
        remedy = template.replace("{subject}", str(self.subject or ""))
        return f"{self.message.rstrip('. ')}: {remedy}"
