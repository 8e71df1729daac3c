"""SVG snapshots of the key screens at 80×24: home, the dashboard mid-capture, the summary.

Deterministic by construction: relative paths (the test runs in a folder of its own), the seeded
simulator on a pty behind a fixed link name, the operator named, no clock on screen, and the
summary reviewing a session file kept with the tests (so its name and hash never change). Update
the baselines after a deliberate change with ``pytest tests/tui/snapshots --snapshot-update``
and look at them (``snapshot_report.html``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from station.tui.app import StationApp, StationConfig
from station.tui.instruments import start_demo_fixture

HERE = Path(__file__).resolve().parent


def _app(sessions: str) -> StationApp:
    return StationApp(
        StationConfig(
            sessions_dir=Path(sessions),
            sessions_reason="the working directory's sessions folder",
            capture_timeout=3.0,
        )
    )


def test_home(snap_compare, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sessions").mkdir()
    assert snap_compare(_app("sessions"), terminal_size=(80, 24))


def test_dashboard_mid_capture(
    snap_compare, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, tui
) -> None:
    monkeypatch.chdir(tmp_path)
    fixture = start_demo_fixture(1990, link="gauges")

    async def walk(pilot) -> None:
        await tui.open_setup(pilot, "R1", fixture.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        for _ in range(20):
            await tui.capture_one(pilot)
        await pilot.press("z")  # the warming-up axis, with its alarms
        await pilot.pause(0.3)  # past the redraw interval

    try:
        assert snap_compare(_app("sessions"), terminal_size=(80, 24), run_before=walk)
    finally:
        fixture.stop()


def test_summary_of_a_saved_session(snap_compare, monkeypatch: pytest.MonkeyPatch, tui) -> None:
    monkeypatch.chdir(HERE)
    from station.tui.screens.summary import SummaryScreen

    async def review(pilot) -> None:
        await pilot.press("v")
        await pilot.pause()
        # R1's session (the folder also keeps the other procedures' sessions).
        table = pilot.app.screen.query_one("#review-table")
        table.move_cursor(
            row=[str(r[0]) for r in map(table.get_row_at, range(table.row_count))].index("R1")
        )
        await pilot.press("enter")
        await tui.wait_until(pilot, lambda: isinstance(pilot.app.screen, SummaryScreen))
        await pilot.pause()

    assert snap_compare(_app("sessions"), terminal_size=(80, 24), run_before=review)
