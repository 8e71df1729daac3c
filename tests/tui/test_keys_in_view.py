"""Issue 26, item 3: every key in view at 80×24. The footer of each screen names all of its keys
(on two rows where one is too short), ``?`` lists the screen's own keys and no Textual
internals, the command palette has one Quit and a theme command, and the texts that were cut at
80 columns (the home screen's folder sentence, the review list's last column, the checklist's
step names) fit or wrap."""

from __future__ import annotations

from pathlib import Path

from textual.widgets import Static

from station.tui.app import StationApp, StationConfig

SNAPSHOTS = Path(__file__).resolve().parent / "snapshots"
TEXTUAL_OWN = ("super+c", "Copy selected text", "Focus Next", "Focus Previous")


def _app(sessions: Path | str = "sessions") -> StationApp:
    return StationApp(
        StationConfig(
            sessions_dir=Path(sessions),
            sessions_reason="the working directory's sessions folder",
            capture_timeout=3.0,
        )
    )


# ---- ? lists the screen's own keys ------------------------------------------------------------


async def test_help_lists_the_screens_own_keys_not_textuals(monkeypatch, tui) -> None:
    from station.tui.screens.dialogs import HelpScreen
    from station.tui.screens.setup import SetupScreen

    monkeypatch.chdir(SNAPSHOTS)
    app = _app()
    async with app.run_test(size=(80, 24)) as pilot:
        for opening, screen_type in (("question_mark", None), ("f1", SetupScreen)):
            if screen_type is not None:
                await pilot.press("n")
                await tui.wait_until(pilot, lambda t=screen_type: isinstance(app.screen, t))
            await pilot.press(opening)
            await tui.wait_until(pilot, lambda: isinstance(app.screen, HelpScreen))
            keys = str(app.screen.query_one("#help-keys", Static).render())
            for textual_own in TEXTUAL_OWN:
                assert textual_own not in keys, keys
            own = "New session" if screen_type is None else "Test connection"
            assert own in keys, keys
            await pilot.press("escape")
            await tui.wait_until(pilot, lambda: not isinstance(app.screen, HelpScreen))


# ---- the command palette: one Quit, and the theme ---------------------------------------------


async def test_palette_has_one_quit_and_changes_the_theme(monkeypatch, tui) -> None:
    from textual.command import CommandPalette

    from station.tui.screens.home import HomeScreen
    from station.tui.theme import HIGH_CONTRAST

    monkeypatch.chdir(SNAPSHOTS)
    app = _app()
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.wait_until(pilot, lambda: isinstance(app.screen, HomeScreen))
        titles = [command.title for command in app.get_system_commands(app.screen)]
        assert titles.count("Quit") == 1, titles
        assert "Theme" in titles, titles
        for textual_own in TEXTUAL_OWN:
            assert textual_own not in titles, titles
        # Chosen by name as a technician would: Ctrl+P, "theme", then the high-contrast one.
        await pilot.press("ctrl+p")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, CommandPalette))
        await pilot.press(*"Theme")
        await pilot.pause(0.5)
        await pilot.press("enter")
        await pilot.pause(0.5)
        await tui.wait_until(pilot, lambda: isinstance(app.screen, CommandPalette))
        await pilot.press(*"high-contrast")
        await pilot.pause(0.5)
        await pilot.press("enter")
        await tui.wait_until(pilot, lambda: app.theme == HIGH_CONTRAST)


# ---- every footer key in view at 80×24 ----------------------------------------------------------


def footer_rows(app: StationApp) -> str:
    """The rows of the screen the footer takes, as the terminal shows them."""
    from textual.widgets import Footer

    from tests.tui.conftest import screen_text

    footer = app.screen.query(Footer).last()
    region = footer.region
    assert region.height and region.bottom <= app.size.height, region
    return "\n".join(screen_text(app).splitlines()[region.y : region.bottom])


def assert_every_key_in_view(app: StationApp, *named: str) -> None:
    """Every key the screen shows in its footer (and the ``named`` ones the issue missed) is
    on the screen whole, as "key description"."""
    screen = app.screen
    wanted: list[str] = []
    actions: set[str] = set()
    for _node, binding, _enabled, _tooltip in screen.active_bindings.values():
        if binding.show and binding.action not in actions:
            actions.add(binding.action)
            wanted.append(f"{app.get_key_display(binding)} {binding.description}")
    if app.COMMAND_PALETTE_BINDING in screen.active_bindings:
        wanted.append("^p palette")
    rows = footer_rows(app)
    for entry in (*wanted, *named):
        assert entry in rows, f"{entry!r} is not in view at 80×24:\n{rows}"


