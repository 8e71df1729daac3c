"""End to end in a real terminal: ``station demo`` under tmux at 80×24, read from the pane.

One test hangs up the terminal during the captures (``tmux
kill-session`` sends SIGHUP, as an SSH drop does): the session file must end ``interrupted``, and
the next ``station`` must offer to resume it on its home screen. The last lets the autopilot walk
a short trial run of each procedure and reads the verdict words off the summary.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.e2e.terminal import Pane, alive

# End to end in a real terminal: slow by nature (the quick lane leaves them out).
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed"),
]

ROOT = Path(__file__).resolve().parents[2]


def scrolled_to(pane: Pane, text: str, pages: int = 8) -> str:
    """The screen once ``text`` is in view, paging down (PageDown) at most ``pages`` times;
    each page waits for the screen to change (at most 5 s)."""
    for _ in range(pages):
        screen = pane.screen()
        if text in screen:
            return screen
        pane.send("PageDown")
        deadline = time.monotonic() + 5
        while pane.screen() == screen and time.monotonic() < deadline:
            time.sleep(0.05)
    return pane.screen()


def _station(*args: str) -> list[str]:
    return [sys.executable, "-m", "station", *args]


def test_hang_up_during_capture_leaves_a_resumable_session(tmp_path: Path) -> None:
    pane = Pane(
        _station("demo", "--autopilot", "--pace", "0.1", "--sessions", str(tmp_path)), tmp_path
    )
    try:
        pane.wait_for(r"cycle ([2-9]|[12]\d) of 30", timeout=60)
        pane.hang_up()
        deadline = time.monotonic() + 15
        while alive(pane.pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not alive(pane.pid), "station did not exit on SIGHUP"
    finally:
        pane.close()

    sessions = list((tmp_path / "demo").glob("*.jsonl"))
    assert len(sessions) == 1
    from station.session.model import load_session

    session = load_session(sessions[0], recover=False)
    assert session.status == "interrupted"
    assert len(session.accepted_cycles) >= 2
    assert any(event.get("type") == "interrupted" for event in session.events)

    second = Pane(_station("--sessions", str(tmp_path / "demo")), tmp_path)
    try:
        screen = second.wait_for("Resume:", timeout=30)
        assert "interrupted" in screen
        assert "demo-robot" in screen
    finally:
        second.close()

    # The next demo resumes it on its own simulator (issue 26, item 4): the recorded
    # pseudo-terminal went with the demo that hung up. The robot's returns are cycles again.
    third = Pane(_station("demo", "--sessions", str(tmp_path)), tmp_path)
    try:
        third.wait_for("Resume:", timeout=30)
        third.send("r")
        third.wait_for("resumes on its own running simulator", timeout=30)
        third.send("F2")
        deadline = time.monotonic() + 30
        while max(load_session(sessions[0], recover=False).cycles) == max(session.cycles):
            assert time.monotonic() < deadline, f"no cycle after the resume:\n{third.screen()}"
            time.sleep(0.2)
    finally:
        third.close()


@pytest.mark.parametrize(
    ("procedure", "channels", "report", "minimum"),
    [
        ("repeatability", ("x ", "y ", "z "), "Summary", 25),
        ("relative_accuracy", ("x ", "y ", "z "), "RELATIVE ACCURACY", 3),
        ("linearity", ("h ", "v "), "LINEARITY", 25),
    ],
)
def test_demo_autopilot_count_5_ends_on_the_verdict(
    tmp_path: Path, procedure: str, channels: tuple[str, ...], report: str, minimum: int
) -> None:
    """``station demo --procedure X --autopilot --count 5`` walks to the summary (the
    repeatability robot comes back every 2 s; 5 placements of the two fixtures; 5 strokes along
    the bar) and shows a verdict word per channel, the procedure's own report block and a
    session file that verifies."""
    command = ["demo", "--procedure", procedure, "--count", "5", "--autopilot"]
    pane = Pane(_station(*command, "--pace", "0.05", "--sessions", str(tmp_path)), tmp_path)
    try:
        pane.wait_for("Verdict:", timeout=180)
        time.sleep(0.5)  # the summary paints in a few frames
        screen = pane.wait_for("Export report", timeout=10)  # the footer names the keys
        # The procedure's own block may sit below the first 24 rows (the budget and the
        # out-of-spec lines come first): the operator pages down to it.
        below = scrolled_to(pane, report)
        assert report in below, below
        lines = [line.strip() for line in screen.splitlines()]
        verdict_lines = [line for line in lines if line[:2] in channels]
        assert len(verdict_lines) == len(channels), screen
        # A word, never only a colour, with each axis' figures whole on its line at 80
        # columns; below the procedure's minimum a trial run is provisional (the count on the
        # verdict line).
        for line in verdict_lines:
            if minimum > 5:
                assert "PROVISIONAL" in line or "UNDEFINED" in line, line
            else:
                assert any(word in line for word in ("CAPABLE", "INCONCLUSIVE", "UNDEFINED")), line
            # (a scroll bar may follow at the right edge once the summary outgrows 24 rows)
            assert re.search(r"σ \d\.\d{5}\s*[▁▂▃▄▅▆▇█]*$", line), line
        verdict = next(line for line in lines if line.startswith("Verdict:"))
        assert verdict.split()[1] in (
            "CAPABLE",
            "NOT",
            "INCONCLUSIVE",
            "UNDEFINED",
            "PROVISIONAL:",
        ), verdict
        if minimum > 5:
            assert verdict.startswith("Verdict: PROVISIONAL: 5 of "), verdict
        sessions = list((tmp_path / "demo").glob("*.jsonl"))
        assert len(sessions) == 1
        verify = subprocess.run(
            _station("verify", str(sessions[0])), capture_output=True, text=True, cwd=ROOT
        )
        assert verify.returncode == 0, verify.stdout + verify.stderr
    finally:
        pane.close()


def test_demo_autopilot_walks_the_gauge_linearity_study(tmp_path: Path) -> None:
    """``station demo --procedure gauge_linearity --autopilot``: the bench's five masters, each
    size copied from the simulated bench into its input step, twelve seatings each, end on the
    study's own verdict (the demo indicator reads long: a slope of 0.0008), filed in the demo
    folder's own gauge register."""
    command = ["demo", "--procedure", "gauge_linearity", "--autopilot", "--pace", "0.05"]
    pane = Pane(_station(*command, "--sessions", str(tmp_path)), tmp_path)
    try:
        screen = pane.wait_for("Verdict:", timeout=300)
        time.sleep(0.5)  # the summary paints in a few frames
        screen = pane.wait_for("Export report", timeout=10)
        assert "Verdict: NOT ACCEPTABLE" in screen, screen
        assert "5 masters" in screen, screen
        (session,) = (tmp_path / "demo").glob("*.jsonl")
        analysed = subprocess.run(
            _station("analyze", str(session), "--json"), capture_output=True, text=True, cwd=ROOT
        )
        study = json.loads(analysed.stdout)["gauge_linearity"]
        assert [b["reference"] for b in study["biases"]] == [0.1, 0.3, 0.5, 0.7, 0.9]
        register = json.loads((tmp_path / "demo" / "gauges.json").read_text())
        assert "gauge_linearity" in register["gauges"]["DEMO-IND-1"]["studies"]
    finally:
        pane.close()


