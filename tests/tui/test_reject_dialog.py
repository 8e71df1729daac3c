"""Issue 26, item 1: under the arrival trigger, `r` titled the dialog "Reject cycle N"; while
the reason was typed cycles N+1 and N+2 arrived, and Enter rejected N+2 (the engine took
whichever cycle was last). The cycle the dialog names is the one rejected. In Pilot, against
the demo's robot that comes back to the fixture every second on its own."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from textual.widgets import Static

from station.session.model import load_session
from station.tui.app import DemoPort, StationApp, StationConfig
from station.tui.instruments import DemoLab

PERIOD = 1.0


@pytest.fixture
def moving_lab() -> Iterator[DemoLab]:
    """The demo's repeatability fixture with the robot returning every second."""
    lab = DemoLab(1990, cycle_period=PERIOD)
    try:
        yield lab
    finally:
        lab.stop()


async def test_the_dialog_rejects_the_cycle_it_names_while_cycles_arrive(
    tmp_path: Path, moving_lab: DemoLab, tui
) -> None:
    from station.tui.screens.dashboard import DashboardScreen
    from station.tui.screens.dialogs import TextPrompt

    fixture = moving_lab.fixture("repeatability")
    assert fixture.trigger == "arrival"
    port = DemoPort(
        url=fixture.url,
        protocol=fixture.protocol,
        channel_map=dict(fixture.channel_map),
        procedure="repeatability",
        trigger=fixture.trigger,
        count=30,
    )
    app = StationApp(
        StationConfig(
            sessions_dir=tmp_path, sessions_reason="test folder", demo=port, demo_lab=moving_lab
        )
    )
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("n")
        await pilot.pause(0.3)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        await tui.wait_until(pilot, lambda: app.runner.state().cycles, timeout=30 * PERIOD)
        # Wait for the dashboard to draw it: `r` names the cycle the screen knows of.
        await tui.wait_until(pilot, lambda: app.current_state().last_cycle is not None)
        await pilot.press("r")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, TextPrompt))
        title = str(app.screen.query_one(".dialog-title", Static).render())
        named = int(title.removeprefix("Reject cycle "))
        await pilot.press(*"cube slipped")
        # The robot keeps coming back while the reason is typed: the next cycle arrives.
        await tui.wait_until(
            pilot, lambda: app.runner.state().last_cycle.cycle > named, timeout=30 * PERIOD
        )
        await pilot.press("enter")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
        await tui.wait_until(pilot, lambda: any(c.rejected for c in app.runner.state().cycles))
        state = app.runner.state()
        path = state.path
        assert [c.cycle for c in state.cycles if c.rejected] == [named]
        assert state.last_cycle.cycle > named and state.last_cycle.rejected is None
    assert load_session(path).rejected == {named: "cube slipped"}