async def test_every_key_in_view_on_the_saved_sessions_screens(monkeypatch, tui) -> None:
    """Home, the review list, a robot's history, the summary, its charts and alarm list,
    and the help and a question over them."""
    from station.tui.screens.alarms import AlarmsScreen
    from station.tui.screens.dashboard import DashboardScreen
    from station.tui.screens.dialogs import HelpScreen, TextPrompt
    from station.tui.screens.home import HomeScreen
    from station.tui.screens.record import RecordScreen
    from station.tui.screens.review import ReviewScreen
    from station.tui.screens.summary import SummaryScreen

    monkeypatch.chdir(SNAPSHOTS)
    app = _app()
    async with app.run_test(size=(80, 24)) as pilot:

        async def to(key: str, screen_type: type, *named: str) -> None:
            await pilot.press(key)
            await tui.wait_until(pilot, lambda: isinstance(app.screen, screen_type))
            await pilot.pause(0.2)
            assert_every_key_in_view(app, *named)

        await tui.wait_until(pilot, lambda: isinstance(app.screen, HomeScreen))
        await pilot.pause(0.2)
        assert_every_key_in_view(app, "n New session", "q Quit")
        await to("question_mark", HelpScreen, "esc Close")
        await to("escape", HomeScreen)
        await to("v", ReviewScreen, "m Mark for compare", "/ Robot filter", "f1 Help")
        await to("slash", TextPrompt, "esc Cancel")
        await to("escape", ReviewScreen)
        await to("h", RecordScreen, "esc Back")
        await to("escape", ReviewScreen)
        await to("enter", SummaryScreen, "e Export report", "q Quit")
        await to("d", DashboardScreen, "a Alarms", "m Messages", "f1 Help", "q Leave")
        await to("a", AlarmsScreen, "esc Back")


async def test_every_key_in_view_while_capturing(tmp_path: Path, fixture_pty, tui) -> None:
    """The set-up, the checklist, the capture dashboard with all of its keys (go on
    included), the note and leave questions over it."""
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.dashboard import DashboardScreen
    from station.tui.screens.dialogs import ConfirmScreen, TextPrompt

    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R1", fixture_pty.url)
        await pilot.pause(0.2)
        assert_every_key_in_view(app, "f2 Start", "f3 Test connection")
        await pilot.press("f2")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        await pilot.pause(0.2)
        assert_every_key_in_view(app, "q Leave (resumable)")
        await tui.walk_checklist(pilot)
        await tui.capture_one(pilot)
        dashboard = app.screen
        assert isinstance(dashboard, DashboardScreen)
        # The most keys it ever shows: "go on" comes once a step inside a repeated block has
        # its minimum (not reached in a few cycles here).
        dashboard._may_go_on = True
        dashboard.refresh_bindings()
        await pilot.pause(0.3)
        assert_every_key_in_view(
            app,
            "space Capture",
            "g Go on",
            "f Finish",
            "a Alarms",
            "m Messages",
            "f1 Help",
            "q Leave",
        )
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, TextPrompt))
        assert_every_key_in_view(app, "esc Cancel")
        await pilot.press("escape")
        await tui.wait_until(pilot, lambda: app.screen is dashboard)
        await pilot.press("q")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
        assert_every_key_in_view(app, "y Yes", "n No")


async def test_every_key_in_view_while_streaming_strokes(tmp_path: Path, monkeypatch, tui) -> None:
    """The linearity dashboard: stream, end stroke, finish, the indicator, note, help, leave."""
    from textual.widgets import Input

    from station.tui.app import DemoPort
    from station.tui.instruments import DemoLab
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.strokes import StrokeDashboardScreen

    monkeypatch.chdir(tmp_path)
    lab = DemoLab(1990, stroke_points=80)
    try:
        fixture = lab.fixture("linearity")
        app = StationApp(
            StationConfig(
                sessions_dir=tmp_path,
                sessions_reason="the test's folder",
                demo=DemoPort(
                    url=fixture.url,
                    protocol=fixture.protocol,
                    channel_map=dict(fixture.channel_map),
                    procedure="linearity",
                    description=fixture.description,
                    trigger=fixture.trigger,
                    count=3,
                ),
                demo_lab=lab,
                capture_timeout=3.0,
            )
        )
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("n")
            await tui.wait_until(pilot, lambda: len(app.screen.query("#operator")) == 1)
            app.screen.query_one("#operator", Input).value = "operator-1"
            await pilot.press("f2")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
            while app.runner.state().action.kind != "stream":
                before = app.runner.state().current.index
                await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
                await tui.wait_until(pilot, lambda: not app.screen.busy)
                await pilot.press("enter")
                await tui.wait_until(
                    pilot, lambda b=before: app.runner.state().current.index != b, timeout=30
                )
            await tui.wait_until(pilot, lambda: isinstance(app.screen, StrokeDashboardScreen))
            await pilot.pause(0.3)
            assert_every_key_in_view(app, "e End stroke", "f Finish", "f1 Help", "q Leave")
    finally:
        lab.stop()


