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
    write_repeatability(
        sessions, robot="KSC-7", seed=2, bias={"y": 0.0004}, created=WHEN + timedelta(days=30)
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
