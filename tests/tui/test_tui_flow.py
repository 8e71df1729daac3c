"""A whole repeatability session through the TUI at 80×24, by keyboard, against the simulator.

Set-up (a bad limit refused with a sentence next to its field), the checklist, 30 cycles with a
reject and its reason, an alarm in the log with its rule in words, acknowledged with a cause on
the alarm list, finish, the summary (the acknowledgement in it and in the exported text
report); then the session file verifies with ``station verify`` and ``station analyze --json``
on it equals the analysis the TUI showed.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

from textual.widgets import Footer, Input, Static

from station.analysis.document import to_json
from station.session.model import load_session
from station.tui.app import StationApp, StationConfig
from station.tui.screens.alarms import AckDialog, AlarmsScreen
from station.tui.screens.dashboard import DashboardScreen
from station.tui.screens.home import HomeScreen
from station.tui.screens.setup import SetupScreen
from station.tui.screens.summary import SummaryScreen
from station.tui.widgets.alarm_log import AlarmLog

ROOT = Path(__file__).resolve().parents[2]
REASON = "the cube slipped in the gripper"


def _same(a: object, b: object, path: str = "") -> None:
    """Equal documents, numbers to 1e-9 relative (live sums against batch sums)."""
    if isinstance(a, dict) and isinstance(b, dict):
        assert a.keys() == b.keys(), f"{path}: {sorted(a)} != {sorted(b)}"
        for key in a:
            _same(a[key], b[key], f"{path}.{key}")
    elif isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), f"{path}: {a} != {b}"
        for index, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{path}[{index}]")
    elif isinstance(a, float) and isinstance(b, int | float) and not isinstance(b, bool):
        assert math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-15), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def _text(app: StationApp, selector: str) -> str:
    return str(app.screen.query_one(selector, Static).render())


async def test_full_repeatability_session(tmp_path: Path, alarming_fixture, tui) -> None:
    fixture_pty = alarming_fixture
    app = StationApp(
        StationConfig(sessions_dir=tmp_path, sessions_reason="test folder", capture_timeout=3.0)
    )
    async with app.run_test(size=(80, 24)) as pilot:
        assert isinstance(app.screen, HomeScreen)
        assert str(tmp_path) in _text(app, "#home-folder")
        await tui.open_setup(pilot, "R1", fixture_pty.url)
        setup = app.screen
        setup.query_one("#limits-x", Input).value = "0.001:-0.001"
        await pilot.press("f2")
        await pilot.pause()
        assert isinstance(app.screen, SetupScreen), "a bad limit must not start a session"
        assert "not above the lower limit" in _text(app, "#limits-x-error")
        assert setup.query_one("#limits-x-error").has_class("-shown")
        assert not list(tmp_path.glob("*.jsonl")), "nothing is written before the set-up is valid"

        # A port that does not exist is refused next to the port field, before any file.
        setup.query_one("#limits-x", Input).value = "±0.001"
        setup.query_one("#port", Input).value = str(tmp_path / "no-such-gauge")
        await pilot.press("f2")
        await tui.wait_until(pilot, lambda: setup.query_one("#port-error").has_class("-shown"))
        assert "did not open" in _text(app, "#port-error")
        assert not list(tmp_path.glob("*.jsonl"))

        setup.query_one("#port", Input).value = fixture_pty.url
        await pilot.press("f2")

        # The checklist: Enter on every step (the zero step zeroes) until the captures start.
        assert await tui.walk_checklist(pilot) == 7
        dashboard = app.screen
        assert isinstance(dashboard, DashboardScreen)

        # 30 accepted cycles, with cycle 5 rejected for a reason on the way.
        while app.runner.state().progress.done < 30:
            await tui.capture_one(pilot)
            if len(app.runner.state().cycles) == 5 and app.runner.state().progress.done == 5:
                await pilot.press("r")
                await pilot.pause()
                await pilot.press(*REASON)
                await pilot.press("enter")
                await tui.wait_until(pilot, lambda: app.runner.state().cycles[-1].rejected)
        state = app.runner.state()
        assert len(state.cycles) == 31 and state.accepted == 30
        await pilot.pause(0.3)  # one redraw
        assert "cycle 30 of 30" in _text(app, "#dash-title")
        alarms = str(app.screen.query_one(AlarmLog).render())
        # Each alarm names its rule in words (e.g. "report rule 4 (two of three points beyond
        # 2 sigma ...)" or the drift rule).
        assert re.search(r"(report rule \d|drift rule) \(", alarms), alarms
        assert "not acknowledged" in alarms and "a: the full list" in alarms
        footer_keys = {
            key.key: key.description for key in app.screen.query_one(Footer).query("FooterKey")
        }
        assert footer_keys.get("a") == "Alarms", footer_keys

        # The alarm list: the first alarm acknowledged with a cause, what it was, the action.
        first = app.runner.state().alarm_list[0]
        await pilot.press("a")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, AlarmsScreen))
        await pilot.press("a")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, AckDialog))
        await pilot.press("down", "down", "enter")  # temperature
        await pilot.press(*"cell door open", "enter")
        await pilot.press(*"waited for warm-up", "enter")
        await tui.wait_until(pilot, lambda: app.runner.state().alarm_list[0].acknowledged)
        await tui.wait_until(pilot, lambda: isinstance(app.screen, AlarmsScreen))
        assert app.runner.state().alarm_list[0].seq == first.seq
        await pilot.pause(0.3)
        listed = "\n".join(str(i.children[0].render()) for i in app.screen.query("AlarmItem"))
        assert listed.count("acknowledged: temperature (cell door open)") == 1, listed
        await pilot.press("escape")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
        await pilot.pause(0.3)
        alarms = str(app.screen.query_one(AlarmLog).render())
        # The log counts what is still open (the acknowledged one may be older than the
        # newest three it shows).
        assert f"{len(app.runner.state().alarm_list) - 1} not acknowledged" in alarms, alarms

        await pilot.press("f")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        summary = app.screen
        verdict = _text(app, "#summary-verdict")
        assert "Verdict:" in verdict
        assert "NOT CAPABLE" in verdict and "CAPABLE" in verdict
        shown = summary.view
        assert shown.excluded_cycles == (5,)
        listed = " ".join(_text(app, "#summary-alarms").split())
        assert (
            f"#{first.seq} {first.channel}, {first.rule_name} [live]" in listed
            and "acknowledged: temperature (cell door open); corrective action: waited for warm-up"
            in listed
        ), listed

        # Exports beside the session file.
        await pilot.press("e")
        await pilot.press("c")
        await pilot.pause()

    files = list(tmp_path.glob("*.jsonl"))
    assert len(files) == 1
    session_file = files[0]
    report = session_file.with_name(session_file.stem + ".report.txt").read_text()
    # The filed report (as `station report` files it) names the cause, action and text.
    assert "acknowledged: temperature; waited for warm-up; cell door open" in (
        " ".join(report.split())
    )
    csv_text = session_file.with_name(session_file.stem + ".csv").read_text()
    assert f"rejected: {REASON}" in csv_text

    session = load_session(session_file, recover=False)
    assert session.status == "finished"
    assert session.rejected == {5: REASON}

    verify = subprocess.run(
        [sys.executable, "-m", "station", "verify", str(session_file)],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert verify.returncode == 0, verify.stdout + verify.stderr
    assert shown.last_hash in verify.stdout

    analyze = subprocess.run(
        [sys.executable, "-m", "station", "analyze", str(session_file), "--json"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert analyze.returncode == 0, analyze.stderr
    shown_document = to_json(shown.analysis)
    command_document = json.loads(analyze.stdout)
    # The command may add what it knows of the file (e.g. the procedure); every figure the
    # TUI showed must be in it, equal.
    _same(shown_document, {key: command_document[key] for key in shown_document})


async def test_leave_then_resume_continues_the_numbering(tmp_path: Path, fixture_pty, tui) -> None:
    from station.tui.screens.dialogs import ConfirmScreen

    app = StationApp(
        StationConfig(sessions_dir=tmp_path, sessions_reason="test folder", capture_timeout=3.0)
    )
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R2", fixture_pty.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        for _ in range(3):
            await tui.capture_one(pilot)
        # Pause refuses captures with a sentence; p again continues; a note goes to the file.
        await pilot.press("p")
        await tui.wait_until(pilot, lambda: app.runner.state().status == "paused")
        await pilot.press("space")
        await tui.wait_until(pilot, lambda: "paused" in _text(app, "#dash-message"))
        assert len(app.runner.state().cycles) == 3
        await pilot.press("p")
        await tui.wait_until(pilot, lambda: app.runner.state().status == "running")
        await pilot.press("n")
        await pilot.pause()
        await pilot.press(*"gripper re-tightened")
        await pilot.press("enter")
        await pilot.pause(0.2)
        await pilot.press("q")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
        await pilot.press("y")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, HomeScreen))
        await pilot.pause()
        session_file = next(tmp_path.glob("*.jsonl"))
        assert load_session(session_file, recover=False).status == "interrupted"

        # The unfinished session is offered first; Enter, then F2 on the recorded line.
        home = app.screen
        first = home.query_one("#home-choices").get_option_at_index(0)
        assert str(first.prompt).startswith("Resume: R2 repeatability (interrupted")
        await pilot.press("enter")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        await pilot.pause()
        assert app.screen.query_one("#port", Input).value == fixture_pty.url
        assert app.screen.query_one("#robot", Input).disabled
        await pilot.press("f2")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
        await tui.capture_one(pilot)
        assert [record.cycle for record in app.runner.state().cycles] == [1, 2, 3, 4]
        await pilot.press("q")
        await pilot.press("y")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, HomeScreen))

    session = load_session(session_file, recover=False)
    assert sorted(session.cycles) == [1, 2, 3, 4]
    assert [e["type"] for e in session.events].count("resume") == 1
    assert any(note.get("text") == "gripper re-tightened" for note in session.notes)
