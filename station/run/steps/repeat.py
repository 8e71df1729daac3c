"""``repeat``: a block of steps walked once per fixture placement (relative accuracy).

The block is unrolled into the plan; it is never current itself."""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

from station.procedures import Step, StepSchema
from station.run.steps.base import PlanItem, StepHandler

if TYPE_CHECKING:
    from station.run.engine import Runner
    from station.run.state import Action


class RepeatBlock(StepHandler):
    """Unrolls into its inner steps, ``placements`` (the set-up's) or its target times."""

    kind = "repeat"
    schema = StepSchema(block=True)

    def unroll(self, step: Step, placements: int | None) -> Iterable[PlanItem]:
        count = int(placements or step.count_target or 1)
        for placement in range(1, count + 1):
            for inner in step.steps:
                yield PlanItem(inner, placement, count)

    def action(self, run: Runner, item: PlanItem) -> Action:
        raise AssertionError("a repeat block is unrolled; it is never the current step")
