"""``station capture`` paced by the robot (``--trigger arrival`` against ``station simulate
--cycle-period``) or by the operator (``--every``, Enter), as real subprocesses on real ptys."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

import pytest
from helpers import STATION, start_simulator, stop_simulator

from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec
from station.session.model import load_session

PERIOD = 1.0
"""The robot's round trip: its rest (a third of it) holds a settle time of dense readings even
when a loaded machine delays some polls (stillness is judged only from readings at most half a
settle time apart)."""
SEED = 5
NOISE = 0.01
"""10 resolutions: every cycle's rest position is told apart from its neighbours'."""

PACED = """\
id = "paced"
title = "Cycles paced by the robot"
version = "1"
report_section = "2.6"
channels = ["x", "y", "z"]
unit = "mm"
resolution = 0.001
trigger = "arrival"

[cycles]
min = 2
target = 10

[limits]
tolerance = 0.1

[arrival]
band = 0.1
still = 2
settle = 0.15
timeout = 1.0

[[steps]]
id = "ready"
kind = "check"
title = "Ready"

[[steps]]
id = "cycles"
kind = "cycles"
title = "Cycles"
prompt = "Cycle {cycle} of {count}."
"""


@pytest.fixture
def procedures(tmp_path: Path) -> Path:
    folder = tmp_path / "procedures"
    folder.mkdir()
    (folder / "paced.toml").write_text(PACED)
    return folder


def simulate(*extra: str) -> tuple[subprocess.Popen, str]:
    """``station simulate`` (Mitutoyo, x y z in mm at 0.001) as a subprocess; its URL."""
    return start_simulator(
        "--protocol", "mitutoyo", "--seed", str(SEED), "--noise", str(NOISE), *extra
    )


def capture(*args: str, timeout: float = 90) -> subprocess.CompletedProcess:
    return subprocess.run(
        [*STATION, "capture", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        stdin=subprocess.DEVNULL,
    )


def rest_cycle(values: dict[str, float], within: float = 0.0021) -> int:
    """The simulated robot's cycle whose rest position ``values`` are (within two counts: the
    indicators' own noise, a third of a count, and the tail of the settling swing may each
    round one off); fails when none is."""
    model = FixtureModel(dict.fromkeys("xyz", AxisModel(noise=NOISE)), GaugeSpec(0.001))
    for cycle in range(200):
        rest = {c: model.value(c, cycle, SEED) for c in "xyz"}
        if all(abs(values[c] - rest[c]) <= within for c in rest):
            return cycle
    raise AssertionError(f"{values} is no rest position of the robot")


def test_arrival_records_ten_cycles_one_per_round_trip_at_rest(
    tmp_path: Path, procedures: Path
) -> None:
    process, url = simulate("--cycle-period", str(PERIOD))
    try:
        done = capture(
            "--procedure", "paced", "--procedures", str(procedures), "--port", url,
            "--protocol", "mitutoyo", "--map", "1=x,2=y,3=z", "--robot", "R1",
            "--sessions", str(tmp_path / "s"), "--cycles", "10", "--timeout", "3",
        )  # fmt: skip
    finally:
        stop_simulator(process)
    assert done.returncode == 0, done.stderr
    session = load_session(next((tmp_path / "s").glob("*.jsonl")))
    assert session.header["instruments"]["trigger"] == "arrival"  # the procedure's default
    assert session.header["instruments"]["arrival"] == {
        "band": 0.1,
        "still": 2,
        "settle": 0.15,
        "timeout": 1.0,
        "stop": "low",
    }
    cycles = [session.cycles[n] for n in sorted(session.cycles)]
    assert len(cycles) == 10
    # Each set is a rest position of the robot (never the free travel, never mid-swing), of
    # consecutive round trips: one set per departure, none skipped, none twice.
    rests = [rest_cycle({c: r.value for c, r in cycle.readings.items()}) for cycle in cycles]
    assert all(later > earlier for earlier, later in zip(rests, rests[1:], strict=False)), rests
    # Spaced by the period: k round trips apart in time when k rests apart (a return the
    # station missed under load is a longer gap, never a second set of one return).
    times = [min(r.t_mono for r in cycle.readings.values()) for cycle in cycles]
    for i in range(len(times) - 1):
        apart = (rests[i + 1] - rests[i]) * PERIOD
        # (half a period of slack: a loaded machine reads a rest late, never a return twice)
        assert abs(times[i + 1] - times[i] - apart) < 0.5 * PERIOD, (times, rests)
    assert rests[-1] - rests[0] <= 12, rests  # nearly every round trip was a cycle


def test_a_return_that_does_not_settle_is_reported_not_recorded(
    tmp_path: Path, procedures: Path
) -> None:
    # A swing of 0.2 s is seen by polls every 0.0375 s (a quarter of the settle time) at any
    # load; a swing as fast as the polls would alias into a still reading.
    process, url = simulate(
        "--cycle-period", str(PERIOD), "--hunt", "y=0.01", "--hunt-every", "2",
        "--hunt-period", "0.2",
    )  # fmt: skip
    try:
        done = capture(
            "--procedure", "paced", "--procedures", str(procedures), "--port", url,
            "--protocol", "mitutoyo", "--map", "1=x,2=y,3=z", "--robot", "R1",
            "--sessions", str(tmp_path / "s"), "--cycles", "4", "--timeout", "3",
        )  # fmt: skip
    finally:
        stop_simulator(process)
    assert done.returncode == 0, done.stderr
    assert "but y was not still" in done.stderr
    session = load_session(next((tmp_path / "s").glob("*.jsonl")))
    cycles = [session.cycles[n] for n in sorted(session.cycles)]
    rests = [rest_cycle({c: r.value for c, r in cycle.readings.items()}) for cycle in cycles]
    # Every second return hunts on y: those are reported, and only the settled ones recorded.
    assert len(rests) == 4 and len({rest % 2 for rest in rests}) == 1, rests


def test_poll_without_a_pace_is_refused_naming_the_three_choices(tmp_path: Path) -> None:
    done = capture(
        "--procedure", "repeatability", "--port", str(tmp_path / "ttyUSB9"), "--protocol",
        "mitutoyo", "--robot", "R1", "--trigger", "poll", "--sessions", str(tmp_path / "s"),
    )  # fmt: skip
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1
    assert "--every" in lines[0] and "terminal" in lines[0] and "arrival" in lines[0]
    assert not (tmp_path / "s").exists() or not list((tmp_path / "s").glob("*.jsonl"))


def test_every_paces_polled_cycles(tmp_path: Path, procedures: Path) -> None:
    process, url = simulate()
    try:
        started = time.monotonic()
        done = capture(
            "--procedure", "paced", "--procedures", str(procedures), "--port", url,
            "--protocol", "mitutoyo", "--map", "1=x,2=y,3=z", "--robot", "R1",
            "--sessions", str(tmp_path / "s"), "--cycles", "10", "--trigger", "poll",
            "--every", "0.2",
        )  # fmt: skip
        elapsed = time.monotonic() - started
    finally:
        stop_simulator(process)
    assert done.returncode == 0, done.stderr
    session = load_session(next((tmp_path / "s").glob("*.jsonl")))
    times = [min(r.t_mono for r in session.cycles[n].readings.values()) for n in session.cycles]
    assert len(times) == 10
    assert times[-1] - times[0] >= 1.8 - 0.01
    assert elapsed >= 1.8


def test_a_mm_simulator_against_an_inch_session_is_refused_naming_both(tmp_path: Path) -> None:
    process, url = simulate()  # Mitutoyo frames in mm at 0.001: its defaults
    try:
        done = capture(
            "--procedure", "repeatability", "--port", url, "--protocol", "mitutoyo",
            "--robot", "R1", "--sessions", str(tmp_path / "s"), "--trigger", "poll",
            "--every", "0.01",
        )  # fmt: skip
    finally:
        stop_simulator(process)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1, done.stderr
    assert (
        "the gauges send steps of 0.001, which is mm on this protocol; the session is in "
        "inches at 0.0001"
    ) in done.stderr
    assert "--unit mm --resolution 0.001" in done.stderr
    assert not (tmp_path / "s").exists() or not list((tmp_path / "s").glob("*.jsonl"))


def test_at_a_terminal_poll_waits_for_enter_before_each_cycle(
    tmp_path: Path, procedures: Path
) -> None:
    import os
    import pty

    process, url = simulate()
    master, slave = pty.openpty()
    try:
        capture_process = subprocess.Popen(
            [*STATION, "capture", "--procedure", "paced", "--procedures", str(procedures),
             "--port", url, "--protocol", "mitutoyo", "--map", "1=x,2=y,3=z", "--robot", "R1",
             "--sessions", str(tmp_path / "s"), "--cycles", "3", "--trigger", "poll"],
            stdin=slave, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        os.close(slave)
        prompts = []
        for _ in range(3):
            line = capture_process.stderr.readline()
            while "[Enter]" not in line:
                assert line, "the capture ended before asking for Enter"
                line = capture_process.stderr.readline()
            prompts.append(line.strip())
            # Nothing is captured before Enter.
            time.sleep(0.3)
            assert len(_events(tmp_path)) == len(prompts) - 1
            os.write(master, b"\n")
            _wait_for_cycles(tmp_path, len(prompts))
        # At a terminal the command then asks the cause of each alarm not acknowledged yet:
        # Enter leaves one as it is.
        os.write(master, b"\n" * 50)
        out, err = capture_process.communicate(timeout=60)
    finally:
        os.close(master)
        stop_simulator(process)
    assert capture_process.returncode == 0, err
    assert prompts == [f"Cycle {n} of 3.  [Enter]" for n in (1, 2, 3)]


def _events(tmp_path: Path) -> list[str]:
    import json

    files = list((tmp_path / "s").glob("*.jsonl")) if (tmp_path / "s").exists() else []
    if not files:
        return []
    lines = files[0].read_text().splitlines()[1:]
    return [line for line in lines if json.loads(line).get("type") == "reading"]


def _wait_for_cycles(tmp_path: Path, count: int) -> None:
    deadline = time.monotonic() + 15
    while len(_events(tmp_path)) < count:
        assert time.monotonic() < deadline, f"cycle {count} was not recorded"
        time.sleep(0.05)
