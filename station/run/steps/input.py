"""``input``: the operator types values (teach-pendant coordinates, a reference size)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from station.errors import StationError
from station.procedures import StepSchema
from station.run.state import Action
from station.run.steps.base import PlanItem, StepHandler

if TYPE_CHECKING:
    from station.run.engine import Runner


class InputStep(StepHandler):
    """Done when its values are recorded (an ``input`` event, then the ``step`` event)."""

    kind = "input"
    schema = StepSchema(fields=True)

    def action(self, run: Runner, item: PlanItem) -> Action:
        return Action("input", prompt=self.prompt(run, item), fields=item.step.fields)

    def confirm(self, run: Runner, item: PlanItem, by: str) -> None:
        raise StationError(
            f"step {item.step.title!r} needs values: type "
            + ", ".join(f.label for f in item.step.fields)
        )

    def submit(self, run: Runner, item: PlanItem, values: Mapping[str, str], by: str) -> None:
        """Each field is checked: a required one must not be empty, a number must parse as a
        finite number; an unknown name is refused. Nothing is written when one is wrong."""
        fields = {f.name: f for f in item.step.fields}
        unknown = sorted(set(values) - set(fields))
        if unknown:
            raise StationError(
                f"step {item.step.title!r} has no field {', '.join(unknown)}; its fields: "
                + ", ".join(fields)
            )
        recorded: dict[str, Any] = {}
        for name, spec in fields.items():
            text = str(values.get(name, "")).strip()
            if not text:
                if spec.required:
                    raise StationError(f"{spec.label} is required: type a value", field=name)
                continue
            if spec.type == "number":
                try:
                    number = float(text)
                except ValueError:
                    number = math.nan
                if not math.isfinite(number):
                    unit = f" in {spec.unit}" if spec.unit else ""
                    raise StationError(
                        f"{spec.label} must be a number{unit}, not {text!r}", field=name
                    )
                recorded[name] = number
            else:
                recorded[name] = text
        run.append("input", step=item.step.id, placement=item.placement, values=recorded, by=by)
        run.complete_step(item, by)
