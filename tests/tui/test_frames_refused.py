"""Gauges whose frames disagree with the session's unit and resolution are refused in the TUI
(Pilot): by the connection test (F3) and by the start (F2), before any file is written, with a
sentence naming both."""

from __future__ import annotations

from pathlib import Path

from textual.widgets import Static

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec, Simulator
from station.tui.app import StationApp, StationConfig
from station.tui.screens.setup import SetupScreen

BOTH = (
    "the gauges send steps of 0.001, which is mm on this protocol; the session is in inches "
    "at 0.0001"
)


def _text(app: StationApp, selector: str) -> str:
    return str(app.screen.query_one(selector, Static).render())


async def test_a_mm_simulator_against_an_inch_session_is_refused(tmp_path: Path, tui) -> None:
    # A Mitutoyo simulator at its defaults: mm at 0.001; repeatability is in inches at 0.0001.
    model = FixtureModel(dict.fromkeys("xyz", AxisModel(noise=0.01)), GaugeSpec(0.001))
    simulator = Simulator(get_protocol("mitutoyo"), model, seed=2)
    simulator.start_pty()
    app = StationApp(StationConfig(sessions_dir=tmp_path, sessions_reason="test folder"))
    try:
        async with app.run_test(size=(80, 24)) as pilot:
            await tui.open_setup(pilot, "R1", simulator.url)
            setup = app.screen
            await pilot.press("f3")
            await tui.wait_until(pilot, lambda: BOTH in _text(app, "#test-output"), timeout=20)
            await pilot.press("f2")
            await tui.wait_until(
                pilot, lambda: "nothing was written" in _text(app, "#setup-error"), timeout=20
            )
            assert app.screen is setup and isinstance(setup, SetupScreen)
            assert BOTH.capitalize() in _text(app, "#setup-error")
            assert app.runner is None
    finally:
        simulator.stop()
    assert not list(tmp_path.glob("*.jsonl"))
