"""Waiting for what a test depends on, instead of sleeping a fixed time and hoping it happened.

A fixed sleep is too long on a quiet machine and too short on a loaded one; a wait on the event
itself returns as soon as it happened and still fails (False) if it never does.
"""

from __future__ import annotations

import time
from collections.abc import Callable


def wait_until(condition: Callable[[], object], timeout: float = 5.0) -> bool:
    """Wait until ``condition()`` is true (True) or ``timeout`` seconds pass (False)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.005)
    return True
