"""Messages that carry news from background threads to the screens.

The runner calls its listener from whatever thread produced an event (the gauge reader, a capture
worker). The listener only posts one of these; every widget update then happens on the UI thread
in a handler. ``RunnerChanged`` replaces an adjacent pending one, so a burst of events costs one
redraw, not one per event.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from textual.message import Message


@dataclass
class RunnerChanged(Message):
    """Something the runner reports has changed: a step, a cycle, a reading, an alarm, a status.

    ``posted_at`` is the monotonic time the first event of a coalesced burst was seen; the
    dashboard uses it to keep the oldest pending reading's wait within the redraw budget.
    """

    event_type: str = ""
    posted_at: float = 0.0
    reading: bool = False
    """A reading set is on disk: paint the last-reading line at once."""
    redraw: bool = True
    """More than a reading changed (the live analysis, a step, an alarm, a message): redraw
    the whole screen (coalesced, at most ~10 a second)."""
    analysis: bool = False
    """The notice carries the engine's live analysis (sent at most ~10 a second)."""

    def can_replace(self, message: Message) -> bool:
        """Coalesce with an adjacent pending ``RunnerChanged``: only the newest state matters."""
        if isinstance(message, RunnerChanged):
            # Textual drops this (older) message for the pending newer one: hand it the older
            # stamp so the latency of the whole burst stays honest, and what it asked for.
            message.posted_at = min(self.posted_at, message.posted_at)
            message.reading = message.reading or self.reading
            message.redraw = message.redraw or self.redraw
            message.analysis = message.analysis or self.analysis
            return True
        return False


@dataclass
class CaptureFinished(Message):
    """A capture worker returned: ``outcome`` is the runner's result, ``error`` a sentence."""

    outcome: Any = None
    error: str = ""


@dataclass
class ConnectionTested(Message):
    """The set-up screen's "test connection" produced readings or a sentence saying why not."""

    lines: list[str] = field(default_factory=list)
    error: str = ""
    done: bool = False
