"""kill -9 of ``station capture`` at 52 seeded random moments: every acknowledged cycle is in
the file, the file loads (a torn tail moved aside), verifies, and ``--resume`` continues."""

from __future__ import annotations

import random
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest

from station.errors import StationError
from station.session.model import load_session
from station.session.verify import verify_session

from .conftest import CYCLE_LINE, REPO, Capture, assert_acknowledged_kept, capture_args

RUNS = 52
WORKERS = 4
CYCLES = 120
RESUMED = 3


@dataclass
class Killed:
    index: int
    capture: Capture
    sessions: Path
    delay: float
    from_start: bool


def kill_once(index: int, url: str, root: Path) -> Killed:
    """Start a capture, wait a seeded random delay, SIGKILL it."""
    rng = random.Random(f"kill9/{index}")
    delay = rng.uniform(0.0, 1.0)
    # One run in six is killed counting from the start (during start-up and the header);
    # the others counting from the first cycle on disk (mid-capture: on a loaded machine the
    # start-up and the zero take longer than any fixed delay, and counted from the zero a kill
    # could still land before the first cycle).
    from_start = index % 6 == 0
    sessions = root / f"run{index:02d}"
    capture = Capture(capture_args(url, sessions, CYCLES))
    if not from_start:
        capture.wait_line(lambda line: CYCLE_LINE.match(line) is not None, 60.0)
    time.sleep(delay)
    capture.process.send_signal(signal.SIGKILL)
    capture.finish()
    return Killed(index, capture, sessions, delay, from_start)


def check_killed(run: Killed) -> str:
    """The file holds every acknowledged cycle, loads and verifies; returns how it ended."""
    files = sorted(run.sessions.glob("*.jsonl")) if run.sessions.exists() else []
    announced = run.capture.session_path
    assert len(files) <= 1
    if announced is None:
        assert not run.capture.acknowledged
        if not files:
            return "before the session"
        # Killed between creating the file and fsyncing its header: nothing was acknowledged,
        # and the loader says what is wrong in one sentence.
        try:
            load_session(files[0])
        except StationError as error:
            assert "header" in error.message or "empty" in error.message
            return "during the header"
        return "header written"
    assert files == [announced]
    session = load_session(announced)  # moves a torn tail aside
    assert_acknowledged_kept(run.capture, session)
    result = verify_session(announced)
    assert result.ok, result.message
    if session.torn is not None:
        assert Path(f"{announced}.torn").stat().st_size == session.torn.length
        return "torn tail recovered"
    return session.status


@pytest.mark.slow  # kill -9 at many points
def test_kill9_at_random_moments(simulators, tmp_path):
    urls = [simulators(seed).url for seed in range(WORKERS)]

    def worker(slot: int) -> list[Killed]:
        return [kill_once(i, urls[slot], tmp_path) for i in range(slot, RUNS, WORKERS)]

    with ThreadPoolExecutor(WORKERS) as pool:
        runs = [run for batch in pool.map(worker, range(WORKERS)) for run in batch]
    assert len(runs) == RUNS
    endings = [check_killed(run) for run in sorted(runs, key=lambda r: r.index)]
    mid_capture = [run for run in runs if run.capture.acknowledged]
    # The seeded moments reach into the capture itself, not only the start-up.
    assert len(mid_capture) >= RUNS // 2, endings
    print("kill -9 endings:", {ending: endings.count(ending) for ending in set(endings)})

    # Resume a few of the killed sessions (the first ones with cycles still to capture).
    unfinished = [
        run
        for run in sorted(runs, key=lambda r: r.index)
        if run.capture.session_path is not None
        and 0 < len(load_session(run.capture.session_path).accepted_cycles) < CYCLES
    ]
    assert len(unfinished) >= RESUMED
    for run in unfinished[:RESUMED]:
        path = run.capture.session_path
        before = load_session(path)
        assert before.status == "running"  # killed: no word from the writer
        resumed = Capture(["--resume", str(path), "--timeout", "3", "--every", "0.01"])
        assert resumed.finish(60) == 0, resumed.errors
        after = load_session(path)
        assert after.status == "finished"
        new = sorted(resumed.acknowledged)
        assert new[0] == before.next_cycle  # numbering continues after the last cycle on disk
        assert sorted(after.cycles) == list(range(1, new[-1] + 1))
        assert len(after.accepted_cycles) == CYCLES
        assert_acknowledged_kept(resumed, after)
        verify = subprocess.run(
            [sys.executable, "-m", "station", "verify", str(path)],
            capture_output=True,
            text=True,
            cwd=REPO,
        )
        assert verify.returncode == 0, verify.stdout + verify.stderr
        assert after.last_hash in verify.stdout


def test_kill9_resume_twice(simulators, tmp_path):
    """A resumed session killed again resumes again: numbering and chain still hold."""
    url = simulators(107).url
    first = Capture(capture_args(url, tmp_path, CYCLES))
    assert first.wait_line(lambda line: line.startswith("cycle 10 "), 30.0), first.errors
    first.process.send_signal(signal.SIGKILL)
    first.finish()
    path = first.session_path
    assert path is not None
    before_second = load_session(path)
    second = Capture(["--resume", str(path), "--timeout", "3", "--every", "0.01"])
    assert second.wait_line(lambda line: line.startswith("cycle "), 30.0), second.errors
    second.process.send_signal(signal.SIGKILL)
    second.finish()
    session = load_session(path)
    assert_acknowledged_kept(first, session)
    assert_acknowledged_kept(second, session)
    assert min(second.acknowledged) == before_second.next_cycle
    assert verify_session(path).ok
    third = Capture(["--resume", str(path), "--timeout", "3", "--every", "0.01"])
    assert third.finish(60) == 0, third.errors
    final = load_session(path)
    assert final.status == "finished" and len(final.accepted_cycles) == CYCLES
    assert [e["type"] for e in final.events].count("resume") == 2
    assert sorted(final.cycles) == list(range(1, max(final.cycles) + 1))
