"""A step kind and an analysis kind registered from the test itself run through the TUI
(Pilot) and ``station capture`` with no change to the engine or the front ends."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import soak_kinds

from station.session.model import load_session
from station.tui.app import StationApp, StationConfig
from station.tui.screens.summary import SummaryScreen

HERE = Path(__file__).resolve().parent


@pytest.fixture(autouse=True)
def soak_kinds_registered() -> None:
    """The soak step and the spread analysis, for this test only (the suite resets the
    registries after each test)."""
    soak_kinds.register()


RUN_WITH_KINDS = """
import sys
sys.path.insert(0, sys.argv[1])
import soak_kinds
soak_kinds.register()  # the soak step and the spread analysis
from station.cli import main
sys.exit(main(sys.argv[2:]))
"""


def _procedures(tmp_path: Path) -> Path:
    folder = tmp_path / "procedures"
    folder.mkdir()
    (folder / "soak-check.toml").write_bytes(soak_kinds.SOAK_PROCEDURE)
    return folder


def _station_with_kinds(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", RUN_WITH_KINDS, str(HERE), *args],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "STATION_PROCEDURES": ""},
    )


def test_headless_capture_runs_a_registered_step_and_analysis_kind(tmp_path, fixture_pty):
    folder = _procedures(tmp_path)
    done = _station_with_kinds(
        "capture", "--procedure", "soak-check", "--procedures", str(folder),
        "--port", fixture_pty.url, "--protocol", fixture_pty.protocol, "--robot", "R1",
        "--sessions", str(tmp_path / "sessions"), "--timeout", "5", "--every", "0.01",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "SPREAD REPORT" in done.stdout and "x range" in done.stdout
    path = next((tmp_path / "sessions").glob("*.jsonl"))
    session = load_session(path, recover=False)
    assert session.status == "finished" and len(session.cycles) == 3
    analysed = _station_with_kinds("analyze", str(path), "--json")
    assert analysed.returncode == 0, analysed.stderr
    document = json.loads(analysed.stdout)
    assert document["procedure"] == "spread" and set(document["spread"]) == {"x", "y", "z"}


async def test_the_tui_runs_a_registered_step_and_analysis_kind(tmp_path, fixture_pty, tui):
    folder = _procedures(tmp_path)
    app = StationApp(
        StationConfig(
            sessions_dir=tmp_path / "sessions",
            sessions_reason="test folder",
            procedure_dirs=(folder,),
            capture_timeout=3.0,
        )
    )
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        app.screen.open_new("soak-check")
        await tui.wait_until(pilot, lambda: app.screen.query("#port"))
        await pilot.pause()
        await pilot.press(*"R1")
        app.screen.query_one("#port").value = fixture_pty.url
        app.screen.query_one("#map").value = "1=x,2=y,3=z"
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        for _ in range(3):
            await tui.capture_one(pilot)
        # Every step is done: the dashboard offers to finish.
        await tui.wait_until(pilot, lambda: app.runner.state().action.kind == "finish")
        await pilot.press("f")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen), timeout=30)
        await pilot.pause()
        shown = str(app.screen.query_one("#summary-report").render())
        assert "SPREAD" in shown and "x range" in shown
        title = str(app.screen.query_one("#summary-title").render())
        assert "3 channels" in title
