"""``parts``: one reading of each of ``target`` numbered parts (1 ... n), in a random order
drawn afresh each time the step comes (each placement of a repeated block: one appraiser's
trial of a Gage R&R), so that nobody reads a part by its place in the order or remembers what
it read last time.

The order is drawn when the step becomes current and recorded at once, before any reading: a
``note`` event by the station naming the step and placement, whose ``order`` holds the parts in
turn, so a resumed session presents the rest of the same order. Every reading records its
``part``. The next part is the first of the order without an accepted reading in the step, so a
rejected reading's part comes back next. The prompt fills ``{part}`` (and ``{cycle}``,
``{count}``: the part's place in the order and how many). Every part must be read before the
step is done (a study whose parts were read unequally cannot be analysed): it is done by the
operator's confirm once they are (``station capture`` confirms at once).
"""

from __future__ import annotations

import random
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from station.errors import StationError
from station.procedures import StepSchema
from station.run.state import Action, Progress
from station.run.steps.base import PlanItem
from station.run.steps.sets import SetStep

if TYPE_CHECKING:
    from station.run.engine import Runner

BY = "station"
"""Who wrote the order's note: the station drew it."""


def order_note(
    step_id: str, placement: int | None, placements: int | None, order: list[int]
) -> str:
    """The note's text: ``Parts in this order for step A, 2 of 3: 4, 9, 1.``"""
    where = "" if placement is None else f", {placement} of {placements}"
    return f"Parts in this order for step {step_id}{where}: {', '.join(map(str, order))}."


class PartsStep(SetStep):
    """Every part once, in a fresh random order (see the module)."""

    kind = "parts"
    schema = StepSchema(channels=True, counts=True, parts=True)
    shuffle = random.SystemRandom().shuffle
    """How the order is drawn (a test may put a seeded generator's in its place)."""

    def counts(self, run: Runner, item: PlanItem) -> tuple[int, int]:
        """Every part: the step's target, which is also its minimum."""
        parts = int(item.step.count_target or 1)
        return parts, parts

    def order(self, run: Runner, item: PlanItem) -> list[int]:
        """The parts in the order drawn for this plan item (drawn now if none is; written to
        the file by :meth:`record_order`)."""
        state = run.step_state(item)
        if "order" not in state:
            order = list(range(1, self.counts(run, item)[0] + 1))
            self.shuffle(order)
            state["order"], state["recorded"] = order, False
        return list(state["order"])

    def record_order(self, run: Runner, item: PlanItem) -> None:
        """Write the order's note unless the file has it."""
        order = self.order(run, item)
        state = run.step_state(item)
        if state["recorded"]:
            return
        # Marked first: the note's notice asks for the state, whose prompt reads the order.
        state["recorded"] = True
        run.append(
            "note",
            text=order_note(item.step.id, item.placement, item.placements, order),
            step=item.step.id,
            placement=item.placement,
            order=order,
            by=BY,
        )

    def next_part(self, run: Runner, item: PlanItem) -> int | None:
        """The first part of the order not yet read (None once every part is)."""
        done = run.accepted_parts(item)
        return next((part for part in self.order(run, item) if part not in done), None)

    def entered(self, run: Runner, item: PlanItem) -> None:
        super().entered(run, item)
        self.record_order(run, item)  # on disk before the first part is asked for

    def replay(self, run: Runner, item: PlanItem, event: Mapping[str, Any]) -> None:
        """A recorded order comes back with the session (resume)."""
        order = event.get("order")
        if event.get("type") == "note" and isinstance(order, list):
            state = run.step_state(item)
            state["order"], state["recorded"] = [int(part) for part in order], True

    def action(self, run: Runner, item: PlanItem) -> Action:
        part = self.next_part(run, item)
        paced = run.devices_pace
        if part is None:
            parts, _ = self.counts(run, item)
            prompt = f"All {parts} parts are read: go on."
            return Action("capture", prompt=prompt, may_confirm=True, paced_by_devices=paced)
        return Action("capture", prompt=self.prompt(run, item), paced_by_devices=paced, part=part)

    def progress(self, run: Runner, item: PlanItem) -> Progress:
        parts, _ = self.counts(run, item)
        return Progress(len(run.accepted_parts(item)), parts, parts, "part")

    def prompt(self, run: Runner, item: PlanItem) -> str:
        """``Part 7 (3 of 10): ...``: the step's prompt with the next part filled in."""
        part = self.next_part(run, item)
        parts, _ = self.counts(run, item)
        if part is None:
            return f"All {parts} parts are read: go on."
        place = str(self.order(run, item).index(part) + 1)
        template = item.step.prompt or "Part {part} ({cycle} of {count}): measure it."
        return (
            template.replace("{part}", str(part))
            .replace("{cycle}", place)
            .replace("{count}", str(parts))
        )

    def cycle_fields(self, run: Runner, item: PlanItem) -> dict[str, Any]:
        return {"part": self.next_part(run, item)}

    def accept_set(self, run: Runner, item: PlanItem, result: Any, by: str) -> Any:
        if self.next_part(run, item) is None:
            parts, _ = self.counts(run, item)
            return run.refuse(
                f"All {parts} parts are read; this reading set was not recorded. Go on."
            )
        self.record_order(run, item)  # a reading never comes before its order
        return super().accept_set(run, item, result, by)

    def confirm(self, run: Runner, item: PlanItem, by: str) -> None:
        if run.busy:
            raise StationError("a capture is under way: wait for it to end")
        part = self.next_part(run, item)
        if part is not None:
            parts, _ = self.counts(run, item)
            left = parts - len(run.accepted_parts(item))
            raise StationError(
                f"{left} of {parts} parts are not read yet (part {part} is next): every part "
                "is read once before going on"
            )
        run.complete_step(item, by)

    def after_cycle(self, run: Runner, item: PlanItem, by: str) -> None:
        if self.next_part(run, item) is None:
            parts, _ = self.counts(run, item)
            run.say("info", f"All {parts} parts are read: go on.")
