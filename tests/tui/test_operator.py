"""Issue 13, the operator at 80×24: what a technician sees and presses, in Pilot against the
seeded simulator on a real pty."""

from __future__ import annotations

from pathlib import Path

from textual.widgets import Input, Static

from station.session.model import load_session
from station.tui.app import StationApp, StationConfig


def _app(folder: Path) -> StationApp:
    return StationApp(
        StationConfig(sessions_dir=folder, sessions_reason="test folder", capture_timeout=3.0)
    )


async def test_ctrl_c_in_the_note_dialog_asks_and_keeps_the_typed_note(
    tmp_path: Path, fixture_pty, tui
) -> None:
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.dialogs import QuitQuestion, TextPrompt

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R6", fixture_pty.url)
        await pilot.press("f2")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, TextPrompt))
        await pilot.press(*"dial 2 loose")
        await pilot.press("ctrl+c")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, QuitQuestion))
        question = " ".join(str(s.render()) for s in app.screen.query(Static))
        assert "dial 2 loose" in question and "not saved" in question
        await pilot.press("n")  # back to the dialog, the text still there
        await tui.wait_until(pilot, lambda: isinstance(app.screen, TextPrompt))
        assert app.screen.query_one(Input).value == "dial 2 loose"
        await pilot.press("enter")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        await pilot.pause(0.2)
        # Ctrl+C twice inside a dialog quits; the session stays resumable.
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, TextPrompt))
        await pilot.press("ctrl+c")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, QuitQuestion))
        await pilot.press("ctrl+c")
        await pilot.pause(0.3)
    assert app.return_code == 0
    session = load_session(next(tmp_path.glob("*.jsonl")), recover=False)
    assert any(note.get("text") == "dial 2 loose" for note in session.notes)
    assert session.status == "interrupted"


def _visible_text(app: StationApp) -> str:
    return " ".join(str(w.render()) for w in app.screen.query(Static) if w.display and w.region)


async def test_a_terminal_below_the_minimum_shows_a_notice_not_broken_tables(
    tmp_path: Path, fixture_pty, tui
) -> None:
    from station.tui.screens.dashboard import DashboardScreen
    from station.tui.widgets.too_small import TooSmallNotice

    app = _app(tmp_path)
    async with app.run_test(size=(60, 20)) as pilot:
        await pilot.pause()
        notice = app.screen.query_one(TooSmallNotice)
        assert notice.region.width == 60 and "Terminal too small: 60×20" in str(notice.render())
        assert not app.screen.query_one("#home-choices").region
        assert "Sessions folder" not in _visible_text(app)
        await pilot.resize_terminal(80, 24)
        await pilot.pause(0.2)
        assert not app.screen.query_one(TooSmallNotice).region
        assert app.screen.query_one("#home-choices").region
        assert "Sessions folder" in _visible_text(app)
        await tui.open_setup(pilot, "R4", fixture_pty.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        await tui.capture_one(pilot)
        assert isinstance(app.screen, DashboardScreen)
        # Six columns: the notice, no crash; captures still work.
        await pilot.resize_terminal(6, 10)
        await pilot.pause(0.2)
        await tui.capture_one(pilot)
        notice = app.screen.query_one(TooSmallNotice)
        assert notice.region.width == 6
        await pilot.resize_terminal(80, 24)
        await pilot.pause(0.2)
        assert not app.screen.query_one(TooSmallNotice).region
        assert len(app.runner.state().cycles) == 2
