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
        await pilot.pause(0.2)
        # Finding 9: the session path is not broken mid-word ("...js / onl."): one line.
        where = app.screen.query_one("#step-message", Static)
        assert str(where.render()).startswith("Session file in ") and where.region.height == 1
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


def _terminal_own(color) -> bool:
    return color is None or color.is_default


def assert_reads_without_colour(segment) -> None:
    """Bold or reverse video, not dim, and a foreground that stands off its background (the
    WCAG contrast ratio of 4.5: grey 237 on 234, the issue's verdict, is 1.1)."""
    style = segment.style
    assert style.bold or style.reverse, f"{segment.text!r} only by colour: {style}"
    assert not style.dim, f"{segment.text!r} is dim: {style}"
    if _terminal_own(style.color) and _terminal_own(style.bgcolor):
        return  # NO_COLOR: the terminal's own foreground on its own background, never a shade
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
        # The first saved session may still be provisional (too few strokes): either word.
        drawn = _screen_text(app)
        verdicts = _segments_of(app, "CAPABLE" if "CAPABLE" in drawn else "PROVISIONAL")
        for segment in verdicts:
            assert_reads_without_colour(segment)
        # NOT CAPABLE stands apart from CAPABLE by more than a shade: reverse video.
        assert verdicts, _screen_text(app)
        for segment in verdicts:
            if "NOT CAPABLE" in segment.text:
                assert segment.style.reverse


async def test_no_color_alarm_lines_read_by_attribute(
    tmp_path: Path, monkeypatch, alarming_fixture, tui
) -> None:
    fixture_pty = alarming_fixture
    from station.tui.widgets.alarm_log import AlarmLog

    monkeypatch.setenv("NO_COLOR", "1")
    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R1", fixture_pty.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        log = app.screen.query_one(AlarmLog)
        for _ in range(30):  # live alarms come once the limits freeze (after 25 cycles)
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
        for expected in ("space", "Capture", "Reject", "Pause", "Finish", "^p", "^c"):
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


# ---- the set-up form follows the focus --------------------------------------------------------


def _in_view(screen, widget) -> bool:
    """The widget is drawn whole inside the scrolling form's visible area."""
    form = screen.query_one("#setup-form")
    region = widget.region
    return bool(region) and form.region.contains_region(region)


async def test_the_setup_form_follows_the_focus(tmp_path: Path, monkeypatch, tui) -> None:
    from textual.widgets import Button

    from station.tui.screens.setup import SetupScreen

    monkeypatch.setenv("NO_COLOR", "1")
    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        await pilot.pause(0.3)
        screen = app.screen
        form = screen.query_one("#setup-form")
        # Opens at the top, on the robot, and the Start button is always in view.
        assert form.scroll_y == 0 and screen.focused.id == "robot"
        assert screen.query_one("#start", Button).region
        # Tab walks every field; each one is scrolled into view, its label in reverse video.
        seen = []
        for _ in range(14):
            await pilot.press("tab")
            await pilot.pause(0.1)
            focused = screen.focused
            if isinstance(focused, Button):
                break
            seen.append(focused.id)
            assert _in_view(screen, focused), f"{focused.id} is off-screen after Tab"
            label = focused.parent.query_one(".field-label")
            strips = app.screen._compositor.render_strips()
            row = strips[label.region.y]
            label_text = str(label.render()).strip()
            segment = next(s for s in row if label_text.split()[0] in s.text)
            assert segment.style.reverse, f"the focused {focused.id}'s label is not marked"
        assert {"procedure", "unit", "port", "protocol", "trigger", "map"} <= set(seen)
        # An unfocused field's label is not reversed: the mark means focus.
        strips = app.screen._compositor.render_strips()
        unit_label = screen.query_one("#unit").parent.query_one(".field-label")
        assert not any(
            s.style and s.style.reverse for s in strips[unit_label.region.y] if "Unit" in s.text
        )

        # F2 with errors: the focus goes to the first bad field, in view.
        await pilot.press("f2")
        await pilot.pause(0.3)
        assert screen.focused.id == "robot"
        assert _in_view(screen, screen.focused)
        port_error = screen.query_one("#port-error", Static)
        assert "Name the port" in str(port_error.render()) and port_error.has_class("-shown")
        # Filling the port in clears its stale sentence at once.
        screen.query_one("#port", Input).value = "/dev/ttyUSB9"
        await pilot.pause(0.1)
        assert not port_error.has_class("-shown")


