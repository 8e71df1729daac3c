"""Issue 12, findings 1 and 2: the hostile corpus on every screen, through Pilot at 80×24.

Session headers, notes, reject reasons, procedure titles and step texts, and file names carry
markup (``[/]`` used to crash the home screen with a MarkupError; ``[@click=app.quit]`` would
be a live action), terminal escapes, BEL, a C1 control, a bidi override and 100,000-character
names. Every screen must open, show them as visible text, and put no raw control character on
the terminal.
"""

from __future__ import annotations

import html
import re
import sys
from pathlib import Path

from textual.widgets import DataTable, Input

from station.tui.app import StationApp, StationConfig
from station.tui.screens.checklist import ChecklistScreen
from station.tui.screens.dashboard import DashboardScreen
from station.tui.screens.dialogs import TextPrompt
from station.tui.screens.home import HomeScreen
from station.tui.screens.review import ReviewScreen
from station.tui.screens.setup import SetupScreen
from station.tui.screens.summary import SummaryScreen

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from hostile import (  # noqa: E402
    HOSTILE_PROCEDURE,
    LONG,
    OSC_TITLE,
    hostile_running_session,
    hostile_session,
    raw_controls,
)

SAFE_MARKUP_ROBOT = "KR16 [cell 3] [/] [@click=app.quit]x\u202e"


def screen_text(app: StationApp) -> str:
    """What the terminal shows, as text: the screenshot's characters, unescaped."""
    svg = app.export_screenshot()
    texts = re.findall(r"<text[^>]*>(.*?)</text>", svg, flags=re.DOTALL)
    return html.unescape("".join(texts)).replace("\xa0", " ")


def assert_shown_as_text(app: StationApp) -> str:
    text = screen_text(app)
    assert raw_controls(text) == [], repr(text[:3000])
    return text


async def test_home_review_and_summary_show_hostile_sessions_as_text(tmp_path: Path) -> None:
    folder = tmp_path / "sessions"
    hostile_running_session(folder)
    hostile_session(folder)
    hostile_running_session(folder, robot=LONG)
    # A file name with escapes that does not load (listed as unreadable by its name).
    (folder / f"x{OSC_TITLE}\u202e[b].jsonl").write_text("not a session\n")
    app = StationApp(StationConfig(sessions_dir=folder, sessions_reason="test"))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        assert isinstance(app.screen, HomeScreen), "the home screen must open"
        home = assert_shown_as_text(app)
        assert "KR16 [cell 3]" in home  # not "KR16 " (markup eaten)
        assert "\\x1b]0;pwned" in home

        await pilot.press("v")
        await pilot.pause()
        assert isinstance(app.screen, ReviewScreen)
        review = assert_shown_as_text(app)
        # (the robot column wraps a long name at 80 columns)
        assert "[/] KR16" in review and "[cell 3]" in review
        assert "\\x1b]0;" in review  # the hostile file name, visible
        table = app.screen.query_one(DataTable)
        finished = next(
            index
            for index, summary in enumerate(app.screen._sessions)
            if summary.status == "finished"
        )
        table.move_cursor(row=finished)
        await pilot.press("enter")
        await pilot.pause()
        assert isinstance(app.screen, SummaryScreen)
        summary = assert_shown_as_text(app)
        assert "robot [/] KR16 [cell 3]" in summary
        await pilot.press("escape")
        await pilot.pause()
        await pilot.press("escape")
        await pilot.pause()
        assert isinstance(app.screen, HomeScreen)
        # Resume: the set-up shows the recorded (hostile) header.
        await pilot.press("r")
        await pilot.pause()
        assert isinstance(app.screen, SetupScreen)
        assert_shown_as_text(app)
        recorded = str(app.screen.query_one("#setup-recorded").render())
        # The newest unfinished session is the one with the 100,000-character robot name: it
        # is shown bounded, with an ellipsis; the operator's name is the hostile line.
        assert "robot RRRR" in recorded and "…" in recorded and len(recorded) < 2000
        assert "operator [/] KR16 [cell 3]" in recorded and raw_controls(recorded) == []
    assert app.return_code in (None, 0)


async def test_setup_checklist_dashboard_dialog_and_summary_of_a_hostile_procedure(
    tmp_path: Path, fixture_pty, tui
) -> None:
    procedures = tmp_path / "procedures"
    procedures.mkdir()
    (procedures / "hostile.toml").write_text(HOSTILE_PROCEDURE)
    app = StationApp(
        StationConfig(
            sessions_dir=tmp_path / "sessions",
            sessions_reason="test",
            procedure_dirs=(procedures,),
            capture_timeout=3.0,
        )
    )
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        app.screen.open_new("hostile")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        await pilot.pause()
        setup = assert_shown_as_text(app)
        assert "New session: [/] KR16 [cell 3]" in setup
        screen = app.screen
        screen.query_one("#robot", Input).value = SAFE_MARKUP_ROBOT
        screen.query_one("#port", Input).value = fixture_pty.url
        screen.query_one("#map", Input).value = "1=x,2=y,3=z"
        await pilot.press("f2")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        await pilot.pause()
        checklist = assert_shown_as_text(app)
        assert "[@click=app.quit]press[/]" in checklist

        await pilot.press("enter")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
        await pilot.pause()
        await tui.capture_one(pilot)
        await pilot.pause(0.2)
        dashboard = assert_shown_as_text(app)
        assert "robot KR16 [cell 3] [/] [@click=app.quit]x\\u202e" in dashboard

        await pilot.press("r")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, TextPrompt))
        assert_shown_as_text(app)
        await pilot.press("escape")
        await pilot.pause()
        for _ in range(2):
            await tui.capture_one(pilot)
        await pilot.press("f")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        await pilot.pause()
        summary = assert_shown_as_text(app)
        assert "KR16 [cell 3]" in summary
    assert app.return_code in (None, 0)
