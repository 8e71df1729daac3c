"""``check``: the operator confirms a statement (the fixture is clamped, the robot is taught)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from station.procedures import StepSchema
from station.run.state import Action
from station.run.steps.base import PlanItem, StepHandler

if TYPE_CHECKING:
    from station.run.engine import Runner


class CheckStep(StepHandler):
    """Done when the operator confirms it."""

    kind = "check"
    schema = StepSchema()

    def action(self, run: Runner, item: PlanItem) -> Action:
        return Action("confirm", prompt=self.prompt(run, item))

    def confirm(self, run: Runner, item: PlanItem, by: str) -> None:
        run.complete_step(item, by)