async def test_limits_far_from_the_resolution_ask_naming_the_ratio(
    tmp_path: Path, fixture_pty, tui
) -> None:
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.dialogs import ConfirmScreen
    from station.tui.screens.setup import SetupScreen

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R5", fixture_pty.url)
        screen = app.screen
        screen.query_one("#limits-x", Input).value = "25"  # ±25 in with a 0.0001 in gauge
        await pilot.press("f2")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
        question = " ".join(str(s.render()) for s in app.screen.query(Static))
        assert "500,000 gauge steps" in question and "x:" in question
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        assert app.screen.focused.id == "limits-x"
        assert app.runner is None and not list(tmp_path.glob("*.jsonl"))
        # Too narrow: 0.0003 wide is 3 steps.
        app.screen.query_one("#limits-x", Input).value = "±0.00015"
        await pilot.press("f2")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
        question = " ".join(str(s.render()) for s in app.screen.query(Static))
        assert "only 3 gauge steps" in question
        await pilot.press("y")  # confirmed: it starts
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))


# ---- the set-up remembered between sessions -------------------------------------------------


async def test_the_last_setup_is_offered_prefilled_but_never_applied_to_a_resume(
    tmp_path: Path, fixture_pty, tui
) -> None:
    from textual.widgets import Select

    from station.session.remembered import load_remembered, settings_path
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.dialogs import ConfirmScreen
    from station.tui.screens.home import HomeScreen
    from station.tui.screens.setup import SetupScreen

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "cell-4 KR16", fixture_pty.url, operator="jdoe")
        app.screen.query_one("#map", Input).value = "1=x, 2=y, 3=z"
        app.screen.query_one("#trigger", Select).value = "stable"
        await pilot.pause()
        await pilot.press("f2")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        await pilot.press("q")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
        await pilot.press("y")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, HomeScreen))

    remembered, problem = load_remembered()
    assert problem == "" and settings_path().is_file()
    assert remembered.robot == "cell-4 KR16" and remembered.trigger == "stable"
    assert remembered.channel_map == "1=x,2=y,3=z"

    # The next new session offers them, and says where they come from.
    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        await pilot.pause(0.2)
        screen = app.screen
        assert screen.query_one("#robot", Input).value == "cell-4 KR16"
        assert screen.query_one("#operator", Input).value == "jdoe"
        assert screen.query_one("#port", Input).value == fixture_pty.url
        assert screen.query_one("#map", Input).value == "1=x,2=y,3=z"
        assert screen.query_one("#trigger", Select).value == "stable"
        assert "last session" in str(screen.query_one("#setup-hint", Static).render())
        await pilot.press("escape")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, HomeScreen))

    # A resume shows what its file recorded, not the remembered line.
    from station.session.remembered import RememberedSetup, save_remembered

    save_remembered(RememberedSetup(robot="other", port="/dev/ttyUSB7", trigger="push"))
    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("r")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        await pilot.pause(0.2)
        assert app.screen.query_one("#port", Input).value == fixture_pty.url
        assert app.screen.query_one("#robot", Input).value == "cell-4 KR16"
        assert app.screen.query_one("#trigger", Select).value == "stable"


def test_a_damaged_settings_file_is_said_not_fatal(tmp_path: Path) -> None:
    from station.session.remembered import load_remembered

    damaged = tmp_path / "settings.toml"
    damaged.write_text("[last\nrobot = 'R1'", encoding="utf-8")
    remembered, problem = load_remembered(damaged)
    assert remembered.filled() == {} and "not valid TOML" in problem


# ---- the review list: verdicts, a robot filter, and crashed sessions named so ---------------


def _write(folder: Path, robot: str, cycles: int, end: str | None, minute: int):
    """A real session file through the real writer; ``end``: finish, interrupted or None
    (the writer is returned still open, holding its lock, when ``end`` is "open")."""
    from datetime import UTC, datetime

    from station.analysis.capability import SpecLimits
    from station.procedures import discover_procedures
    from station.run import PortSetup, SessionSetup
    from station.session.journal import SessionWriter

    procedure = discover_procedures(use_env=False).get("repeatability")
    port = PortSetup(url="loop://", protocol="mitutoyo", channel_map={"1": "x", "2": "y", "3": "z"})
    header = SessionSetup(
        procedure=procedure,
        robot=robot,
        operator="ana",
        ports=(port,),
        limits={c: SpecLimits(lsl=-0.001, usl=0.001, nominal=0.0) for c in "xyz"},
    ).header_fields()
    writer = SessionWriter.create(
        folder, header, now=datetime(2026, 11, 23, 12, minute, tzinfo=UTC)
    )
    for cycle in range(1, cycles + 1):
        channels = {
            c: {"value": round(((cycle * 7 + i * 3) % 11 - 5) * 0.0001, 4), "unit": "in"}
            for i, c in enumerate("xyz")
        }
        writer.append("reading", cycle=cycle, step="cycles", channels=channels)
    if end == "open":
        return writer
    if end == "finish":
        writer.append("finish", complete=True, accepted=cycles, rejected=[])
    elif end == "interrupted":
        writer.append("interrupted", reason="SIGHUP")
    writer.close()
    return None


