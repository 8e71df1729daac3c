"""The registry of step kinds: one :class:`StepHandler` per kind, each in its own module.

A new step kind is a handler class registered with :func:`register` (the procedure loader then
accepts its ``kind`` with the keys its ``schema`` names); the engine and the front ends need no
change, since they act on the handler's answers (its action and progress).
"""

from __future__ import annotations

from station.errors import StationError
from station.procedures import register_step_schema
from station.run.steps.base import PlanItem, StepHandler

_HANDLERS: dict[str, StepHandler] = {}


def register(handler: StepHandler) -> StepHandler:
    """Add (or replace) the handler of ``handler.kind`` and tell the procedure loader its keys."""
    if not handler.kind:
        raise ValueError("a step handler needs a kind")
    register_step_schema(handler.kind, handler.schema)
    _HANDLERS[handler.kind] = handler
    return handler


def handler_for(kind: str) -> StepHandler:
    """The handler of a step kind; StationError when none is registered."""
    try:
        return _HANDLERS[kind]
    except KeyError:
        raise StationError(
            f"no handler for step kind {kind!r}; known kinds: {', '.join(sorted(_HANDLERS))}"
        ) from None


def kinds() -> tuple[str, ...]:
    """The registered step kinds."""
    return tuple(_HANDLERS)


# The built-in kinds register themselves on import (after the registry exists).
from station.run.steps import check, input, repeat, sets, stroke, zero  # noqa: E402

__all__ = [
    "PlanItem",
    "StepHandler",
    "check",
    "handler_for",
    "input",
    "kinds",
    "register",
    "repeat",
    "sets",
    "stroke",
    "zero",
]
