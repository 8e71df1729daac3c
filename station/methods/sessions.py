"""Sessions as the methods read them: a session file's accepted readings, settings and notes
(:class:`SessionSource`), the readings taken at the placements of a repeated block, and the
values typed at its input steps. Shared by the methods; what only one method reads (linearity's
streamed strokes) is in its own package."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeGuard

import numpy as np

from station.analysis.summary import AnalysisConfig
from station.errors import StationError
from station.methods.contract import MethodInputs
from station.session.header import analysis_config
from station.session.model import Session, load_session
from station.text import zero_taken

AXES = ("x", "y", "z")

PlacementReadings = tuple[np.ndarray, dict[str, np.ndarray], dict[int, dict[str, Any]]]
"""The placement of each accepted reading, the readings per channel, and the values typed at
each placement's input steps."""


@dataclass(frozen=True)
class SessionSource:
    """What a session file gives the analysis: its accepted channels, the cycle number and time
    of each reading, its recorded settings and the notes a report prints about it."""

    session: Session
    channels: dict[str, np.ndarray]
    cycles: dict[str, np.ndarray]
    excluded_cycles: tuple[int, ...]
    config: AnalysisConfig
    notes: tuple[str, ...]
    times: dict[str, np.ndarray] | None = None
    """The time (s) of each reading, for the drift's trend test."""


def accepted_readings(session: Session) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The accepted readings of each channel that has any, and the cycle number of each."""
    channels = {name: values for name, values in session.channel_values().items() if len(values)}
    cycles = session.channel_cycles()
    return channels, {name: cycles[name] for name in channels}


def session_source(session: Session) -> SessionSource:
    """The accepted channels (rejected cycles left out), settings and notes of a session."""
    notes = [
        f"Session {session.session_id}: robot {session.robot}, operator "
        f"{session.operator or 'not given'}, procedure {session.procedure_id}, "
        f"created {session.created}, {session.status}.",
        f"Last line hash (anchors the session file): {session.last_hash}",
    ]
    zero = zero_taken(session.zeroes, session.header.get("resolution"))
    if zero:
        notes.append(zero)
    if session.torn is not None:
        notes.append(f"Torn tail: {session.torn.message}")
    channels, cycles = accepted_readings(session)
    return SessionSource(
        session=session,
        channels=channels,
        cycles=cycles,
        excluded_cycles=tuple(session.excluded_cycles),
        # The same settings the live analysis of the running session used.
        config=analysis_config(session.header, session.zeroes, session.events),
        notes=tuple(notes),
        times={name: times for name, times in session.channel_times().items() if name in channels},
    )


def load_session_source(path: Path) -> SessionSource:
    """:func:`session_source` of the session file at ``path``, read-only (a torn tail is
    reported in the notes, not repaired)."""
    return session_source(load_session(path, recover=False))


def session_inputs(
    source: SessionSource,
    *,
    config: AnalysisConfig | None = None,
    width: int = 80,
    options: Mapping[str, Any] | None = None,
) -> MethodInputs:
    """A loaded session as the inputs of a batch analysis (``config``: other settings than
    the ones it recorded; ``options``: the command line's values)."""
    return MethodInputs(
        config=source.config if config is None else config,
        channels=source.channels,
        cycles=source.cycles,
        excluded_cycles=source.excluded_cycles,
        times=source.times,
        options=dict(options or {}),
        width=width,
        session=source.session,
    )


# -- what was typed -----------------------------------------------------------------------------


def is_number(value: Any) -> TypeGuard[float]:
    """True for an int or a float (never a bool)."""
    return isinstance(value, int | float) and not isinstance(value, bool)


def typed_values(events: Sequence[Mapping[str, Any]], *fields: str) -> dict[str, Any]:
    """The values of the last input event holding all ``fields`` (empty when none does)."""
    for event in reversed(events):
        values = event.get("values") or {}
        if all(name in values for name in fields):
            return dict(values)
    return {}


def typed_per_placement(events: Sequence[Mapping[str, Any]]) -> dict[int, dict[str, Any]]:
    """The values typed at each placement of a repeated block (a later input event of the same
    placement adds to, or replaces, what was typed before)."""
    typed: dict[int, dict[str, Any]] = {}
    for event in events:
        placement = event.get("placement")
        if isinstance(placement, int):
            typed.setdefault(placement, {}).update(dict(event.get("values") or {}))
    return typed


def typed_points(
    typed: Mapping[int, Mapping[str, Any]], fields: Sequence[str] = AXES
) -> dict[int, tuple[float, ...]]:
    """The point typed at each placement (the teach pendant's X, Y, Z: ``fields``) where every
    one of its fields is a number; a placement missing one has no point."""
    return {
        placement: tuple(float(values[name]) for name in fields)
        for placement, values in typed.items()
        if all(is_number(values.get(name)) for name in fields)
    }


# -- placements ---------------------------------------------------------------------------------


def placement_readings(
    session: Session, channels: Sequence[str] = AXES, *, what: str = "a fixture placement"
) -> PlacementReadings:
    """The accepted readings a session took at the placements of a repeated block (fixture
    placements, joints, reference masters): the placement of each, the readings of each of
    ``channels`` every such cycle has, and the values typed per placement. StationError when
    no accepted reading was taken at a placement (``what``) yet."""
    numbers = [n for n in session.accepted_cycles if session.cycles[n].placement is not None]
    if not numbers:
        raise StationError(f"{session.path}: the session has no accepted readings at {what} yet.")
    readings = {
        channel: np.asarray([session.cycles[n].readings[channel].value for n in numbers])
        for channel in channels
        if all(channel in session.cycles[n].readings for n in numbers)
    }
    placements = np.asarray([session.cycles[n].placement for n in numbers])
    return placements, readings, typed_per_placement(session.input_events)