async def test_review_names_verdicts_filters_by_robot_and_calls_a_crash_a_crash(
    tmp_path: Path, tui
) -> None:
    from textual.widgets import DataTable

    from station.tui.screens.dialogs import TextPrompt
    from station.tui.screens.review import ReviewScreen

    _write(tmp_path, "R1", 30, "finish", 1)
    _write(tmp_path, "R2", 5, None, 2)  # the writer went away without a word: a crash
    _write(tmp_path, "R2", 4, "interrupted", 3)
    live = _write(tmp_path, "R3", 3, "open", 4)  # a station is writing it right now
    try:
        app = _app(tmp_path)
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("v")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ReviewScreen))
            table = app.screen.query_one(DataTable)

            def rows() -> list[tuple[str, str]]:
                return [
                    (str(r[0]), str(r[2]))
                    for r in (table.get_row_at(i) for i in range(table.row_count))
                ]

            await tui.wait_until(pilot, lambda: "…" not in [v for _, v in rows()])
            assert [c.label.plain for c in table.ordered_columns][2] == "verdict / state"
            listed = rows()
            assert listed[0][0] == "R1"
            assert listed[0][1] in ("CAPABLE", "NOT CAPABLE", "INCONCLUSIVE")
            assert ("R2", "stopped without a word (crashed?)") in listed
            assert ("R2", "interrupted") in listed
            assert ("R3", "running now") in listed
            # At 80 columns the state is read whole, beside the robot and the date: wrapped
            # in its column when the columns together are wider (issue 26), never cut.
            drawn = _screen_text(app)
            for word in ("stopped", "without", "word", "(crashed?)", "5/30 cycles"):
                assert word in drawn, drawn
            # / shows one robot's sessions.
            await pilot.press("slash")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, TextPrompt))
            await pilot.press("r", "2", "enter")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ReviewScreen))
            await pilot.pause()
            assert {robot for robot, _ in rows()} == {"R2"} and table.row_count == 2
            assert "2 of 4 session(s), robot “r2”" in str(
                app.screen.query_one("#review-folder", Static).render()
            )
    finally:
        live.close()


# ---- relative accuracy at 80×24 ---------------------------------------------------------------


def _screen_text(app: StationApp) -> str:
    """What the terminal shows, row by row (the screen's region of each widget, cropped)."""
    rows = []
    for strip in app.screen._compositor.render_strips():
        rows.append("".join(segment.text for segment in strip))
    return "\n".join(rows)


def _whole_in(container, widget) -> bool:
    return bool(widget.region) and container.region.contains_region(widget.region)


