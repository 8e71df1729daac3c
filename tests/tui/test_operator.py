"""Issue 13, the operator at 80×24: what a technician sees and presses, in Pilot against the
seeded simulator on a real pty."""

from __future__ import annotations

from pathlib import Path

import pytest
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


# ---- NO_COLOR: the verdict and the alarms by attribute, never only by colour or shade -------

SNAPSHOT_SESSIONS = Path(__file__).resolve().parent / "snapshots"


def _luminance(color) -> float:
    red, green, blue = color.get_truecolor() if color is not None else (128, 128, 128)

    def channel(value: int) -> float:
        c = value / 255
        return c / 12.92 if c <= 0.03928 else ((c + 0.055) / 1.055) ** 2.4

    return 0.2126 * channel(red) + 0.7152 * channel(green) + 0.0722 * channel(blue)


def _segments_of(app: StationApp, word: str) -> list:
    """The drawn segments (after Textual's NO_COLOR filter) that carry ``word``."""
    found = []
    for strip in app.screen._compositor.render_strips():
        for segment in strip:
            if word in segment.text:
                found.append(segment)
    assert found, f"{word!r} is not on the screen"
    return found


def assert_reads_without_colour(segment) -> None:
    """Bold or reverse video, not dim, and a foreground that stands off its background (the
    WCAG contrast ratio of 4.5: grey 237 on 234, the issue's verdict, is 1.1)."""
    style = segment.style
    assert style.bold or style.reverse, f"{segment.text!r} only by colour: {style}"
    assert not style.dim, f"{segment.text!r} is dim: {style}"
    fore, back = _luminance(style.color), _luminance(style.bgcolor)
    ratio = (max(fore, back) + 0.05) / (min(fore, back) + 0.05)
    assert ratio >= 4.5, f"{segment.text!r} is a shade on a shade ({ratio:.1f}): {style}"


@pytest.mark.parametrize(
    ("variable", "value"), [("NO_COLOR", "1"), ("STATION_THEME", "high-contrast")]
)
async def test_no_color_summary_verdict_reads_by_attribute(
    monkeypatch, tui, variable: str, value: str
) -> None:
    from station.tui.screens.summary import SummaryScreen

    monkeypatch.chdir(SNAPSHOT_SESSIONS)
    monkeypatch.setenv(variable, value)
    app = _app(Path("sessions"))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("v")
        await pilot.pause()
        await pilot.press("enter")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        await pilot.pause(0.2)
        verdicts = _segments_of(app, "CAPABLE")
        for segment in verdicts:
            assert_reads_without_colour(segment)
        # NOT CAPABLE stands apart from CAPABLE by more than a shade: reverse video.
        for segment in verdicts:
            if "NOT CAPABLE" in segment.text:
                assert segment.style.reverse


async def test_no_color_alarm_lines_read_by_attribute(
    tmp_path: Path, monkeypatch, fixture_pty, tui
) -> None:
    from station.tui.widgets.alarm_log import AlarmLog

    monkeypatch.setenv("NO_COLOR", "1")
    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R1", fixture_pty.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        log = app.screen.query_one(AlarmLog)
        for _ in range(25):
            await tui.capture_one(pilot)
            if "⚠" in str(log.render()):
                break
        await pilot.pause(0.3)
        assert "⚠" in str(log.render()), "the seeded simulator's warming-up z raised no alarm"
        for segment in _segments_of(app, "alarms ("):
            assert_reads_without_colour(segment)
        for segment in _segments_of(app, "⚠"):
            assert_reads_without_colour(segment)


async def test_command_palette_runs_the_screens_actions_and_question_mark_lists_keys(
    tmp_path: Path, fixture_pty, tui
) -> None:
    from textual.command import CommandPalette

    from station.tui.screens.dashboard import DashboardScreen
    from station.tui.screens.dialogs import HelpScreen

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R7", fixture_pty.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        assert isinstance(app.screen, DashboardScreen)
        # ? lists the keys of this screen, by key and by what it does.
        await pilot.press("question_mark")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, HelpScreen))
        keys = str(app.screen.query_one("#help-keys", Static).render())
        for expected in ("space", "Capture", "Reject", "Pause", "Finish", "Ctrl+P"):
            assert expected.lower() in keys.lower(), keys
        await pilot.press("escape")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
        # Ctrl+P: every action by name; "Pause" runs the dashboard's own action.
        await pilot.press("ctrl+p")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, CommandPalette))
        await pilot.press(*"Pause")
        await pilot.pause(0.5)
        await pilot.press("enter")
        await tui.wait_until(pilot, lambda: app.runner.state().status == "paused")
        assert isinstance(app.screen, DashboardScreen)
        commands = [c.title for c in app.get_system_commands(app.screen)]
        for expected in ("Capture", "Reject", "Note", "Finish", "Leave", "Keys of this screen"):
            assert expected in commands, commands