# ---- the texts that were cut at 80 columns ------------------------------------------------------


async def test_the_review_lists_last_column_is_in_view(tmp_path: Path, tui) -> None:
    """A long robot name beside a crashed session's state pushed "done" off the screen."""
    from station.tui.screens.review import ReviewScreen
    from tests.tui.conftest import screen_text
    from tests.tui.test_operator import _write

    robot = "KUKA-KR16-2-cell-3-line-B"
    _write(tmp_path, robot, 30, "finish", 1)
    _write(tmp_path, robot, 7, None, 2)  # the writer went away without a word: a crash
    app = _app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("v")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ReviewScreen))
        verdicts = ("CAPABLE", "INCONCLUSIVE", "PROVISIONAL", "UNDEFINED")
        await tui.wait_until(pilot, lambda: any(v in screen_text(app) for v in verdicts))
        await pilot.pause(0.2)
        drawn = screen_text(app)
        words = " ".join(drawn.split())
        for whole in ("done", "30/30", "7/30", "cycles", "(crashed?)", "repeatability"):
            assert whole in words, drawn
        # Wrapped where narrowed, never cut: every word of the crashed state is there.
        for part in ("stopped", "without", "word", robot[:8]):
            assert part in drawn, drawn


async def test_the_home_screen_keeps_its_folder_sentence_in_view(tmp_path: Path, tui) -> None:
    """In the demo, at 80×24, the banner and the demo's choices pushed the sessions folder off
    the screen: the choices scroll now, and the folder is said."""
    from station.tui.app import DemoPort
    from station.tui.instruments import DemoLab
    from station.tui.screens.home import HomeScreen
    from tests.tui.conftest import screen_text

    app = StationApp(
        StationConfig(
            sessions_dir=tmp_path,
            sessions_reason="the demo's own folder",
            demo=DemoPort(url="/dev/pts/99", protocol="mitutoyo", channel_map={"1": "x"}),
            demo_lab=DemoLab(1990),  # its simulators start only when a procedure is chosen
        )
    )
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.wait_until(pilot, lambda: isinstance(app.screen, HomeScreen))
        await pilot.pause(0.3)
        drawn = screen_text(app)
        words = " ".join(drawn.split())  # the path may wrap at the screen's edge
        assert f"Sessions folder: {tmp_path}" in words, drawn
        assert "(the demo's own folder)" in drawn, drawn
        assert "New session" in drawn, drawn


async def test_the_checklists_step_names_wrap_in_its_list(tui) -> None:
    """The step list is 38 columns wide at 80×24 (as station.tcss lays out the checklist):
    a long step name wraps under itself instead of ending in "…"."""
    from types import SimpleNamespace

    from textual.app import App, ComposeResult
    from textual.containers import VerticalScroll

    from station.tui.widgets.step_list import StepList
    from tests.tui.conftest import screen_text

    titles = ("Fit the cube", "Bring the cube into the second fixture", "Zero the scale")
    steps = [
        SimpleNamespace(
            mark=mark, step=SimpleNamespace(title=title), id=f"s{n}", placement=1 if n else None
        )
        for n, (mark, title) in enumerate(zip(("done", "current", "pending"), titles, strict=True))
    ]

    class Steps(App[None]):
        CSS_PATH = str(Path(__file__).resolve().parents[2] / "station/tui/station.tcss")

        def compose(self) -> ComposeResult:
            with VerticalScroll(id="steps-box"):
                yield StepList(id="steps")

    app = Steps()
    async with app.run_test(size=(80, 24)) as pilot:
        app.query_one(StepList).show(steps)
        await pilot.pause(0.1)
        drawn = screen_text(app)
        assert "…" not in drawn, drawn
        words = " ".join(drawn.replace("│", " ").split())
        assert "2 Bring the cube into the second fixture (1)" in words, drawn
        assert "3 Zero the scale (1)" in words, drawn
