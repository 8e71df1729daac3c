"""``capture`` and ``cycles``: steps that take reading sets.

A ``capture`` step is done by one recorded set; a ``cycles`` step takes sets up to its target
and is done by the operator's confirm once it has its minimum (``station capture`` confirms at
the target). A set becomes a cycle only when every channel the step needs has a fresh reading
from this trigger; a missing, stale or duplicated channel is an operator message and nothing is
written. Cycles are numbered over the whole session by the engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from station.errors import StationError
from station.procedures import StepSchema
from station.run.state import Action, CycleOutcome, Progress
from station.run.steps.base import PlanItem, StepHandler

if TYPE_CHECKING:
    from station.run.engine import Runner


class SetStep(StepHandler):
    """What capture and cycles steps share: a capture takes one set (the engine waits for a
    pushed or arrived set, or polls the gauges) and records it through :meth:`accept_set`."""

    takes_sets = True

    def counts(self, run: Runner, item: PlanItem) -> tuple[int, int]:
        """(target, minimum) accepted sets."""
        return (1, 1)

    def entered(self, run: Runner, item: PlanItem) -> None:
        # With the arrival trigger, the robot's next round trip from now is the first cycle.
        run.arm_trigger()

    def action(self, run: Runner, item: PlanItem) -> Action:
        target, minimum = self.counts(run, item)
        done = run.accepted_in(item)
        paced = run.devices_pace
        if done >= target:
            # Still the capture family (the dashboard stays up), with nothing left to take.
            prompt = f"All {target} cycles are recorded: go on, or finish."
            return Action("capture", prompt=prompt, may_confirm=True, paced_by_devices=paced)
        return Action(
            "capture",
            prompt=self.prompt(run, item),
            may_confirm=done >= minimum,
            paced_by_devices=paced,
        )

    def capture(self, run: Runner, item: PlanItem, timeout: float, by: str) -> CycleOutcome:
        return run.take_set(timeout, by)

    def accept_set(self, run: Runner, item: PlanItem, result: Any, by: str) -> CycleOutcome:
        target, _ = self.counts(run, item)
        if run.accepted_in(item) >= target:
            # The set-up asked for N: more is a change of plan, not a capture.
            return run.refuse(
                f"All {target} cycles are recorded; this reading set was not. Go on, or finish."
            )
        problem = run.set_problem(result, item.step.channels)
        if problem:
            outcome = run.refuse(f"Not recorded: {problem} Capture again.")
            if getattr(result, "port_down", False):
                outcome = CycleOutcome(False, outcome.message, port_down=True)
            return outcome
        readings = {ch: result.readings[ch] for ch in item.step.channels}
        outcome = run.write_cycle(item, readings, by, **self.cycle_fields(run, item))
        trace = getattr(result, "trace", None)
        if trace is not None and outcome.cycle is not None:
            run.write_trace(item, outcome.cycle.cycle, trace)
        self.after_cycle(run, item, by)
        return outcome

    def cycle_fields(self, run: Runner, item: PlanItem) -> dict[str, Any]:
        """What the step records with the next cycle besides its readings (a part)."""
        return {}

    def after_cycle(self, run: Runner, item: PlanItem, by: str) -> None:
        """What a recorded cycle does to the step (complete it, or say the target is met)."""


class CaptureStep(SetStep):
    """One reading set, then the step is done."""

    kind = "capture"
    schema = StepSchema(channels=True)

    def confirm(self, run: Runner, item: PlanItem, by: str) -> None:
        raise StationError("this step records one reading set: capture it")

    def after_cycle(self, run: Runner, item: PlanItem, by: str) -> None:
        run.complete_step(item, by)


class CyclesStep(SetStep):
    """N cycles with a per-cycle prompt; done by the operator once at least the minimum is in."""

    kind = "cycles"
    schema = StepSchema(channels=True, counts=True)

    def counts(self, run: Runner, item: PlanItem) -> tuple[int, int]:
        """The set-up's count applies to steps outside repeat blocks."""
        step = item.step
        target = (
            run.setup.resolved_cycles if item.placement is None else int(step.count_target or 1)
        )
        return target, min(int(step.count_min or target), target)

    def progress(self, run: Runner, item: PlanItem) -> Progress:
        target, minimum = self.counts(run, item)
        return Progress(run.accepted_in(item), target, minimum, "cycle")

    def prompt(self, run: Runner, item: PlanItem) -> str:
        """The step's per-cycle prompt. Outside a repeat block ``{cycle}`` is the number the
        next cycle is recorded under; once a rejected cycle makes it differ from the count of
        accepted ones, both are said: ``Cycle 5 (4 of 30 accepted)``."""
        if not item.step.prompt:
            return super().prompt(run, item)
        target, _ = self.counts(run, item)
        ordinal = min(run.accepted_in(item) + 1, target)
        number = run.next_cycle
        if item.placement is not None or number == ordinal:
            return item.step.prompt_for(ordinal, target)
        # Numbers by the record: the prompt names the cycle the file and the reports will.
        counted = f"{number} ({ordinal} of {target} accepted)"
        text = item.step.prompt.replace("{cycle} of {count}", counted)
        return text.replace("{cycle}", str(number)).replace("{count}", str(target))

    def confirm(self, run: Runner, item: PlanItem, by: str) -> None:
        if run.busy:
            # The set being taken belongs to this step: going on now would file it under the
            # next one.
            raise StationError("a capture is under way: wait for it to end")
        done = run.accepted_in(item)
        target, minimum = self.counts(run, item)
        if done < minimum:
            raise StationError(
                f"only {done} of {target} cycles are recorded; capture at least "
                f"{minimum - done} more before going on"
            )
        if done < target:
            run.say("warning", f"Going on with {done} cycles, fewer than the {target} asked for.")
        run.complete_step(item, by)

    def after_cycle(self, run: Runner, item: PlanItem, by: str) -> None:
        target, _ = self.counts(run, item)
        if run.accepted_in(item) == target:
            run.say("info", f"All {target} cycles are recorded: go on, or finish.")
