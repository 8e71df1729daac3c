"""A file-size limit (RLIMIT_FSIZE in the child) and a full disk (a small tmpfs, when this
machine lets us mount one) stop ``station capture`` with a one-line error; nothing acknowledged
is lost, and the session resumes once there is room."""

from __future__ import annotations

import os
import resource
import shutil
import subprocess
from pathlib import Path

import pytest

from station.session.model import load_session
from station.session.verify import verify_session

from .conftest import Capture, assert_acknowledged_kept, capture_args

CYCLES = 80
FILE_LIMIT = 16_000  # bytes: the header, the steps and some twenty cycles


def limit_file_size() -> None:
    """preexec_fn: the child may not write any file past FILE_LIMIT bytes."""
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_LIMIT, FILE_LIMIT))


def assert_stopped_cleanly(capture: Capture, cause: str) -> Path:
    """Exit 2, one ``station:`` line naming the cause, every acknowledged cycle on disk."""
    assert capture.finish() == 2
    errors = [line for line in capture.errors if not line.startswith("station: warning:")]
    assert len(errors) == 1, capture.errors
    assert errors[0].startswith("station: ") and cause in errors[0]
    assert "nothing was lost up to cycle" in errors[0] and "--resume" in errors[0]
    path = capture.session_path
    assert path is not None and capture.acknowledged
    session = load_session(path)
    assert_acknowledged_kept(capture, session)
    assert max(session.cycles) == max(capture.acknowledged)
    assert f"up to cycle {max(session.cycles)} " in errors[0]
    assert verify_session(path).ok
    return path


def test_file_size_limit_stops_with_one_line(simulators, tmp_path):
    url = simulators(21).url
    capture = Capture(capture_args(url, tmp_path, CYCLES), preexec_fn=limit_file_size)
    path = assert_stopped_cleanly(capture, "file-size limit")
    assert path.stat().st_size <= FILE_LIMIT

    resumed = Capture(["--resume", str(path), "--timeout", "3", "--every", "0.01"])
    assert resumed.finish(60) == 0, resumed.errors
    final = load_session(path)
    assert final.status == "finished" and len(final.accepted_cycles) == CYCLES
    assert verify_session(path).ok


@pytest.fixture
def small_tmpfs(tmp_path):
    """A 32 KiB tmpfs, or a skip when mounting is not permitted here."""
    mount, umount = shutil.which("mount"), shutil.which("umount")
    if os.geteuid() != 0 or mount is None or umount is None:
        pytest.skip("a full disk needs a small tmpfs: mounting one requires root")
    folder = tmp_path / "full"
    folder.mkdir()
    done = subprocess.run(
        [mount, "-t", "tmpfs", "-o", "size=32k", "tmpfs", str(folder)],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()}")
    yield folder
    subprocess.run([umount, str(folder)], check=False)


def test_full_disk_stops_with_one_line(simulators, small_tmpfs, tmp_path):
    url = simulators(22).url
    capture = Capture(capture_args(url, small_tmpfs, CYCLES))
    path = assert_stopped_cleanly(capture, "disk is full")
    # Free room the way an operator would (move the file to a roomy disk), then resume there.
    roomy = tmp_path / path.name
    shutil.copyfile(path, roomy)
    resumed = Capture(["--resume", str(roomy), "--timeout", "3", "--every", "0.01"])
    assert resumed.finish(60) == 0, resumed.errors
    assert load_session(roomy).status == "finished"


def test_push_trigger_failed_write_says_why(simulators, tmp_path):
    """With the push trigger the sets are written on the runner's own thread: the failed
    write's sentence (not a bare "the session is failed") still ends the command."""
    url = simulators(23, push_rate=40.0).url
    args = capture_args(url, tmp_path, CYCLES, trigger="push")
    capture = Capture(args, preexec_fn=limit_file_size)
    path = assert_stopped_cleanly(capture, "file-size limit")
    assert load_session(path).status == "running"  # no word could be written after the failure
