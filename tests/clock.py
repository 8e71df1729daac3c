"""A clock the test moves: what a simulated robot does then depends on the test's steps, never on
how busy the machine is.

Pass :class:`ManualClock` where station code takes ``clock=`` (a callable returning monotonic
seconds, ``time.monotonic`` by default) and call :meth:`ManualClock.advance` where the test wants
time to pass.
"""

from __future__ import annotations

import threading


class ManualClock:
    """Monotonic seconds that move only when :meth:`advance` is called (thread-safe)."""

    def __init__(self, start: float = 1000.0) -> None:
        self._now = float(start)
        self._lock = threading.Lock()

    def __call__(self) -> float:
        with self._lock:
            return self._now

    def advance(self, seconds: float) -> float:
        """Move the clock on by ``seconds`` (not negative); returns the new time."""
        if seconds < 0:
            raise ValueError(f"a monotonic clock does not go back ({seconds} s)")
        with self._lock:
            self._now += seconds
            return self._now
