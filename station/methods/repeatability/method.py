"""The repeatability method: each channel's readings judged as the report does (§2.6, §2.7),
with the gauge checks that covered its gauges when the session began."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from station.analysis.summary import analyze
from station.methods.contract import DemoRig, Judgement, Method, MethodInputs
from station.session.gauge_register import coverage_fields, gauge_block

if TYPE_CHECKING:
    from station.instruments.simulator import GaugeSpec


class Repeatability(Method):
    """Repeatability at one taught point (the default method)."""

    name = "repeatability"
    title = "BASIC STATISTICS COMPREHENSIVE REPORT"
    demo_words = "three dial indicators in one fixture"

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The report's statistics of every channel, and the gauge checks' block."""
        analysis = (
            analyze(
                dict(inputs.channels),
                inputs.config,
                excluded_cycles=inputs.excluded_cycles,
                cycles=inputs.cycles,
                times=inputs.times,
            )
            if inputs.channels
            else None
        )
        return Judgement(analysis, None, gauge_block(inputs.header, inputs.width))

    def header_fields(self, fields: Mapping[str, Any]) -> dict[str, Any]:
        """The gauge checks that cover its gauges, from the gauge register at the start."""
        return coverage_fields(fields)

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """A robot that repeats well in x, sits a little off nominal in y and warms up (drifts)
        in z, so the demo shows each kind of verdict and a control-chart alarm; it can run a
        playback loop."""
        # Deferred, as every demo set-up: the simulator loads only for the demo.
        from station.instruments.simulator import AxisModel, FixtureModel

        model = FixtureModel(
            {
                "x": AxisModel(bias=0.0, noise=0.00022),
                "y": AxisModel(bias=0.00025, noise=0.00036, skew=2.0),
                "z": AxisModel(bias=-0.0002, noise=0.00012, drift=0.0005, drift_tau=6.0),
            },
            gauge,
        )
        return DemoRig(model, "simulated dial indicators (seeded)", loops=True)


METHOD = Repeatability()
