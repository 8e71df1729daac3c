"""Honest verdicts in the TUI, by keyboard against the simulated fixture at 80×24: a reading
beyond a limit is marked on the dashboard the moment it is on disk and counted per axis; a
session finished with 9 cycles says PROVISIONAL: 9 of 25 on the dashboard and in the summary,
with the readings out of specification listed."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console
from textual.widgets import Input, Static

from station.tui.app import StationApp, StationConfig
from station.tui.screens.dashboard import DashboardScreen
from station.tui.screens.dialogs import ConfirmScreen
from station.tui.screens.summary import SummaryScreen
from station.tui.widgets.stats_panel import StatsPanel, stats_table


def stats_text(app: StationApp) -> str:
    """The statistics table as the screen draws it (its rows, rendered 80 columns wide)."""
    panel = app.screen.query_one(StatsPanel)
    console = Console(width=80, record=True, color_system=None)
    console.print(stats_table(panel._rows))
    return console.export_text()


def row_of(text: str, channel: str) -> str:
    return next(line for line in text.splitlines() if line.strip().lstrip("▶").startswith(channel))


async def test_out_of_spec_flagged_live_and_nine_cycles_are_provisional(
    tmp_path: Path, fixture_pty, tui
) -> None:
    app = StationApp(
        StationConfig(sessions_dir=tmp_path, sessions_reason="test folder", capture_timeout=3.0)
    )
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R9", fixture_pty.url)
        # A tolerance on x tighter than its spread: some readings fall outside.
        app.screen.query_one("#limits-x", Input).value = "±0.0002"
        await pilot.press("f2")
        # Two gauge steps either side is implausibly tight: the set-up asks; yes, on purpose.
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
        await pilot.press("y")
        await tui.walk_checklist(pilot)
        assert isinstance(app.screen, DashboardScreen)
        flagged = 0
        while app.runner.state().progress.done < 9:
            await tui.capture_one(pilot)
            last = app.runner.state().last_cycle.values["x"]
            await pilot.pause(0.15)  # the next redraw, at most ~10 a second
            row = row_of(stats_text(app), "x")
            if abs(last) > 0.0002:
                flagged += 1
                assert ("▲" if last > 0 else "▼") in row, (last, row)
            else:
                assert "▲" not in row and "▼" not in row, (last, row)
        assert flagged, "the fixture's x spread should put a reading beyond ±0.0002"
        text = stats_text(app)
        analysis = app.live_analysis()
        out = analysis.channels["x"].out_of_spec
        assert out.total >= flagged and row_of(text, "x").split()[-2] == str(out.total)
        assert "PROVISIONAL: 9 of 25 readings, 16 more before a verdict" in text
        assert "PROVISIONAL" in row_of(text, "x") and "CAPABLE" not in text

        await pilot.press("f")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
        await pilot.press("y")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        verdict = " ".join(str(app.screen.query_one("#summary-verdict", Static).render()).split())
        assert "Verdict: PROVISIONAL: 9 of 25" in verdict, verdict
        assert "CAPABLE" not in verdict
        # Finding 9: each axis' figures on one line at 80 columns ("σ" was left at a line's
        # end with its value on the next, after "PROVISIONAL: 9 of 25" on every axis).
        shown_lines = tui.screen_text(app).splitlines()
        assert not [line for line in shown_lines if line.rstrip().endswith("σ")], shown_lines
        cycles = ", ".join(str(c) for c in out.cycles)
        assert f"out of specification: {out.total} reading" in verdict
        assert f"cycle{'s' if out.total > 1 else ''} {cycles}" in verdict