async def test_relative_accuracy_at_80x24_pendant_fields_instruction_and_captured_error(
    tmp_path: Path, tui
) -> None:
    from station.tui.instruments import DemoLab
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.dashboard import DashboardScreen

    lab = DemoLab(7, stroke_points=80)
    try:
        from station.tui.app import DemoPort
        from station.tui.screens.setup import SetupScreen

        fixture = lab.fixture("relative_accuracy")
        port = DemoPort(
            url=fixture.url,
            protocol=fixture.protocol,
            channel_map=fixture.channel_map,
            procedure="relative_accuracy",
            description=fixture.description,
            trigger=fixture.trigger,
            count=2,
        )
        app = StationApp(
            StationConfig(
                sessions_dir=tmp_path, sessions_reason="test folder", demo=port, demo_lab=lab
            )
        )
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("n")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
            await pilot.pause()
            await pilot.press("f2")
            await tui.wait_until(pilot, lambda: app.runner is not None)
            while app.runner.state().current.kind != "input":
                before = app.runner.state().current.index
                await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
                await tui.wait_until(pilot, lambda: not app.screen.busy)
                await pilot.press("enter")
                await tui.wait_until(
                    pilot, lambda before=before: app.runner.state().current.index != before
                )
            await tui.wait_until(pilot, lambda: len(app.screen.query("#step-inputs Input")) == 3)
            # The first field takes the focus (once mounted: awaited, not slept for).
            await tui.wait_until(
                pilot, lambda: getattr(app.screen.focused, "id", "") == "input-x", timeout=30.0
            )
            await pilot.pause(0.1)
            panel = app.screen.query_one("#step-panel")
            shown = fixture.simulator.model.placement_of(app.runner.state().current.placement)
            # Typed by keyboard: each field in view as it is typed into.
            for axis, value in zip("xyz", shown.pendant, strict=True):
                field = app.screen.focused
                assert field.id == f"input-{axis}", field
                assert _whole_in(panel, field), f"pendant {axis} is typed blind"
                await pilot.press(*str(value))
                await pilot.press("enter")
                await pilot.pause(0.1)
            await tui.wait_until(pilot, lambda: app.runner.state().current.kind != "input")
            # On to the capture: the whole instruction is on screen.
            while app.runner.state().action.kind != "capture":
                before = app.runner.state().current.index
                await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
                await tui.wait_until(pilot, lambda: not app.screen.busy)
                await pilot.press("enter")
                await tui.wait_until(
                    pilot, lambda before=before: app.runner.state().current.index != before
                )
            await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
            await pilot.pause(0.3)
            prompt = app.screen.query_one("#dash-prompt", Static)
            words = str(prompt.render()).split()
            on_screen = " ".join(_screen_text(app).split())
            # The instruction's last words (where it says which key) are drawn, not cut.
            assert " ".join(words[-4:]) in on_screen, (words, on_screen)
            assert "Space" in " ".join(words)
            # Space: the error just captured is shown before the checklist comes back.
            await pilot.press("space")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen), 15)
            await pilot.pause(0.2)
            captured = str(app.screen.query_one("#step-captured", Static).render())
            assert captured.startswith("Captured (set ") and " in" in captured, captured
            assert all(f"{axis} " in captured for axis in "xyz"), captured
            # Drawn whole (wrapped, perhaps, between a channel and its figure), never cut.
            shown = " ".join(_screen_text(app).replace("│", " ").split())
            assert " ".join(captured.split()) in shown or all(
                word in shown for word in captured.split()
            ), (captured, shown)
    finally:
        lab.stop()


async def test_no_readings_yet_only_with_none(tmp_path: Path, fixture_pty, tui) -> None:
    """Finding 9: the chart said "no readings yet" beside a table with one reading."""
    from station.tui.widgets.control_chart import ControlChartView

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R9", fixture_pty.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        await pilot.pause(0.3)
        chart = app.screen.query_one(ControlChartView)
        assert "no readings yet" in str(chart.render())
        await tui.capture_one(pilot)
        await pilot.pause(0.3)
        drawn = str(chart.render())
        assert "no readings yet" not in drawn and "2 readings (have 1)" in drawn, drawn
        await tui.capture_one(pilot)
        await pilot.pause(0.3)
        assert "have 1" not in str(chart.render())


async def test_test_connection_reads_at_the_resolution_with_the_unit(
    tmp_path: Path, fixture_pty, tui
) -> None:
    """Finding 9: the live readings of F3 showed no unit. Issue 22: in the one number format
    of every screen (one decimal beyond the gauge step), not the gauge's own four."""
    import re

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R8", fixture_pty.url)
        await pilot.press("f3")
        output = app.screen.query_one("#test-output", Static)
        await tui.wait_until(pilot, lambda: "The line works" in str(output.render()), 20)
        lines = [line for line in str(output.render()).splitlines() if "x=" in line]
        assert lines
        for line in lines:
            # 0.0001 in gauge: five decimals, as every figure, and the unit.
            assert re.search(r"x=[+-]\d\.\d{5}  y=[+-]\d\.\d{5}  z=[+-]\d\.\d{5} in$", line), line


