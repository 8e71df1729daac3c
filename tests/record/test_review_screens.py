"""The record from the TUI's review list: a robot's history (h) and a comparison of two sessions
(m on the before, c on the after), as ``station history`` and ``station compare`` print them."""

from __future__ import annotations

import time
from datetime import timedelta

from textual.widgets import Static

from station.tui.app import StationApp, StationConfig
from station.tui.screens.home import HomeScreen
from station.tui.screens.record import RecordScreen
from station.tui.screens.review import ReviewScreen

from .conftest import WHEN, write_repeatability


async def _until(pilot, condition, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {condition}"
        await pilot.pause(0.05)


def _text(app: StationApp) -> str:
    return str(app.screen.query_one("#record-text", Static).render())


async def test_history_and_compare_from_the_review_list(sessions):
    write_repeatability(sessions, robot="KSC-7", seed=1)
    # Each session zeroes on its own: y's shift must stand out beyond the two zeros' (σ·√2).
    write_repeatability(
        sessions, robot="KSC-7", seed=2, bias={"y": 0.0012}, created=WHEN + timedelta(days=30)
    )
    app = StationApp(StationConfig(sessions_dir=sessions, sessions_reason="test folder"))
    async with app.run_test(size=(80, 24)) as pilot:
        await _until(pilot, lambda: isinstance(app.screen, HomeScreen))
        app.push_screen(ReviewScreen())
        await _until(pilot, lambda: isinstance(app.screen, ReviewScreen))
        await pilot.pause()
        await pilot.press("h")
        await _until(pilot, lambda: isinstance(app.screen, RecordScreen))
        await _until(pilot, lambda: "Working" not in _text(app))
        history = _text(app)
        assert "KSC-7" in history and "2 session" in history, history
        await pilot.press("escape")
        await _until(pilot, lambda: isinstance(app.screen, ReviewScreen))
        await pilot.press("c")  # nothing marked yet: a sentence, no screen
        await pilot.pause()
        assert isinstance(app.screen, ReviewScreen)
        await pilot.press("m", "down", "c")
        await _until(pilot, lambda: isinstance(app.screen, RecordScreen))
        await _until(pilot, lambda: "Working" not in _text(app))
        compared = _text(app)
        assert "A (before)" in compared and "B (after)" in compared, compared
        assert "y moved" in compared, compared


async def test_a_tui_session_of_a_robot_with_a_baseline_records_it(sessions, tmp_path):
    """Phase II from the robot's baseline: a session the TUI starts for that robot and
    procedure records the baseline in its header (its live alarms test against it)."""
    from station.record.baseline import store_baseline
    from station.tui.instruments import start_demo_fixture

    filed = write_repeatability(sessions, robot="R1", seed=4, alarm=False, reject=None)
    store_baseline("R1", filed)
    fixture = start_demo_fixture(1990)
    (tmp_path / "new").mkdir()
    app = StationApp(StationConfig(sessions_dir=tmp_path / "new", sessions_reason="test"))
    try:
        async with app.run_test(size=(80, 24)) as pilot:
            await _until(pilot, lambda: isinstance(app.screen, HomeScreen))
            await pilot.press("n")
            await _until(pilot, lambda: app.screen.query("#port"))
            await pilot.pause()
            await pilot.press(*"R1")
            app.screen.query_one("#port").value = fixture.url
            app.screen.query_one("#map").value = "1=x,2=y,3=z"
            app.screen.query_one("#trigger").value = "poll"
            await pilot.press("f2")
            await _until(pilot, lambda: app.runner is not None)
            recorded = app.runner.header.get("baseline")
            assert recorded and set(recorded["limits"]) == {"x", "y", "z"}, recorded
            assert recorded["session"] and recorded["anchor"]
            app.interrupt_session("test over")
    finally:
        fixture.stop()
