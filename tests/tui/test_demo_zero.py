"""The demo's robot never stops moving: Enter at the zero step while it is away from the
fixture zeroed the indicators at their free travel (-0.375 in), and every later "cycle" was then
taken away from the fixture (all +0.00000). The engine now zeroes only with the robot at rest at
the fixture (never at the plungers' stop), whichever front end asks and whenever Enter is
pressed: here while the robot is away, approaching, or just about to leave."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from station.session.model import load_session
from station.tui.app import DemoPort, StationApp, StationConfig
from station.tui.instruments import DemoLab

PERIOD = 2.0


@pytest.fixture
def moving_lab() -> Iterator[DemoLab]:
    """The demo's repeatability fixture with the robot leaving and returning every 2 s."""
    lab = DemoLab(1990, cycle_period=PERIOD)
    try:
        yield lab
    finally:
        lab.stop()


def _in_stage(lab: DemoLab, wanted: str, after: float = 0.0) -> bool:
    """True when the demo's robot is in stage ``wanted``, at least ``after`` into it."""
    simulator = lab.fixture("repeatability").simulator
    _, stage, into = simulator.motion.stage(time.monotonic() - simulator.motion_t0)
    return stage == wanted and into >= after


@pytest.mark.parametrize(
    ("stage", "after"), [("away", 0.0), ("approaching", 0.0), ("at rest", 0.8)]
)
async def test_enter_at_the_zero_step_at_any_moment_zeroes_at_the_fixture(
    tmp_path: Path, moving_lab: DemoLab, tui, stage: str, after: float
) -> None:
    from station.tui.screens.checklist import ChecklistScreen

    fixture = moving_lab.fixture("repeatability")
    port = DemoPort(
        url=fixture.url,
        protocol=fixture.protocol,
        channel_map=dict(fixture.channel_map),
        procedure="repeatability",
        trigger=fixture.trigger,
        count=3,
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
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        while app.runner.state().action.kind != "zero":
            before = app.runner.state().current.index
            await tui.wait_until(pilot, lambda: not app.screen.busy)
            app.screen.action_confirm()
            await tui.wait_until(
                pilot, lambda before=before: app.runner.state().current.index != before
            )
        await tui.wait_until(pilot, lambda: not app.screen.busy)
        # Enter at that moment of the simulated robot's loop.
        await tui.wait_until(pilot, lambda: _in_stage(moving_lab, stage, after), timeout=3 * PERIOD)
        app.screen.action_confirm()
        await tui.wait_until(
            pilot, lambda: app.runner.state().action.kind != "zero", timeout=4 * PERIOD
        )
        path = app.runner.state().path
    zero = load_session(path, recover=False).zeroes[-1]
    for channel, spec in zero["channels"].items():
        # At rest the indicators read within a few thousandths of their own zero; away, -0.375.
        assert abs(spec["offset"]) < 0.01, (channel, spec)