def test_demo_autopilot_walks_the_gage_rr_study(tmp_path: Path) -> None:
    """``station demo --procedure gage_rr --autopilot --count 2``: three appraisers' names
    copied from the simulated bench, each appraiser's ten parts seated in the order the station
    drew (one reading rejected and its part read again), two trials, and the study's own
    verdict on the summary, filed in the demo folder's own gauge register."""
    command = ["demo", "--procedure", "gage_rr", "--count", "2", "--autopilot", "--pace", "0.05"]
    pane = Pane(_station(*command, "--sessions", str(tmp_path)), tmp_path)
    try:
        pane.wait_for("Verdict:", timeout=300)
        time.sleep(0.5)  # the summary paints in a few frames
        screen = pane.wait_for("Export report", timeout=10)
        assert re.search(r"Verdict: (CONDITIONALLY )?ACCEPTABLE|Verdict: NOT ACCEPTABLE", screen)
        assert "3 appraisers x 10 parts" in screen, screen
        (session,) = (tmp_path / "demo").glob("*.jsonl")
        analysed = subprocess.run(
            _station("analyze", str(session), "--json"), capture_output=True, text=True, cwd=ROOT
        )
        study = json.loads(analysed.stdout)["gage_rr"]
        assert study["trials"] == 2 and study["n"] == 60
        assert study["appraiser_names"] == {"A": "Ann", "B": "Bo", "C": "Cy"}
        register = json.loads((tmp_path / "demo" / "gauges.json").read_text())
        assert "gage_rr" in register["gauges"]["DEMO-IND-1"]["studies"]
    finally:
        pane.close()
