"""The "off nominal" hint between an untouched robot and its zero (issue 20): a zero is one rest
of the robot, so the mean of a session carries one draw of its repeatability; the hint weighs
that draw (Var(z), station.analysis.zeros) before it blames the inverse kinematics."""

from __future__ import annotations

import numpy as np

from station.analysis.summary import analyze
from station.instruments.simulator import AxisModel, GaugeSpec, fixture_model
from station.session.header import analysis_config

from .conftest import header_fields, simulated_session

GOOD_ROBOT = AxisModel(noise=0.00008)
INDICATOR = GaugeSpec(0.0001, -0.5, 0.5, "in", noise=0.00003)
SEEDS = 60


def _blamed(header, zeros, readings, channels, *, with_readings: bool) -> int:
    events = [{"type": "zero", **z} for z in zeros] + [{"type": "reading", **r} for r in readings]
    config = analysis_config(header, events[:1], events if with_readings else None)
    values = {c: np.array([r["channels"][c]["value"] for r in readings]) for c in channels}
    hints = analyze(values, config).hints
    return sum("off nominal" in h and "inverse kinematics" in h for h in hints)


def test_an_untouched_robot_is_rarely_blamed_for_its_zeros_draw():
    model = fixture_model("xyz", axis=GOOD_ROBOT, gauge=INDICATOR)
    header = header_fields("repeatability", robot="KSC-7")
    blamed = blamed_in_force = blamed_within_only = 0
    for seed in range(SEEDS):
        zeros, readings = simulated_session(model, seed)
        blamed += _blamed(header, zeros, readings, model.channels, with_readings=True)
        blamed_in_force += _blamed(header, zeros, readings, model.channels, with_readings=False)
        # The old comparison: the zero's within-rest uncertainty only.
        events = [{"type": "zero", **z} for z in zeros]
        old = analysis_config(header, events)
        values = {
            c: np.array([r["channels"][c]["value"] for r in readings]) for c in model.channels
        }
        hints = analyze(values, _without_draws(old)).hints
        blamed_within_only += sum("inverse kinematics" in h for h in hints)
    judged = SEEDS * len(model.channels)
    # About 5 % of channels at a 95 % half-width (5.7 % of 600 measured over 200 seeds; at
    # most 10 % here, within simulation error) ...
    assert blamed <= 0.10 * judged, (blamed, judged)
    # ... the same whether the zero's weight comes from the readings or from the zero in force
    assert blamed_in_force == blamed
    # ... where the within-rest noise alone blamed the robot for its own zero's draw in 37 %.
    assert blamed_within_only >= 0.25 * judged, (blamed_within_only, judged)


def _without_draws(config):
    from dataclasses import replace

    return replace(config, zero_draws={})
