"""``station capture`` as a script runs it: a real subprocess against the simulator on a pty."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import run_station

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, GaugeSpec, Simulator, fixture_model
from station.session.model import load_session
from station.session.verify import verify_session

from .conftest import CYCLES_ONLY, EVERY_KIND

REPO = Path(__file__).resolve().parents[2]


def station(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    """Run ``station`` in this process, as a script: no terminal to ask an alarm's cause at
    (the tests below that are about the terminal or the process run the real one)."""
    return run_station(*args, cwd=REPO)


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
        "--limit", "x=-0.002:0.002", "--cycles", "4", "--every", "0.01",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    cycle_lines = [line for line in lines if line.startswith("cycle ")]
    # Two single captures (x, y) in the repeat block, then four cycles of x, y, z: values at
    # one decimal beyond the 0.0001 in gauges' step, as every figure.
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
        (["--procedure", "repeatability", "--port", "/dev/null", "--protocol", "mitutoyo",
          "--robot", "r", "--unit", "mm"],
         "resolution and limits are in in; give them in mm: --resolution R --limit x=LSL:USL "
         "--limit y=LSL:USL --limit z=LSL:USL"),
        (["--procedure", "repeatability", "--port", "/dev/null", "--protocol", "mitutoyo",
          "--robot", "r", "--unit", "mm", "--resolution", "0.001", "--limit", "x=-0.02:0.02"],
         "give them in mm: --limit y=LSL:USL --limit z=LSL:USL"),
        (["--procedure", "repeatability", "--port", "/dev/null", "--protocol", "mitutoyo",
          "--robot", "r", "--resolution", "-1"], "--resolution must be more than 0"),
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
        "--attempts", "2", "--trigger", "poll", "--every", "0.01",
    )  # fmt: skip
    assert done.returncode == 2
    errors = [line for line in done.stderr.splitlines() if not line.startswith("station: warn")]
    assert len(errors) == 1, done.stderr
    assert said in errors[0] and "--resume" in errors[0]
    (path,) = (tmp_path / "s").glob("*.jsonl")
    session = load_session(path, recover=False)
    assert session.status == "interrupted" and not session.cycles
    assert session.events[-1]["reason"].startswith("station capture stopped: ")


def mm_simulator(protocol: str = "mitutoyo", push_rate: float = 0.0) -> Simulator:
    """Three gauges in millimetres at 0.001 mm (a metric fixture)."""
    model = fixture_model(
        ("x", "y", "z"),
        axis=AxisModel(noise=0.004),
        gauge=GaugeSpec(resolution=0.001, unit="mm", low=-12.5, high=12.5),
    )
    return Simulator(get_protocol(protocol), model, seed=3, push_rate=push_rate)


def test_unit_and_resolution_options(procedures, tmp_path):
    (procedures / "cycles-only.toml").write_bytes(CYCLES_ONLY)
    sim = mm_simulator()
    sim.start_pty()
    try:
        # Mitutoyo frames carry no unit: only the operator can say these gauges read in mm.
        done = station(
            "capture", "--procedure", "cycles-only", "--procedures", str(procedures),
            "--port", sim.url, "--protocol", "mitutoyo", "--robot", "r", "--sessions",
            str(tmp_path), "--unit", "mm", "--resolution", "0.001", "--cycles", "3",
            "--limit", "x=-0.05:0.05", "--every", "0.01",
        )  # fmt: skip
    finally:
        sim.stop()
    assert done.returncode == 0, done.stderr
    (path,) = tmp_path.glob("*.jsonl")
    session = load_session(path, recover=False)
    assert (session.header["unit"], session.header["resolution"]) == ("mm", 0.001)
    assert session.header["limits"]["x"]["usl"] == 0.05
    # The gauge step and every figure one decimal beyond it (the one number format).
    assert "Unit: mm   Resolution: 0.0010 " in done.stdout
    cycle_lines = [line for line in done.stdout.splitlines() if line.startswith("cycle ")]
    assert len(cycle_lines) == 3
    assert all(re.fullmatch(r"cycle \d (\w=[+-]\d+\.\d{4} ?){3}", line) for line in cycle_lines)


def test_gauges_in_another_unit_are_refused_before_the_session(procedures, tmp_path):
    # U-WAVE frames say their unit: millimetres, while the procedure is in inches.
    sim = mm_simulator("uwave", push_rate=20.0)
    sim.start_pty()
    try:
        done = station(
            "capture", "--procedure", "repeatability", "--port", sim.url, "--protocol",
            "uwave", "--robot", "r", "--sessions", str(tmp_path), "--trigger", "push",
            "--timeout", "5",
        )  # fmt: skip
    finally:
        sim.stop()
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert "the gauges send steps of 0.001 mm; the session is in inches at 0.0001" in done.stderr
    assert "--unit mm" in done.stderr and "nothing was written" in done.stderr
    assert not list(tmp_path.glob("*.jsonl"))


@pytest.mark.parametrize(
    "options",
    [["--cycles", "40"], ["--limit", "x=-1:1"], ["--trigger", "push"], ["--robot", "other"],
     ["--operator", "bo"], ["--procedure", "linearity"], ["--unit", "mm"],
     ["--resolution", "0.001"], ["--placements", "2"], ["--strokes", "3"]],
)  # fmt: skip
def test_resume_refuses_setup_options(tmp_path, options):
    from station.run import PortSetup, SessionSetup
    from station.session.journal import SessionWriter

    from .conftest import DEVICE_MAP, repeatability

    setup = SessionSetup(
        procedure=repeatability(),
        robot="KSC-7",
        operator="ana",
        ports=(PortSetup(str(tmp_path / "ttyUSB9"), "mitutoyo", DEVICE_MAP),),
    )
    writer = SessionWriter.create(tmp_path, setup.header_fields())
    path = writer.path
    writer.close()
    before = Path(path).read_bytes()
    done = station("capture", "--resume", str(path), "--timeout", "0.5", *options)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1
    assert f"{' '.join(options)} (the session's: " in done.stderr
    assert "cannot change a resumed session" in done.stderr
    assert Path(path).read_bytes() == before  # refused before anything was written


def test_resume_accepts_the_same_setup_again(tmp_path):
    """A script may repeat its command line with --resume: equal values are not a change."""
    from station.run import PortSetup, SessionSetup
    from station.session.journal import SessionWriter

    from .conftest import DEVICE_MAP, repeatability

    port = tmp_path / "ttyUSB9"
    setup = SessionSetup(
        procedure=repeatability(),
        robot="KSC-7",
        operator="ana",
        ports=(PortSetup(str(port), "mitutoyo", DEVICE_MAP),),
        cycles=28,
    )
    writer = SessionWriter.create(tmp_path, setup.header_fields())
    path = writer.path
    writer.close()
    done = station(
        "capture", "--resume", str(path), "--timeout", "0.3", "--procedure", "repeatability",
        "--robot", "KSC-7", "--operator", "ana", "--cycles", "28", "--trigger", "poll",
        "--unit", "in", "--resolution", "0.0001", "--limit", "x=-0.001:0.001",
        "--every", "0.01",
    )  # fmt: skip
    # Past the option check: it fails only because the recorded port does not exist.
    assert done.returncode == 2 and "did not connect" in done.stderr, done.stderr


CRASHING = """
import sys
import station.run.engine as runner

