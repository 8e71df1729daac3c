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
