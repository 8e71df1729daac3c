"""A redraw that comes after the app closed (a coalescing timer, a late notice from the engine's
threads) does nothing: it used to raise ScreenStackError while the app shut down."""

from __future__ import annotations

from station.procedures import discover_procedures
from station.run import PortSetup, SessionSetup
from station.tui.app import StationApp, StationConfig
from station.tui.screens.checklist import ChecklistScreen


async def test_a_redraw_after_the_app_closed_does_nothing(tmp_path, fixture_pty, tui):
    app = StationApp(StationConfig(sessions_dir=tmp_path, sessions_reason="test"))
    setup = SessionSetup(
        procedure=discover_procedures(use_env=False).get("repeatability"),
        robot="R-1",
        operator="tester",
        ports=(PortSetup(fixture_pty.url, fixture_pty.protocol, fixture_pty.channel_map),),
        trigger="poll",
    )
    async with app.run_test(size=(80, 24)) as pilot:
        app.start_session(setup)
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        await pilot.pause()
        app.interrupt_session("test over")
    assert not app.screen_stack and app.current_state() is not None
    app.redraw_live()
    app._paint_last_reading()