original = runner.Runner.capture
calls = []


def capture(self, *args, **kwargs):
    calls.append(1)
    if len(calls) == 3:
        raise ValueError("a bug in the capture path")
    return original(self, *args, **kwargs)


runner.Runner.capture = capture
from station.cli import main

sys.exit(main(sys.argv[1:]))
"""


def test_a_crash_in_the_capture_thread_interrupts_the_session(simulator, tmp_path):
    # A bug injected on purpose (the third capture raises): no real part fails on demand.
    done = subprocess.run(
        [sys.executable, "-c", CRASHING, "capture", "--procedure", "repeatability",
         "--port", simulator.url, "--protocol", "mitutoyo", "--robot", "r",
         "--sessions", str(tmp_path), "--cycles", "30", "--trigger", "poll", "--every", "0.01"],
        capture_output=True, text=True, cwd=REPO, timeout=60,
        env={**os.environ, "STATION_PROCEDURES": ""},
    )  # fmt: skip
    assert done.returncode == 70, done.stdout + done.stderr
    assert "Traceback" not in done.stderr and done.stderr.count("\n") == 1, done.stderr
    assert "station capture crashed (ValueError: a bug in the capture path)" in done.stderr
    assert "--resume" in done.stderr
    assert "BASIC STATISTICS" not in done.stdout  # no summary of a session that did not end
    (path,) = tmp_path.glob("*.jsonl")
    session = load_session(path, recover=False)
    assert session.status == "interrupted" and len(session.cycles) == 2
    assert session.events[-1]["reason"].startswith("station capture crashed: ValueError")
    assert not any(e["type"] == "finish" for e in session.events)


def test_capture_help_fits_80_columns():
    done = subprocess.run(
        [sys.executable, "-m", "station", "capture", "--help"],
        capture_output=True, text=True, cwd=REPO, env={**os.environ, "COLUMNS": "80"},
    )  # fmt: skip
    assert done.returncode == 0
    assert max(len(line) for line in done.stdout.splitlines()) <= 79, done.stdout


def _read_until(stream, marker: str, timeout: float = 60.0) -> str:
    """What ``stream`` (a pipe's fd) gives until ``marker`` appears."""
    import select
    import time

    seen = b""
    deadline = time.monotonic() + timeout
    while marker.encode() not in seen:
        left = deadline - time.monotonic()
        assert left > 0, f"no {marker!r} in: {seen.decode(errors='replace')}"
        if select.select([stream], [], [], left)[0]:
            chunk = os.read(stream.fileno(), 65536)
            assert chunk, f"the command ended before {marker!r}: {seen.decode()}"
            seen += chunk
    return seen.decode()


def test_capture_prints_alarms_and_asks_their_causes_only_at_a_terminal(warming_robot, tmp_path):
    import pty

    folder = tmp_path / "procedures"
    folder.mkdir()
    (folder / "cycles-only.toml").write_bytes(CYCLES_ONLY)
    arguments = [
        sys.executable, "-m", "station", "capture", "--procedure", "cycles-only",
        "--procedures", str(folder), "--port", warming_robot.url, "--protocol", "mitutoyo",
        "--robot", "R7", "--sessions", str(tmp_path / "s"), "--cycles", "40",
        "--every", "0.01",
    ]  # fmt: skip
    env = {**os.environ, "STATION_PROCEDURES": ""}

    # A script (no terminal on stdin): the alarms are printed as they are written, nothing
    # is asked, the session finishes.
    script = subprocess.run(
        arguments, stdin=subprocess.DEVNULL, capture_output=True, text=True, cwd=REPO,
        env=env, timeout=120,
    )  # fmt: skip
    assert script.returncode == 0, script.stderr
    printed = [line for line in script.stdout.splitlines() if line.startswith("alarm #")]
    assert printed and "[live]:" in printed[0] and "rule" in printed[0]
    assert "not acknowledged. For each" not in script.stdout
    session = load_session(Path(script.stdout.splitlines()[-2].split(": ", 1)[1]))
    assert len(printed) == len(session.alarms) and not session.acks
    # Each printed as soon as written: after the cycle that raised it, before the next one.
    lines = script.stdout.splitlines()
    first = session.alarms[0]
    at = lines.index(printed[0])
    assert lines[at - 1].startswith(f"cycle {first['raised_at']} ")
    assert "ALARMS RECORDED DURING THE SESSION" in script.stdout  # the summary lists them

    # At a terminal: one question per alarm; the first gets a cause, the rest are left.
    master, slave = pty.openpty()
    process = subprocess.Popen(
        arguments, stdin=slave, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=REPO,
        env=env,
    )  # fmt: skip
    os.close(slave)
    try:
        _read_until(process.stdout, "  cause: ")
        os.write(master, b"coffee\n\n\n")  # not one of the causes: said, and asked again
        _read_until(process.stdout, "not one of the procedure's causes")
        os.write(master, b"temperature\ncell door open\nwaited 30 min\n" + b"\n" * 200)
        out, err = process.communicate(timeout=120)
    finally:
        os.close(master)
        if process.poll() is None:
            process.kill()
    assert process.returncode == 0, err.decode()
    path = Path(out.decode().splitlines()[-2].split(": ", 1)[1])
    session = load_session(path)
    (ack,) = session.acks
    assert ack["cause"] == "temperature" and ack["action"] == "waited 30 min"
    assert ack["alarm"] == session.alarms[0]["seq"] and ack["by"] == "station capture"
    assert "acknowledged: temperature (cell door open); corrective action: waited 30 min" in (
        " ".join(out.decode().split())
    )


def test_capture_summary_of_nine_cycles_is_provisional(simulator, tmp_path):
    simulator.returns_each_set = True  # no zero step: the robot returns between two polls
    folder = tmp_path / "procedures"
    folder.mkdir()
    (folder / "cycles-only.toml").write_bytes(CYCLES_ONLY)
    done = station(
        "capture", "--procedure", "cycles-only", "--procedures", str(folder),
        "--port", simulator.url, "--protocol", "mitutoyo", "--robot", "R9",
        "--sessions", str(tmp_path / "s"), "--cycles", "9", "--limit", "x=-0.002:0.002",
        "--every", "0.01",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    verdicts = [line for line in done.stdout.splitlines() if line.startswith("VERDICT:")]
    assert verdicts[0].startswith("VERDICT: PROVISIONAL: 9 of 25 readings (Cpk "), verdicts
    assert not any(" CAPABLE (" in line for line in verdicts)
