"""``station capture`` as a script runs it: a real subprocess against the simulator on a pty."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from station.session.model import load_session
from station.session.verify import verify_session

from .conftest import CYCLES_ONLY, EVERY_KIND

REPO = Path(__file__).resolve().parents[2]


def station(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    """Run ``station`` in a subprocess (no site procedures from the environment)."""
    return subprocess.run(
        [sys.executable, "-m", "station", *args],
        capture_output=True,
        text=True,
        cwd=REPO,
        env={**os.environ, "STATION_PROCEDURES": ""},
        timeout=timeout,
    )


@pytest.fixture
def procedures(tmp_path: Path) -> Path:
    folder = tmp_path / "procedures"
    folder.mkdir()
    (folder / "every-kind.toml").write_bytes(EVERY_KIND)
    return folder


def test_full_headless_session(simulator, procedures, tmp_path):
    sessions = tmp_path / "sessions"
    done = station(
        "capture", "--procedure", "every-kind", "--procedures", str(procedures),
        "--port", simulator.url, "--protocol", "mitutoyo", "--robot", "KSC 7/../../etc",
        "--operator", "ana", "--sessions", str(sessions), "--input", "x=12.5",
        "--limit", "x=-0.002:0.002", "--cycles", "4",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    cycle_lines = [line for line in lines if line.startswith("cycle ")]
    # Two single captures (x, y) in the repeat block, then four cycles of x, y, z.
    assert re.fullmatch(r"cycle 1 x=[+-]\d\.\d{5} y=[+-]\d\.\d{5}", cycle_lines[0])
    assert re.fullmatch(r"cycle 6 x=\S+ y=\S+ z=\S+", cycle_lines[-1])
    assert len(cycle_lines) == 6
    path = Path(lines[-2].removeprefix("session file: "))
    assert path.parent == sessions  # the robot's odd name stays a file name in the folder
    session = load_session(path, recover=False)
    assert lines[-1] == f"last hash: {session.last_hash}"
    assert "BASIC STATISTICS COMPREHENSIVE REPORT" in done.stdout
    assert session.status == "finished"
    assert session.inputs["pendant"] == {"x": 12.5}
    steps = [e for e in session.events if e["type"] == "step"]
    assert steps and all(e["by"] == "station capture" for e in steps)
    assert session.header["limits"]["x"]["usl"] == 0.002
    assert verify_session(path).ok


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["--procedure", "repeatability"], "--port, --protocol, --robot missing"),
        (["--procedure", "nope", "--port", "/dev/null", "--protocol", "mitutoyo", "--robot", "r"],
         "no procedure 'nope'"),
        (["--procedure", "repeatability", "--port", "/dev/null", "--protocol", "mitutoyo",
          "--robot", "r", "--limit", "q=0:1"], "limits given for q"),
        (["--procedure", "repeatability", "--port", "/dev/null", "--protocol", "mitutoyo",
          "--robot", "r", "--cycles", "0"], "--cycles must be more than 0"),
        (["--procedure", "every-kind", "--port", "/dev/null", "--protocol", "mitutoyo",
          "--robot", "r"], "pass --input x=VALUE"),
        (["--resume", "/nonexistent/session.jsonl"], "does not exist"),
    ],
)  # fmt: skip
def test_bad_input_is_one_line_exit_2(procedures, tmp_path, arguments, message):
    done = station("capture", "--procedures", str(procedures), "--sessions", str(tmp_path),
                   *arguments)  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("station: ")
    assert message in done.stderr
    assert not list(tmp_path.glob("*.jsonl"))  # refused before any session file


def test_port_that_never_opens(tmp_path):
    done = station(
        "capture", "--procedure", "repeatability", "--port", str(tmp_path / "ttyUSB9"),
        "--protocol", "mitutoyo", "--robot", "r", "--sessions", str(tmp_path), "--timeout", "0.5",
    )  # fmt: skip
    assert done.returncode == 2
    assert "did not connect" in done.stderr and done.stderr.count("\n") == 1
    assert not list(tmp_path.glob("*.jsonl"))


@pytest.mark.parametrize(
    ("procedure", "said"),
    [
        # The software zero needs a fresh z too: the run stops there with the reader's sentence.
        ("repeatability", "Could not zero z"),
        ("cycles-only", "2 reading sets in a row were refused (last: Not recorded: no reading"),
    ],
)
def test_refused_sets_stop_the_run_resumably(simulator, procedures, tmp_path, procedure, said):
    (procedures / "cycles-only.toml").write_bytes(CYCLES_ONLY)
    # Device channel 4 (z) never answers: every set is refused, nothing is recorded.
    done = station(
        "capture", "--procedure", procedure, "--procedures", str(procedures),
        "--port", simulator.url, "--protocol", "mitutoyo", "--robot", "r",
        "--sessions", str(tmp_path / "s"), "--map", "1=x,2=y,4=z", "--timeout", "0.3",
        "--attempts", "2",
    )  # fmt: skip
    assert done.returncode == 2
    errors = [line for line in done.stderr.splitlines() if not line.startswith("station: warn")]
    assert len(errors) == 1, done.stderr
    assert said in errors[0] and "--resume" in errors[0]
    (path,) = (tmp_path / "s").glob("*.jsonl")
    session = load_session(path, recover=False)
    assert session.status == "interrupted" and not session.cycles
    assert session.events[-1]["reason"].startswith("station capture stopped: ")
