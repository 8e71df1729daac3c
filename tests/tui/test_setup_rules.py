"""The set-up reads limits and channel maps with ``station.text``'s rules, the ones the command
line uses (issue 9: one place for text in; the stricter rule wins): a channel map that names a
device channel twice and an infinite limit, which the screen's own parser let through, are
refused under their fields with the command line's sentences."""

from __future__ import annotations

from pathlib import Path

import pytest
from textual.widgets import Input, Static

from station.errors import StationError
from station.text import parse_channel_map, parse_limits_text
from station.tui.app import StationApp, StationConfig


def _sentence(typed: str, parse) -> str:
    with pytest.raises(StationError) as refused:
        parse(typed)
    return refused.value.message


async def test_the_set_up_refuses_what_the_command_line_refuses(
    tmp_path: Path, fixture_pty, tui
) -> None:
    from station.tui.screens.setup import SetupScreen

    app = StationApp(StationConfig(sessions_dir=tmp_path, sessions_reason="test folder"))
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R10", fixture_pty.url)
        screen = app.screen
        screen.query_one("#map", Input).value = "1=x,1=y,3=z"
        screen.query_one("#limits-x", Input).value = "-1e999:0.001"
        await pilot.press("f2")
        await pilot.pause(0.3)
        assert isinstance(app.screen, SetupScreen)  # nothing started
        said = {
            field: str(screen.query_one(f"#{field}-error", Static).render())
            for field in ("map", "limits-x")
        }
        assert _sentence("1=x,1=y,3=z", parse_channel_map) in said["map"], said
        assert _sentence("-1e999:0.001", parse_limits_text) in said["limits-x"], said
        assert "twice" in said["map"] and "finite" in said["limits-x"]
    assert not list(tmp_path.glob("*.jsonl"))
