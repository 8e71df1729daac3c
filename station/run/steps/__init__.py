"""The step kinds: one :class:`StepHandler` per kind, each in its own module, listed in
:data:`BUILT_IN`.

A site's own step kind is a handler its installed package offers under the entry-point group
``station.step_kinds`` (:mod:`station.extensions`); the procedure loader validates its keys
with the handler's ``schema``. The engine and the front ends need no change for one, since they
act on the handler's answers (its action and progress).
"""

from __future__ import annotations

from functools import lru_cache

from station.errors import StationError
from station.extensions import STEP_KINDS, SiteExtensions, site_extensions
from station.run.steps.base import PlanItem, StepHandler
from station.run.steps.check import CheckStep
from station.run.steps.input import InputStep
from station.run.steps.parts import PartsStep
from station.run.steps.repeat import RepeatBlock
from station.run.steps.sets import CaptureStep, CyclesStep
from station.run.steps.stroke import StrokeStep
from station.run.steps.zero import ZeroStep

BUILT_IN: tuple[StepHandler, ...] = (
    CheckStep(),
    InputStep(),
    ZeroStep(),
    CaptureStep(),
    CyclesStep(),
    PartsStep(),
    StrokeStep(),
    RepeatBlock(),
)
"""The station's own step kinds."""


def handlers() -> dict[str, StepHandler]:
    """Every step kind's handler by kind: the built-in ones, then a site's (which cannot
    replace a built-in kind)."""
    return _handlers(site_extensions(STEP_KINDS))


@lru_cache(maxsize=4)
def _handlers(site: SiteExtensions) -> dict[str, StepHandler]:
    # Asked at every state the engine computes: built once per set of installed kinds.
    found = {handler.kind: handler for handler in BUILT_IN}
    for handler in site.loaded:
        if isinstance(handler, StepHandler) and handler.kind and handler.kind not in found:
            found[handler.kind] = handler
    return found


def handler_for(kind: str) -> StepHandler:
    """The handler of a step kind; StationError when there is none."""
    known = handlers()
    try:
        return known[kind]
    except KeyError:
        failed = site_extensions(STEP_KINDS).failed
        problems = f" ({'; '.join(failed)})" if failed else ""
        raise StationError(
            f"no handler for step kind {kind!r}; known kinds: {', '.join(sorted(known))}" + problems
        ) from None


def kinds() -> tuple[str, ...]:
    """The step kinds there are handlers for."""
    return tuple(handlers())


__all__ = ["BUILT_IN", "PlanItem", "StepHandler", "handler_for", "handlers", "kinds"]