async def test_exporting_from_the_summary_says_so_without_covering_it(
    tmp_path: Path, monkeypatch, tui
) -> None:
    """Finding 9: the export toasts covered the summary's text."""
    import shutil

    from textual.widgets._toast import Toast

    from station.tui.screens.summary import SummaryScreen, SummaryView

    saved = SNAPSHOT_SESSIONS / "sessions" / "2026-11-23T175031Z_R1_repeatability.jsonl"
    shutil.copy(saved, tmp_path / saved.name)
    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        app.push_screen(SummaryScreen(SummaryView.from_file(tmp_path / saved.name)))
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        await pilot.press("e")
        await pilot.pause(0.3)
        message = app.screen.query_one("#summary-message", Static)
        # Both files said, whole, on the screen (the HTML report's path was cut at the edge,
        # the text report not said at all); their full paths are in the session file's block.
        said = "Report filed beside the session file, as .report.txt and .report.html"
        assert said in tui.screen_text(app), tui.screen_text(app)
        block = str(app.screen.query_one("#summary-file", Static).render())
        stem = saved.name.removesuffix(".jsonl")
        assert f"{stem}.report.txt" in block and f"{stem}.report.html" in block
        assert message.region and message.region.y < 23  # above the footer, in view
        assert not list(app.query(Toast)), "a toast covers the summary"


async def test_the_help_is_wrapped_for_80_columns(tmp_path: Path) -> None:
    """Finding 9: the help broke mid-sentence at 80 columns (its lines were longer than the
    dialog, so each was re-wrapped where it happened to end). Every line of it is drawn whole
    on one row of the 80×24 screen."""
    import re

    from station.tui.screens.dialogs import HELP_TEXT, HelpScreen

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("question_mark")
        await pilot.pause(0.3)
        assert isinstance(app.screen, HelpScreen)
        body = app.screen.query_one(".dialog")
        width = body.scrollable_content_region.width
        for line in HELP_TEXT.splitlines():
            visible = re.sub(r"\[/?b\]", "", line)
            assert len(visible) <= width, f"re-wrapped at {width}: {visible!r}"


async def test_linearity_one_sided_limits_are_explained_on_screen(
    tmp_path: Path, monkeypatch, tui
) -> None:
    """Finding 9: the straightness judged one-sided against a 0.002 zone was explained only
    in the procedure's TOML file."""
    from textual.widgets import Select

    from station.tui.screens.setup import SetupScreen
    from station.tui.screens.summary import SummaryScreen, SummaryView

    saved = SNAPSHOT_SESSIONS / "sessions" / "2026-11-29T211526Z_demo-robot_linearity.jsonl"
    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        await pilot.pause()
        app.screen.query_one("#procedure", Select).value = "linearity"
        await tui.wait_until(
            pilot, lambda: isinstance(app.screen, SetupScreen) and app.screen.is_mounted
        )
        await pilot.pause(0.3)
        hints = " ".join(str(s.render()) for s in app.screen.query(".field-hint"))
        assert "judged one-sided" in hints and "0.002" in hints
        app.push_screen(SummaryScreen(SummaryView.from_file(saved), reviewing=True))
        await tui.wait_until(
            pilot,
            lambda: (
                isinstance(app.screen, SummaryScreen) and bool(app.screen.query("#summary-verdict"))
            ),
        )
        verdict = str(app.screen.query_one("#summary-verdict", Static).render())
        # Signed like every limit on the screen (the histogram's "USL +0.00200").
    assert "one-sided: upper limit +0.00200 in only" in verdict, verdict


async def test_long_alarm_texts_open_in_full(tmp_path: Path, alarming_fixture, tui) -> None:
    """The alarm log cuts each alarm to one line; ``m`` shows them in full."""
    fixture_pty = alarming_fixture
    from station.tui.screens.dialogs import FullTextScreen
    from station.tui.widgets.alarm_log import AlarmLog

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R1", fixture_pty.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        log = app.screen.query_one(AlarmLog)
        for _ in range(30):  # live alarms come once the limits freeze (after 25 cycles)
            await tui.capture_one(pilot)
            if "⚠" in str(log.render()):
                break
        await pilot.pause(0.3)
        drawn = _screen_text(app)
        alarm_row = next(row for row in drawn.splitlines() if "⚠" in row)
        assert alarm_row.rstrip().endswith("…"), alarm_row  # cut on the dashboard
        await pilot.press("m")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, FullTextScreen))
        await pilot.pause(0.2)
        full = str(app.screen.query_one("#full-text", Static).render())
        cut = alarm_row.strip().lstrip("⚠ ").rstrip("…").strip()
        line = next(line for line in full.split("\n\n") if line.startswith(cut))
        assert len(line) > len(cut) and not line.endswith("…")
        # Drawn whole, wrapped, on the 80×24 screen.
        assert " ".join(line.split()[-3:]) in " ".join(_screen_text(app).split())
        await pilot.press("escape")
