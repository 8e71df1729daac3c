"""Linearity end to end: ``station capture --procedure linearity`` against ``station simulate
--model bar`` (both real processes on a real pty), then ``station verify`` and ``station analyze
FILE --json`` on the session file."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import time
from pathlib import Path

import pytest
from helpers import STATION, run_station, start_simulator, stop_simulator

from station.instruments.simulator import BarModel
from station.session.model import load_session

SEED = 5
BAR = {"points": 100, "dwell": 6, "bow": 0.0015, "sag": 0.0008, "noise": 0.00002}
STROKES = 25
HOLD = 20


def start_bar(*extra: str) -> tuple[subprocess.Popen, str]:
    """``station simulate --model bar`` pushing 500 sets a second; returns it and its URL."""
    return start_simulator(
        "--protocol",
        "mitutoyo",
        "--model",
        "bar",
        "--seed",
        str(SEED),
        "--push-rate",
        "500",
        *(f"--{key}={value}" for key, value in BAR.items()),
        # The robot stands at A from the simulator's first frame: long enough for a capture
        # started on a loaded machine to check the frames and zero there (8 s was not).
        f"--hold={HOLD}",
        *extra,
    )


def capture(url: str, folder: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [
            *STATION,
            "capture",
            "--procedure",
            "linearity",
            "--port",
            url,
            "--protocol",
            "mitutoyo",
            "--robot",
            "KSC-7",
            "--operator",
            "tester",
            "--trigger",
            "push",
            "--strokes",
            str(STROKES),
            "--sessions",
            str(folder),
            *extra,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def analyze_json(path: Path) -> dict:
    done = run_station("analyze", str(path), "--json")
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def verify(path: Path) -> None:
    done = run_station("verify", str(path))
    assert done.returncode == 0, done.stdout + done.stderr


def streamed_points(path: Path) -> list[list[float]]:
    """Every point of the stroke step, in the order it was written."""
    return [list(row) for batch in load_session(path).samples for row in batch.values]


def assert_contiguous(path: Path) -> None:
    """No point was dropped or torn apart: the recorded (h, v, s) points are the simulator's
    k-th sets for consecutive k, each set one instant (the model gives what it sent)."""
    session = load_session(path)
    model = BarModel(**BAR)
    offsets = {
        channel: spec["offset"]
        for channel, spec in session.zeroes[-1]["channels"].items()  # the last zero
    }
    points = streamed_points(path)
    channels = session.samples[0].channels

    def shown(channel: str, k: int) -> float:
        # The device shows its reading; the station subtracts the software zero's offset.
        return model.value(channel, k, SEED) - offsets[channel]

    def point_is(i: int, k: int) -> bool:
        return all(abs(points[i][c] - shown(name, k)) < 1e-7 for c, name in enumerate(channels))

    # The robot may still stand at A (where it was zeroed) when the stream begins: those points
    # show A within the indicators' own noise. From its first point of travel on, every point
    # is the simulator's next set.
    s_index = channels.index("s")
    moved = next(i for i, point in enumerate(points) if abs(point[s_index]) > 0.001)
    assert all(abs(point[s_index]) <= 0.001 for point in points[:moved])
    first = max(moved - 1, 0)
    start = next(
        (k for k in range(20_000) if all(point_is(first + i, k + i) for i in range(40))), None
    )
    assert start is not None, "the first points of travel are not consecutive sets"
    wrong = next((i for i in range(first, len(points)) if not point_is(i, start + i - first)), None)
    assert wrong is None, f"point {wrong} is missing, repeated or mixes two sets"


def test_a_linearity_session_streams_every_point_and_recovers_the_bar(tmp_path: Path) -> None:
    simulator, url = start_bar()
    try:
        process = capture(url, tmp_path)
        out, err = process.communicate(timeout=60)
    finally:
        stop_simulator(simulator)
    assert process.returncode == 0, err
    lines = [line for line in out.splitlines() if line.startswith("stroke ")]
    assert len(lines) == STROKES
    assert re.fullmatch(
        r"stroke 1 (A→B|B→A) \d+ points h=\d\.\d{5} v=\d\.\d{5} \(LS straightness\)", lines[0]
    )
    directions = [line.split()[2] for line in lines]
    assert all(a != b for a, b in zip(directions, directions[1:], strict=False))
    path = next(tmp_path.glob("*.jsonl"))
    verify(path)
    assert_contiguous(path)

    document = analyze_json(path)
    linearity = document["linearity"]
    assert len(linearity["strokes"]) == STROKES
    for stroke in linearity["strokes"]:
        # The bow is seen by h, the sag by v; the bar model's wobble adds at most its p-v.
        assert stroke["h"]["mz"] == pytest.approx(BAR["bow"], abs=0.0004 * 2 + 0.00015)
        assert stroke["v"]["mz"] == pytest.approx(BAR["sag"], abs=0.0002 * 2 + 0.00015)


def test_sigterm_mid_stream_then_resume_continues_the_strokes(tmp_path: Path) -> None:
    simulator, url = start_bar()
    try:
        process = capture(url, tmp_path)
        seen = []
        deadline = time.monotonic() + 30
        while len(seen) < 8 and time.monotonic() < deadline:
            line = process.stdout.readline()
            if line.startswith("stroke "):
                seen.append(line)
        process.send_signal(signal.SIGTERM)
        out, err = process.communicate(timeout=20)
        assert process.returncode == 143, err
        path = next(tmp_path.glob("*.jsonl"))
        assert load_session(path).status == "interrupted"
        acknowledged = len(seen) + sum(1 for line in out.splitlines() if line.startswith("stroke "))

        resumed = capture(url, tmp_path, "--resume", str(path))
        out, err = resumed.communicate(timeout=60)
    finally:
        stop_simulator(simulator)
    assert resumed.returncode == 0, err
    numbers = [int(line.split()[1]) for line in out.splitlines() if line.startswith("stroke ")]
    # The numbering continues after the strokes acknowledged before the signal.
    assert numbers == list(range(acknowledged + 1, STROKES + 1))
    verify(path)
    document = analyze_json(path)
    assert len(document["linearity"]["strokes"]) == STROKES


def test_a_site_copy_of_linearity_under_another_id_gets_the_linearity_report(
    tmp_path: Path,
) -> None:
    """The report follows the procedure's ``analysis``, never its id: a site's own copy of
    linearity.toml (id "bar-check") gets the linearity report from capture and analyze."""
    from station.methods import analyze_session_file
    from station.procedures import builtin_procedures_dir

    folder = tmp_path / "site"
    folder.mkdir()
    text = (builtin_procedures_dir() / "linearity.toml").read_text()
    text = re.sub(r'(?m)^id = "linearity"$', 'id = "bar-check"', text)
    assert 'id = "bar-check"' in text
    (folder / "bar-check.toml").write_text(text)
    simulator, url = start_bar()
    try:
        process = subprocess.Popen(
            [
                *STATION,
                "capture",
                "--procedure",
                "bar-check",
                "--procedures",
                str(folder),
                "--port",
                url,
                "--protocol",
                "mitutoyo",
                "--robot",
                "KSC-7",
                "--trigger",
                "push",
                "--strokes",
                "4",
                "--sessions",
                str(tmp_path / "sessions"),
            ],  # fmt: skip
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        out, err = process.communicate(timeout=60)
    finally:
        stop_simulator(simulator)
    assert process.returncode == 0, err
    assert "LINEARITY REPORT" in out
    path = next((tmp_path / "sessions").glob("*.jsonl"))
    assert load_session(path).procedure_id == "bar-check"
    document = analyze_json(path)
    assert document["procedure"] == "linearity" and len(document["linearity"]["strokes"]) == 4
    # The TUI's summary reads the same registry (its report block is this one).
    report = analyze_session_file(path)
    assert report.kind == "linearity" and report.sections
