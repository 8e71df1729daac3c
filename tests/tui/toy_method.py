"""A method and a step kind the station does not ship, offered the way a site's package offers
them (entry points ``station.methods`` and ``station.step_kinds``; :mod:`site_install` installs
them for a test), to show that a new one needs no change to ``station/``.

``soak``: a step that takes ``readings`` reading sets (a key of its own in the procedure file)
and is done after them. ``spread``: a method judging each channel's readings by capability as
repeatability does, with a report block of its own (the range per channel), JSON under
``spread``, a chart of the ranges, and a wide CSV of its own (``cycle`` and the channels, the
table ``station analyze --procedure spread`` reads back).
"""

from __future__ import annotations

import csv
from typing import Any

import numpy as np

from station.analysis.summary import analyze
from station.methods.contract import Judgement, Method, MethodInputs
from station.methods.tables import export_comments, number
from station.procedures import StepSchema
from station.run.state import Action, Progress
from station.run.steps.sets import SetStep

SOAK_PROCEDURE = b"""
id = "soak-check"
title = "Readings at rest after a soak"
version = "1"
report_section = "test"
channels = ["x", "y", "z"]
unit = "in"
resolution = 0.0001
analysis = "spread"

[cycles]
min = 3
target = 3

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


class Spread(Method):
    """Each channel's capability, and its range in a block of its own."""

    name = "spread"
    title = "SPREAD REPORT"
    json_key = "spread"
    export_layout = "wide"

    def batch(self, inputs: MethodInputs) -> Judgement:
        analysis = analyze(
            dict(inputs.channels), inputs.config, cycles=inputs.cycles, times=inputs.times
        )
        ranges = {name: float(np.ptp(values)) for name, values in inputs.channels.items()}
        block = ("SPREAD", *(f"{name} range {value:.5f}" for name, value in ranges.items()))
        return Judgement(analysis, ranges, (block,))

    def json(self, result: Any) -> dict[str, Any]:
        return dict(result)

    def count(self, result: Any) -> str:
        return f"{len(result)} channels"

    def charts(self, inputs: MethodInputs, judgement: Judgement, kit: Any):
        figure = kit.figure()
        axes = figure.add_subplot()
        axes.bar(list(judgement.result), list(judgement.result.values()), color=kit.point)
        axes.set_title("Range of each channel")
        yield "ranges", "Range of each channel", figure

    def write_wide(self, session: Any, out: Any) -> int:
        export_comments(session, out)
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(("cycle", *session.channels))
        for cycle in session.accepted_cycles:
            readings = session.cycles[cycle].readings
            writer.writerow((cycle, *(number(readings[c].value) for c in session.channels)))
        return len(session.accepted_cycles)


METHOD = Spread()
SOAK = SoakStep()
