"""``zero``: zero the indicators at the taught pose (the gauge's own command where it has one,
else a software offset from the readings)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from station.errors import StationError
from station.instruments.zeroing import DEFAULT_ZERO_SETTLE, DEFAULT_ZERO_STILL
from station.procedures import StepSchema
from station.run.state import Action
from station.run.steps.base import PlanItem, StepHandler

if TYPE_CHECKING:
    from station.run.engine import Runner

ZERO_TIMEOUT = 5.0
ZERO_READINGS = 5
"""Readings per channel of a zero step without ``readings`` (polled, or under ``arrival``)."""
PUSH_ZERO_READINGS = 3
"""DATA presses a zero step without ``readings`` asks for under the ``push`` trigger: each press
sends one reading per gauge, and a technician presses three times with the robot still rather
than ten (the zero is their mean; a gauge that moved between the presses is named)."""


class ZeroStep(StepHandler):
    """Done when the ``zero`` event (per channel: method and offset) is on disk."""

    kind = "zero"
    schema = StepSchema(channels=True, zero_window=True)
    confirm_waits = True

    def action(self, run: Runner, item: PlanItem) -> Action:
        return Action("zero", prompt=self.prompt(run, item))

    def prompt(self, run: Runner, item: PlanItem) -> str:
        text = super().prompt(run, item)
        if run.setup.trigger != "push":
            return text
        presses = self.readings(run, item)
        # A push gauge sends only when its DATA button (or foot switch) is pressed.
        return f"{text} Press DATA {presses} times, the robot still: the zero is their mean."

    def confirm(self, run: Runner, item: PlanItem, by: str) -> None:
        # Confirming a zero step is zeroing: the engine releases its lock for the wait.
        run.zero(by=by)

    @staticmethod
    def default_readings(run: Runner) -> int:
        """Readings per channel when the step does not say: one reading is no zero (its noise
        shifts every later reading), so always several, taken while every gauge is still: 5
        polled or under ``arrival``, 3 DATA presses under ``push``."""
        return PUSH_ZERO_READINGS if run.setup.trigger == "push" else ZERO_READINGS

    def readings(self, run: Runner, item: PlanItem) -> int:
        """Readings per channel this zero step takes: the step's own, else the default."""
        return item.step.readings or self.default_readings(run)

    def zero(self, run: Runner, item: PlanItem, by: str, timeout: float) -> None:
        """The mean of the step's ``readings`` (when it gives them) per channel over its
        ``settle`` seconds
        (refused, naming the channel, while a channel's readings spread over more than ``still``
        resolutions: the robot or a gauge moves). A port that is down is waited for until
        ``timeout``; a gauge reading in another unit than the session's is refused (nothing
        zeroed). The event records per channel the method, offset, n, mean, spread, readings
        and the zero's standard uncertainty."""
        step = item.step
        with run.lock:
            run.claim()
        try:
            results = run.gauges.zero(
                list(step.channels),
                timeout,
                unit=run.setup.resolved_unit,
                readings=self.readings(run, item),
                settle=step.settle if step.settle is not None else DEFAULT_ZERO_SETTLE,
                still=step.still if step.still is not None else DEFAULT_ZERO_STILL,
            )
        except StationError as error:
            with run.lock:
                run.release()
                run.say("error", error.message)
            raise
        except BaseException:
            with run.lock:
                run.release()
            raise
        # Where each plunger rests free, as far as the gauges know it: the record shows the
        # zero was taken away from it.
        stops = run.gauges.stops()
        with run.lock:
            run.release()
            run.ensure_open()
            event = run.append(
                "zero",
                step=item.step.id,
                placement=item.placement,
                channels={
                    result.channel: {
                        **result.record(),
                        "uncertainty": result.uncertainty,
                        **({"stop": stops[result.channel]} if result.channel in stops else {}),
                    }
                    for result in results
                },
                by=by,
            )
            run.zero_recorded(event)
            run.complete_step(item, by)
