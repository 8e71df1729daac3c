"""Reading sets as the engine judges them: which triggers let the devices set the pace, why a
set cannot be a cycle, and the time a cycle's readings are dated with."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from station.instruments.capture import at_stop_sentence
from station.instruments.units import unit_mismatch
from station.session.model import event_seconds

if TYPE_CHECKING:
    from station.instruments.capture import CaptureResult

DEVICE_DRIVEN_TRIGGERS = ("push", "arrival")
"""Triggers where the devices (a DATA press, the robot's arrival) decide when a set is taken:
the engine records the sets they send instead of polling."""


def cycle_times(channels: Sequence[str], event: Mapping[str, Any]) -> dict[str, float] | None:
    """The time of a cycle's readings for the drift's trend: its ``reading`` event's ``t``
    (what the session file's analysis and its exports use), for every channel."""
    stamp = event_seconds(str(event.get("t") or ""))
    return None if math.isnan(stamp) else dict.fromkeys(channels, stamp)


def set_problem(result: CaptureResult, needed: Sequence[str], unit: str) -> str:
    """Why a reading set cannot be a cycle ('' when it can): a needed channel missing, stale
    or duplicated, or in another unit than the session's."""
    problems = []
    missing = [c for c in needed if c not in result.readings]
    down = set(getattr(result, "disconnected", ()))
    stale = [c for c in missing if c in result.stale and c not in down]
    # A channel whose port is down is explained by the port's own sentence (in errors).
    absent = [c for c in missing if c not in stale and c not in down]
    if absent:
        problems.append("no reading from " + ", ".join(absent))
    if stale:
        problems.append("only readings from before the trigger on " + ", ".join(stale))
    duplicated = [c for c in needed if c in result.duplicated]
    if duplicated:
        problems.append("more than one reading from " + ", ".join(duplicated))
    at_stop = [c for c in needed if c in result.at_stop]
    if at_stop:
        problems.append(at_stop_sentence(at_stop))
    mismatch = unit_mismatch(result.readings, needed, unit)
    if mismatch:
        problems.append(mismatch)
    if missing and result.errors:
        # A port's sentence may end in a full stop already; this one ends the whole list.
        problems.extend(error.rstrip(". ") for error in result.errors)
    elif down & set(missing):
        unexplained = [c for c in missing if c in down]
        problems.append(f"the port of {', '.join(unexplained)} is disconnected (reconnecting...)")
    return "; ".join(problems) + "." if problems else ""
