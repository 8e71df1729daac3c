"""The gauge check, per-joint troubleshooting and gain schedule end to end: ``station capture``
against ``station simulate`` (real processes on a real pty), then the session file analysed
(``station analyze FILE --json``) and the gauge check filed in the gauge register."""

from __future__ import annotations

import datetime as dt
import json
import os
import subprocess
from pathlib import Path

import pytest
from helpers import STATION, run_station, start_simulator, stop_simulator

from station.instruments.gauge_bench import GaugeBenchModel
from station.instruments.joint_model import faulty_arm
from station.instruments.protocols import get_protocol
from station.instruments.simulator import GaugeSpec, Simulator
from station.methods import analyze_session_file
from station.session.gauge_register import coverage, coverage_lines, load_register
from station.session.model import load_session

from .playing import play_capture


def simulate(*args: str, protocol: str = "idh") -> tuple[subprocess.Popen, str]:
    return start_simulator("--protocol", protocol, *args)


def capture(
    url: str, folder: Path, procedure: str, *extra: str, protocol: str = "idh"
) -> tuple[Path, str]:
    """The session file and the summary ``station capture`` printed."""
    done = subprocess.run(
        [
            *STATION,
            "capture",
            # A still simulated gauge: polled, paced (the robot does not leave and return).
            "--trigger",
            "poll",
            "--every",
            "0.01",
            "--procedure",
            procedure,
            "--port",
            url,
            "--protocol",
            protocol,
            "--robot",
            "KSC-7",
            "--sessions",
            str(folder),
            *extra,
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    return next(folder.glob("*.jsonl")), done.stdout


PACE = "0.15"
RETURNS = 25
"""Returns per joint (the procedure's target)."""
"""Seconds ``station capture`` waits after each cycle and zero: the player moves the robot."""


def played(
    simulator: Simulator, returns: int, folder: Path, procedure: str, *extra: str, **options
) -> tuple[subprocess.CompletedProcess[str], Path | None]:
    """``station capture`` polling ``simulator`` (started here on a pty), the robot played
    between its cycles (:mod:`tests.runner.playing`); the process and the session file."""
    url = simulator.start_pty()
    try:
        done, _ = play_capture(
            simulator,
            returns,
            [
                *STATION,
                "capture",
                *("--trigger", "poll", "--every", PACE, "--procedure", procedure),
                *("--port", url, "--protocol", simulator.protocol.name, "--robot", "KSC-7"),
                *("--sessions", str(folder)),
                *extra,
            ],
            **options,
        )
    finally:
        simulator.stop()
    return done, next(folder.glob("*.jsonl"), None)


def bench(protocol: str = "idh", bias: float = 0.0) -> Simulator:
    """The gauge bench: a 0.1 in block on a surface plate, the indicator's noise 5e-5 in."""
    gauge = GaugeSpec(0.0001, -0.5, 1.0, "in", noise=0.00002)
    model = GaugeBenchModel(0.1, bias=bias, noise=0.00005, gauge=gauge)
    return Simulator(get_protocol(protocol), model, seed=0, channel_map={"1": "x"})


def gauges(*args: str) -> subprocess.CompletedProcess[str]:
    return run_station("gauges", *args)


def analyze_json(path: Path) -> dict:
    result = run_station("analyze", str(path), "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


# idh zeroes the indicator itself; mitutoyo has no zero command, so the station zeroes in
# software by reading the plate once.
@pytest.mark.parametrize(
    ("bias", "capable", "protocol"), [(0.0, True, "idh"), (0.0003, False, "mitutoyo")]
)
def test_gauge_check_session_is_analysed_and_filed(
    tmp_path: Path, bias: float, capable: bool, protocol: str
):
    simulator = bench(protocol, bias)
    done, path = played(
        simulator,
        25,
        tmp_path / "sessions",
        "gauge_check",
        *("--cycles", "25", "--input", "gauge=MIT-0042", "--input", "reference=0.1"),
        *("--input", "tolerance=0.004", "--input", "calibration_due=2099-01-01"),
    )
    assert done.returncode == 0, done.stderr
    summary, url = done.stdout, simulator.url
    study = analyze_json(path)["gauge_check"]
    assert study["n"] == 25 and study["capable"] is capable
    # The zero is the mean of several readings on the plate (a device zero: the gauge's own
    # zero on its last reading there), so the bias is known to about one 0.0001 in step.
    assert study["bias"] == pytest.approx(bias, abs=0.00015)
    zero = load_session(path).zeroes[0]["channels"]["x"]
    assert zero["n"] > 1 and zero["spread"] <= 0.0003
    # The capture summary is the kind's report, and the finished check filed itself in the
    # gauge register (the test's own: STATION_GAUGES), with the line it was read on.
    assert f"GAUGE CHECK (TYPE-1 STUDY): {'CAPABLE' if capable else 'NOT CAPABLE'}" in summary
    assert "filed in the gauge register" in summary
    result = "passed" if capable else "failed"
    assert f"gauge register: MIT-0042, {result} on" in summary
    session = load_session(path)
    register = Path(os.environ["STATION_GAUGES"])
    entry = load_register(register)["gauges"]["MIT-0042"]["checks"][-1]
    assert entry["session"] == session.session_id and entry["port"]["url"] == url
    status = coverage({"x": "MIT-0042"}, dt.date.fromisoformat(session.created[:10]), path=register)
    assert status["x"].state == ("passed" if capable else "failed")
    line = coverage_lines(status)[0]
    assert ("gauge check passed on" in line) is capable
    assert analyze_session_file(path).count == "25 readings"


def test_gauges_record_files_a_finished_gauge_check_once(tmp_path: Path):
    """``station gauges record`` files the study in the register it is given, and filing the
    same session again replaces its entry (the finish already filed it in the default one)."""
    done, path = played(
        bench(),
        25,
        tmp_path / "sessions",
        "gauge_check",
        *("--cycles", "25", "--input", "gauge=MIT-0042", "--input", "reference=0.1"),
        *("--input", "tolerance=0.004"),
    )
    assert done.returncode == 0, done.stderr
    other = tmp_path / "other-register.json"
    for _ in range(2):
        recorded = gauges("record", str(path), "--register", str(other))
        assert recorded.returncode == 0, recorded.stderr
        assert "Gauge check of MIT-0042: passed on" in recorded.stdout
        assert f"filed in the gauge register {other}" in recorded.stdout
    checks = load_register(other)["gauges"]["MIT-0042"]["checks"]
    assert len(checks) == 1 and checks[0]["session"] == load_session(path).session_id
    again = gauges("record", str(path))
    assert again.returncode == 0, again.stderr
    default = load_register(Path(os.environ["STATION_GAUGES"]))["gauges"]["MIT-0042"]["checks"]
    assert len(default) == 1
    listed = gauges("list", "--register", str(other))
    assert listed.returncode == 0 and "gauge MIT-0042: gauge check passed on" in listed.stdout
    status = gauges("status", "MIT-0042", "--register", str(other), "--json")
    assert status.returncode == 0, status.stderr
    assert json.loads(status.stdout)["gauges"][0]["state"] == "passed"
    unknown = gauges("status", "MIT-0042", "DIAL-9", "--register", str(other))
    assert unknown.returncode == 1 and "DIAL-9: no gauge check on record" in unknown.stdout


def test_gauges_record_refuses_what_is_no_gauge_study(tmp_path: Path):
    fixture, url = simulate("--unit", "in", "--resolution", "0.0001")
    try:
        path, _ = capture(url, tmp_path / "sessions", "repeatability", "--cycles", "2")
    finally:
        stop_simulator(fixture)
    refused = gauges("record", str(path))
    assert refused.returncode == 2
    assert "is a repeatability session, which files nothing in the gauge register" in refused.stderr


MASTERS = (0.1, 0.3, 0.5, 0.7, 0.9)
"""The linearity study's gauge blocks (in), across the bench indicator's 1 in of travel."""


def test_a_gauge_linearity_study_headless_recovers_the_bench_slope(tmp_path: Path):
    """Five gauge blocks, twelve seatings each, on a bench whose indicator reads a block of
    size r as r + 0.0001 + 0.001·r: the study recovers the slope and bias within their
    intervals, calls the gauge not acceptable against a 0.004 in tolerance, and files itself
    in the gauge register beside the gauge's checks (``station gauges list`` shows it)."""
    gauge = GaugeSpec(0.0001, -0.5, 1.0, "in", noise=0.00002)
    model = GaugeBenchModel(MASTERS, bias=0.0001, slope=0.001, noise=0.00004, gauge=gauge)
    simulator = Simulator(get_protocol("idh"), model, seed=2, channel_map={"1": "x"})
    sizes = [f"{n}:reference={size}" for n, size in enumerate(MASTERS, start=1)]
    done, path = played(
        simulator,
        len(MASTERS) * 12,
        tmp_path / "sessions",
        "gauge_linearity",
        *("--input", "gauge=MIT-0042", "--input", "tolerance=0.004"),
        *(arg for size in sizes for arg in ("--input", size)),
    )
    assert done.returncode == 0, done.stderr
    assert "GAUGE LINEARITY AND BIAS STUDY: NOT ACCEPTABLE" in done.stdout
    assert "Gauge linearity study of MIT-0042: NOT ACCEPTABLE" in done.stdout
    study = analyze_json(path)["gauge_linearity"]
    assert [b["reference"] for b in study["biases"]] == list(MASTERS)
    assert all(b["n"] == 12 for b in study["biases"])
    t = 2.002  # Student's t, 95 %, 58 degrees of freedom
    assert abs(study["slope"] - 0.001) <= t * study["slope_se"]
    # The zero is the plate's, read by the gauge at its step: the intercept is the bias.
    assert abs(study["intercept"] - 0.0001) <= t * study["intercept_se"] + 0.0001
    assert study["acceptable"] is False
    assert analyze_session_file(path).count == "5 masters"
    register = Path(os.environ["STATION_GAUGES"])
    entry = load_register(register)["gauges"]["MIT-0042"]["studies"]["gauge_linearity"][-1]
    assert entry["result"] == "not acceptable" and entry["references"] == list(MASTERS)
    assert entry["port"]["url"] == simulator.url
    listed = gauges("list", "--json")
    (gauge,) = json.loads(listed.stdout)["gauges"]
    assert gauge["studies"]["gauge_linearity"]["session"] == load_session(path).session_id
    text = gauges("list").stdout
    assert "  gauge_linearity: not acceptable on" in text
    other = tmp_path / "other-register.json"
    recorded = gauges("record", str(path), "--register", str(other))
    assert recorded.returncode == 0, recorded.stderr
    assert "Gauge linearity study of MIT-0042: NOT ACCEPTABLE" in recorded.stdout
    assert load_register(other)["gauges"]["MIT-0042"]["studies"]["gauge_linearity"]
    # Its wide export is the table the study reads back, and gives the same figures.
    table = tmp_path / "study.csv"
    exported = run_station("export", str(path), "--csv", "-o", str(table))
    assert exported.returncode == 0, exported.stderr
    again = run_station(
        "analyze",
        str(table),
        "--procedure",
        "gauge_linearity",
        "--tolerance",
        "0.004",
        "--resolution",
        "0.0001",
        "--unit",
        "in",
        "--json",
    )
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["gauge_linearity"]["slope"] == pytest.approx(study["slope"])


@pytest.mark.parametrize("protocol", ["idh", "mitutoyo"])
def test_joint_troubleshooting_session_names_the_faulty_joint(tmp_path: Path, protocol: str):
    gauge = GaugeSpec(0.0001, -0.5, 0.5, "in", noise=0.00003)
    arm = faulty_arm(2, "backlash", size=4e-5, cycles=RETURNS, home_readings=1, gauge=gauge)
    simulator = Simulator(get_protocol(protocol), arm, seed=5)
    done, path = played(
        simulator,
        RETURNS,
        tmp_path / "sessions",
        "joint_troubleshooting",
        *("--placements", "3", "--input", "1:lever=31.177"),
        *("--input", "2:lever=31.241", "--input", "3:lever=16"),
    )
    assert done.returncode == 0, done.stderr
    summary = done.stdout
    assert [z["placement"] for z in load_session(path).zeroes] == [1, 2, 3]
    document = analyze_json(path)
    assert document["procedure"] == "joint_troubleshooting"
    assert document["suspect"] == 2 and document["cause"] == "backlash"
    assert all(j["n"] == RETURNS and j["lever_arm"] for j in document["joints"])
    assert analyze_session_file(path).count == "3 joints"
    assert "SUSPECT: joint 2." in summary


def test_gain_schedule_session_from_typed_gains(tmp_path: Path):
    inputs = tmp_path / "gains.csv"
    rows = ["placement,q,kp,ki,kd"]
    for number in range(1, 10):
        q = -30 + 18.75 * (number - 1)
        kp = 2 - 0.03 * q + 4e-4 * q**2 - 1e-6 * q**3
        rows.append(f"{number},{q},{kp},{0.4 + 0.001 * q},{0.07}")
    inputs.write_text("\n".join(rows) + "\n")
    simulator, url = simulate("--channels", "q")
    try:
        path, summary = capture(
            url,
            tmp_path / "sessions",
            "gain_schedule",
            "--map",
            "1=q",
            "--placements",
            "9",
            "--inputs",
            str(inputs),
        )
    finally:
        stop_simulator(simulator)
    document = analyze_json(path)
    assert list(document["gains"]) == ["kp", "ki", "kd"]
    assert document["gains"]["kp"]["order"] == 3
    assert document["gains"]["kp"]["coefficients"] == pytest.approx(
        [2, -0.03, 4e-4, -1e-6], rel=1e-6
    )
    assert document["gains"]["kd"]["order"] == 0
    assert len(document["positions"]) == 9
    assert "GAIN SCHEDULE REPORT ON" in summary and "GAIN SCHEDULE: 9 positions" in summary
    # The filed report of a session without a capability analysis: the fit under VERDICTS.
    report = run_station("report", str(path))
    assert report.returncode == 0, report.stderr
    assert "GAIN SCHEDULE: 9 positions" in report.stdout.split("VERDICT:", 1)[1]


def test_a_repeatability_session_says_which_gauge_check_covers_it(tmp_path: Path):
    """The gauge check files MIT-0042 in the register; a repeatability session that names it on
    x records the check at its start, and its verdict (capture summary, analyze, the filed
    report) says so, while y and z, checked by nobody, warn."""
    done, _ = played(
        bench(),
        25,
        tmp_path / "checks",
        "gauge_check",
        *("--cycles", "25", "--input", "gauge=MIT-0042", "--input", "reference=0.1"),
        *("--input", "tolerance=0.004"),
    )
    assert done.returncode == 0, done.stderr
    fixture, url = simulate("--unit", "in", "--resolution", "0.0001")
    try:
        path, summary = capture(
            url, tmp_path / "sessions", "repeatability", "--cycles", "3", "--gauge", "x=MIT-0042"
        )
    finally:
        stop_simulator(fixture)
    today = load_session(path).created[:10]
    passed = f"x: gauge MIT-0042: gauge check passed on {today}"
    assert passed in summary
    assert "y: WARNING: no gauge check covers this channel" in summary
    header = load_session(path).header
    assert header["gauges"] == {"x": "MIT-0042"}
    assert header["gauge_checks"]["x"]["state"] == "passed"
    assert header["gauge_checks"]["z"]["state"] == "none"
    analysed = run_station("analyze", str(path))
    assert passed in analysed.stdout
    report = run_station("report", str(path))
    assert report.returncode == 0, report.stderr
    assert passed in report.stdout


def test_a_failed_gauge_check_warns_in_the_next_session(tmp_path: Path):
    """The register says the gauge on the line failed its check: a session on that line and
    device channel finds it without being told, and its verdict warns."""
    from station.analysis.gauge_check import gauge_check
    from station.session.gauge_register import record_check

    fixture, url = simulate("--unit", "in", "--resolution", "0.0001")
    register = Path(os.environ["STATION_GAUGES"])
    biased = gauge_check([0.1003, 0.1004, 0.1003, 0.1002] * 7, 0.1, 0.002, resolution=0.0001)
    record_check(register, "DIAL-7", biased, when=dt.date.today(), port={"url": url, "device": "2"})
    try:
        path, summary = capture(url, tmp_path / "sessions", "repeatability", "--cycles", "3")
    finally:
        stop_simulator(fixture)
    assert "y: WARNING: gauge DIAL-7: its last gauge check" in summary
    assert "failed" in summary
    assert load_session(path).header["gauges"] == {"y": "DIAL-7"}


@pytest.mark.parametrize("given", ["q=MIT-0042", "x=", "MIT-0042"])
def test_a_gauge_named_on_no_channel_is_refused_before_anything_is_written(
    tmp_path: Path, given: str
):
    done = subprocess.run(
        [
            *STATION,
            "capture",
            *("--procedure", "repeatability", "--port", "loop://", "--protocol", "mitutoyo"),
            *("--robot", "R1", "--sessions", str(tmp_path), "--gauge", given),
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2
    assert "is not CH=ID with CH one of x, y, z" in done.stderr
    assert not list(tmp_path.glob("*.jsonl"))


def test_a_register_that_cannot_be_written_is_a_warning_not_a_lost_check(tmp_path: Path):
    """The register is a symbolic link (never followed): the finished check warns on stderr,
    exits 0, and its session file and report are whole."""
    target = tmp_path / "elsewhere.json"
    target.write_text("{}")
    link = tmp_path / "gauges.json"
    link.symlink_to(target)
    done, _ = played(
        bench(),
        25,
        tmp_path / "s",
        "gauge_check",
        *("--cycles", "25", "--input", "gauge=G-1", "--input", "reference=0.1"),
        *("--input", "tolerance=0.004"),
        env={**os.environ, "STATION_GAUGES": str(link)},
    )
    assert done.returncode == 0, done.stderr
    assert "station: warning: the gauge register" in done.stderr
    assert "symbolic link" in done.stderr
    assert target.read_text() == "{}"
    assert "GAUGE CHECK (TYPE-1 STUDY)" in done.stdout
    path = next((tmp_path / "s").glob("*.jsonl"))
    assert load_session(path).finished
