"""Relative accuracy end to end: the runner against the two-fixture simulator on a real pty, and
``station capture`` against ``station simulate --model two-fixture`` (real processes); the
analysis of the session file (``station analyze FILE --json``) recovers the simulator's scale
error per axis and keeps the pendant coordinates with each placement."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from helpers import STATION, run_station

from station.analysis.document import to_json
from station.instruments.protocols import get_protocol
from station.instruments.simulator import GaugeSpec, Simulator, TwoFixtureModel
from station.methods import analyze_session_file
from station.procedures import discover_procedures
from station.run import PortSetup, Runner, SessionSetup
from station.session.model import load_session

from .playing import play_capture

SCALE = (2.0e-5, -1.5e-5, 1.0e-5)
NOISE = 0.0001
PLACEMENTS = 8
DEVICE_MAP = {"1": "x", "2": "y", "3": "z"}


def model(seed: int) -> TwoFixtureModel:
    """The simulator's model: mitutoyo has no zero command, so the station zeroes in software
    from readings at home (the indicators' own noise 0.3 of a resolution)."""
    return TwoFixtureModel(
        scale=SCALE,
        rotation=(0.0, 0.0, 0.0),
        noise=NOISE,
        preload=0.05,
        gauge=GaugeSpec(0.0001, -0.5, 0.5, "in", noise=0.00003),
        seed=seed,
    )


def analyze_json(path: Path) -> dict:
    done = run_station("analyze", str(path), "--json")
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def assert_recovers(path: Path, seed: int) -> None:
    """The file's analysis gives the configured scale error per axis, the pendant of every
    placement, and each placement's error near the model's."""
    done = run_station("verify", str(path))
    assert done.returncode == 0, done.stdout + done.stderr
    accuracy = analyze_json(path)["accuracy"]
    truth = model(seed)
    assert [p["placement"] for p in accuracy["placements"]] == list(range(1, PLACEMENTS + 1))
    for placement in accuracy["placements"]:
        number = placement["placement"]
        expected = truth.placement_of(number).pendant
        assert placement["pendant"] == dict(zip("xyz", expected, strict=True))
        error = truth.systematic_error(number)
        for axis, value in zip("xyz", error, strict=True):
            # One capture per placement: the error within 5 sigma of the two rests' noise (home,
            # where the zero is the mean of several readings, and the return).
            assert placement["mean"][axis] == pytest.approx(value, abs=5 * NOISE * 2**0.5)
    for axis, scale in zip("xyz", SCALE, strict=True):
        assert accuracy["axes"][axis]["scale_error"] == pytest.approx(scale, abs=6e-6)


def test_the_runner_walks_relative_accuracy_against_the_two_fixture_simulator(
    tmp_path: Path, gauges_for
) -> None:
    seed = 11
    simulator = Simulator(get_protocol("mitutoyo"), model(seed), seed=seed)
    url = simulator.start_pty()
    try:
        procedure = discover_procedures(use_env=False).get("relative_accuracy")
        setup = SessionSetup(
            procedure=procedure,
            robot="KSC-7",
            operator="tester",
            ports=(PortSetup(url, "mitutoyo", DEVICE_MAP),),
            placements=PLACEMENTS,
        )
        runner = Runner.start(setup, gauges_for(setup), tmp_path)
        while (state := runner.state()).current is not None:
            step = state.current
            # The operator brings the robot home for the zero and back for the capture.
            returned = 1 if state.action.kind == "capture" else 0
            simulator.move_to_rest(simulator.model.rest_of(state.placement or 1, returned))
            if step.kind == "check":
                runner.confirm()
            elif step.kind == "zero":
                runner.zero()
            elif step.kind == "input":
                # The operator reads the pendant of this placement (the autopilot's way).
                pendant = simulator.model.placement_of(step.placement).pendant
                runner.submit_input({a: str(v) for a, v in zip("xyz", pendant, strict=True)})
            else:
                assert runner.capture(5.0).recorded
        # A zero at every placement changes the zero in force: the live analysis still holds
        # every capture (a zero once rebuilt it empty from the second placement on) and judges
        # them as the batch analysis of the file does.
        live = runner.analysis()
        assert live.channels["x"].descriptive.n == PLACEMENTS
        batch = to_json(analyze_session_file(runner.path).analysis)["channels"]
        for channel, shown in to_json(live)["channels"].items():
            for part in ("n", "mean", "sd", "range", "capability", "out_of_spec", "alarms"):
                assert shown[part] == batch[channel][part], (channel, part)
        runner.finish()
    finally:
        simulator.stop()
    session = load_session(runner.path)
    assert [c.placement for c in session.cycles.values()] == list(range(1, PLACEMENTS + 1))
    assert len(session.zeroes) == PLACEMENTS
    assert_recovers(runner.path, seed)


def write_inputs(path: Path, seed: int) -> Path:
    """What the operator copies from the pendant: one row per placement."""
    rows = ["placement,x,y,z"]
    for number in range(1, PLACEMENTS + 1):
        x, y, z = model(seed).placement_of(number).pendant
        rows.append(f"{number},{x},{y},{z}")
    path.write_text("\n".join(rows) + "\n")
    return path


def capture_args(url: str, folder: Path, inputs: Path) -> list[str]:
    return [
        *STATION,
        "capture",
        "--every",
        "0.15",
        "--procedure",
        "relative_accuracy",
        "--port",
        url,
        "--protocol",
        "mitutoyo",
        "--robot",
        "KSC-7",
        "--operator",
        "tester",
        "--placements",
        str(PLACEMENTS),
        "--inputs",
        str(inputs),
        "--sessions",
        str(folder),
    ]


def test_station_capture_against_station_simulate_two_fixture(tmp_path: Path) -> None:
    """The operator plays the robot (home for each zero, back for each return) while a headless
    ``station capture`` polls; the frames check and zeros of several readings at home never
    shift which fixture the capture reads."""
    seed = 4
    inputs = write_inputs(tmp_path / "pendant.csv", seed)
    simulator = Simulator(get_protocol("mitutoyo"), model(seed), seed=seed)
    url = simulator.start_pty()
    try:
        done, _ = play_capture(simulator, 1, capture_args(url, tmp_path / "sessions", inputs))
    finally:
        simulator.stop()
    assert done.returncode == 0, done.stderr
    assert sum(line.startswith("cycle ") for line in done.stdout.splitlines()) == PLACEMENTS
    assert "RELATIVE ACCURACY REPORT" in done.stdout
    zeroes = load_session(next((tmp_path / "sessions").glob("*.jsonl"))).zeroes
    assert all(entry["n"] > 1 for zero in zeroes for entry in zero["channels"].values())
    path = next((tmp_path / "sessions").glob("*.jsonl"))
    assert_recovers(path, seed)


@pytest.mark.parametrize(
    ("extra", "fault"),
    [
        (["--input", "x=1", "--input", "y=2"], "asks for z: pass --input 1:z=VALUE"),
        (["--input", "0:x=1"], "the placement before ':' must be 1, 2, 3"),
        (["--input", "2:q=1"], "asks for x, y, z"),
    ],
)
def test_missing_or_bad_pendant_values_are_refused_before_anything_is_written(
    tmp_path: Path, extra: list[str], fault: str
) -> None:
    args = [
        *STATION,
        "capture",
        "--procedure",
        "relative_accuracy",
        "--port",
        "/dev/null-no-such-port",
        "--protocol",
        "mitutoyo",
        "--robot",
        "R",
        "--sessions",
        str(tmp_path),
        *extra,
    ]
    done = subprocess.run(args, capture_output=True, text=True, timeout=30)
    assert done.returncode == 2
    assert fault in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.glob("*.jsonl"))
