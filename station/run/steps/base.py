"""The shape of a step handler, and the plan item it works on.

A handler answers, for its step kind: does it take reading sets, what confirming it means, what
a set does to it, its progress, and the next :class:`~station.run.state.Action`. The engine
(:mod:`station.run.engine`) holds the lock, the journal, the plan, the intake thread, the
listener and the gauge subscription, and calls the current step's handler for everything that
depends on the kind. A handler's methods are called with the engine's lock held unless they say
otherwise (``zero``, ``capture`` and ``stream`` take the lock themselves around their waits).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from station.errors import StationError
from station.procedures import StepSchema

if TYPE_CHECKING:
    from station.procedures import Step
    from station.run.engine import Runner
    from station.run.setup import SessionSetup
    from station.run.state import Action, CycleOutcome, Progress


@dataclass(frozen=True)
class PlanItem:
    """One step of the unrolled procedure (a repeat block's steps appear once per placement)."""

    step: Step
    placement: int | None
    placements: int | None

    @property
    def key(self) -> tuple[str, int | None]:
        """(step id, placement): a step's identity in the session."""
        return (self.step.id, self.placement)


class StepHandler:
    """The default behaviour of a step kind: not counted, takes no sets, refuses every
    operator call but those its subclass implements (with a sentence naming the step)."""

    kind: ClassVar[str] = ""
    schema: ClassVar[StepSchema] = StepSchema()
    """The procedure-file keys and facets of this kind (registered with the loader)."""
    takes_sets: ClassVar[bool] = False
    """True when a reading set (a poll, a DATA press, an arrival) is recorded into this step."""
    confirm_waits: ClassVar[bool] = False
    """True when confirming waits on the instruments (the engine calls :meth:`confirm`
    without its lock)."""

    # -- the plan ---------------------------------------------------------------------------

    def unroll(self, step: Step, placements: int | None) -> Iterable[PlanItem]:
        """The plan items of ``step`` (a block repeats its inner steps)."""
        yield PlanItem(step, None, None)

    def header_fields(self, setup: SessionSetup, step: Step) -> Mapping[str, Any]:
        """Fields this step kind adds to the session header (e.g. a deadband)."""
        return {}

    def entered(self, run: Runner, item: PlanItem) -> None:
        """The step became current (the session started or resumed on it, or the step before
        it was completed). Lock held."""

    # -- what the operator sees ---------------------------------------------------------------

    def action(self, run: Runner, item: PlanItem) -> Action:
        """The operator's next action while this step is current."""
        raise NotImplementedError

    def progress(self, run: Runner, item: PlanItem) -> Progress | None:
        """How far the step is, or None when it counts nothing."""
        return None

    def prompt(self, run: Runner, item: PlanItem) -> str:
        """The instruction shown for the step."""
        return item.step.text or item.step.title

    # -- what the operator does ---------------------------------------------------------------

    def confirm(self, run: Runner, item: PlanItem, by: str) -> None:
        """Complete the step by the operator's word."""
        raise StationError(f"step {item.step.title!r} cannot be confirmed")

    def submit(self, run: Runner, item: PlanItem, values: Mapping[str, str], by: str) -> None:
        """Record typed values."""
        raise StationError(f"step {item.step.title!r} does not take typed values")

    def zero(self, run: Runner, item: PlanItem, by: str, timeout: float) -> None:
        """Zero the gauges (called without the lock)."""
        raise StationError(f"step {item.step.title!r} is not a zero step")

    def capture(self, run: Runner, item: PlanItem, timeout: float, by: str) -> CycleOutcome:
        """Take one reading set (called without the lock)."""
        raise StationError(f"step {item.step.title!r} does not capture readings")

    def stream(self, run: Runner, item: PlanItem, **options: Any) -> int:
        """Stream reading sets until the step has what it needs (called without the lock)."""
        raise StationError(f"step {item.step.title!r} does not stream readings")

    # -- what a reading set does ----------------------------------------------------------------

    def accept_set(self, run: Runner, item: PlanItem, result: Any, by: str) -> CycleOutcome:
        """Record a reading set into the step (only for ``takes_sets`` kinds)."""
        raise StationError(f"step {item.step.title!r} does not take reading sets")

    def closing(self, run: Runner, item: PlanItem) -> None:
        """Called just before the step's ``step`` event is written (e.g. to check the whole
        analysis for alarms once the step's sets are in)."""

    def replay(self, run: Runner, item: PlanItem, event: Mapping[str, Any]) -> None:
        """Rebuild this step's own state from one of its recorded events (resume)."""
