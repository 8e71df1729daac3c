"""An ISO 230-2 positioning test through the TUI at 80×24, by keyboard, against a simulated axis
with a known positioning error and backlash on a real pty: the set-up counts runs of the test
cycle, the targets are typed, the scale zeroed at the reference, each run's ten stops captured
(the axis following the steps, as the demo's does), and the summary is the ISO 230-2 report."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from station.instruments.axis_model import AxisPositioningModel
from station.instruments.protocols import get_protocol
from station.instruments.simulator import Simulator
from station.tui.instruments import DemoFixture, track
from tests.tui.test_tui_method_procedures import (
    PROTOCOL,
    analyze_json,
    run_procedure,
    text_of,
    tui_app,
)

TARGETS = (10.3, 97.6, 203.1, 301.9, 398.4)
BACKLASH = 0.020
RUNS = 3
"""Runs of the test cycle (ISO 230-2 asks for 5; 3 keep the test short and give each target 3
approaches each way, which the report notes)."""


@pytest.fixture
def axis() -> Iterator[str]:
    """The simulated axis on a pty, followed by the session's steps; its URL."""
    model = AxisPositioningModel(TARGETS, slope=5e-5, backlash=BACKLASH, noise=0.002)
    simulator = Simulator(get_protocol(PROTOCOL), model, seed=4, channel_map={"1": "s"})
    url = simulator.start_pty()
    fixture = track(DemoFixture(url, PROTOCOL, {"1": "s"}, simulator))
    try:
        yield url
    finally:
        fixture.stop()


async def test_a_positioning_test_through_the_tui(tmp_path: Path, axis: str, tui) -> None:
    app = tui_app(tmp_path)
    typed = {f"target_{i}": str(t) for i, t in enumerate(TARGETS, start=1)}
    async with app.run_test(size=(80, 24)) as pilot:
        await run_procedure(pilot, tui, "positioning", axis, "1=s", str(RUNS), lambda _: typed)
        report = text_of(app, "#summary-report")
        assert f"AXIS POSITIONING (ISO 230-2): 5 targets, {RUNS * 10} approaches" in report
        assert "note: 5 target(s) approached fewer than 5 times in a direction" in report
        assert f"5 targets, {RUNS * 10} approaches" in text_of(app, "#summary-title")
        assert "judges no readings" in text_of(app, "#summary-verdict")
        view = app.screen.view
    figures = analyze_json(view.path)["iso230_2"]
    assert [t["target"] for t in figures["targets"]] == list(TARGETS)
    assert all(t["n_up"] == t["n_down"] == RUNS for t in figures["targets"])
    # The axis loses 0.020 mm at each reversal (σ 0.002 mm per stop: 3 runs resolve it).
    assert figures["B_mean"] == pytest.approx(-BACKLASH, abs=0.004)
