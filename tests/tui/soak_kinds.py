"""A step kind and an analysis kind that the station does not ship, registered from outside
(the tests), to show that a new kind needs no change to the engine or the front ends.

``soak``: a step that takes ``readings`` reading sets (a key of its own in the procedure file)
and is done after them. ``spread``: an analysis kind judging each channel's readings as
repeatability does, with a report block of its own (the range per channel) and JSON under
``spread``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from station.procedures import StepSchema
from station.run.state import Action, Progress
from station.run.steps import register as register_step
from station.run.steps.sets import SetStep
from station.verdicts import AnalysisKind, Judgement, KindInputs, LiveCycles
from station.verdicts import register as register_kind

SOAK_PROCEDURE = b"""
id = "soak-check"
title = "Readings at rest after a soak"
version = "1"
report_section = "test"
channels = ["x", "y", "z"]
unit = "in"
resolution = 0.0001
analysis = "spread"

[limits]
tolerance = 0.002

[[steps]]
id = "fixture"
kind = "check"
title = "Fix the fixture"

[[steps]]
id = "soak"
kind = "soak"
title = "Soak readings"
text = "Leave the robot at the taught point."
readings = 3
"""


class SoakStep(SetStep):
    """Takes ``readings`` sets, then the step is done by itself."""

    kind = "soak"
    schema = StepSchema(channels=True, keys=("readings",))

    def counts(self, run: Any, item: Any) -> tuple[int, int]:
        wanted = int(item.step.options.get("readings", 1))
        return wanted, wanted

    def progress(self, run: Any, item: Any) -> Progress:
        target, minimum = self.counts(run, item)
        return Progress(run.accepted_in(item), target, minimum, "reading")

    def action(self, run: Any, item: Any) -> Action:
        return Action("capture", prompt=self.prompt(run, item))

    def after_cycle(self, run: Any, item: Any, by: str) -> None:
        target, _ = self.counts(run, item)
        if run.accepted_in(item) >= target:
            run.complete_step(item, by)


def _spread(inputs: KindInputs) -> Judgement:
    from station.verdicts import kind_of

    judged = kind_of("repeatability").batch(inputs)
    ranges = {name: float(np.ptp(values)) for name, values in inputs.channels.items()}
    block = ("SPREAD", *(f"{name} range {value:.5f}" for name, value in ranges.items()))
    return Judgement(judged.analysis, ranges, (block,))


def register() -> None:
    """Register both kinds (idempotent); the suite's registries lose them after each test."""
    register_step(SoakStep())
    register_kind(
        AnalysisKind(
            name="spread",
            title="SPREAD REPORT",
            batch=_spread,
            live=LiveCycles,
            json_key="spread",
            json=lambda ranges: dict(ranges),
            count=lambda ranges: f"{len(ranges)} channels",
        )
    )
