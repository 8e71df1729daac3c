"""An ISO 230-2 positioning test end to end: ``station capture --procedure positioning`` polling
a simulated axis with a known positioning error and backlash (real processes on a real pty),
the stops played as the robot's program runs the standard test cycle; the session analysed
(``station analyze FILE --json``) recovers the injected reversal and error within their
sampling error, and its wide export is the table the analysis reads back."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from helpers import STATION, run_station

from station.instruments.axis_model import AxisPositioningModel
from station.instruments.protocols import get_protocol
from station.instruments.simulator import Simulator
from station.methods import analyze_session_file

from .playing import play_capture

TARGETS = (10.3, 97.6, 203.1, 301.9, 398.4)
"""Five targets over a 400 mm travel, spaced unevenly as ISO 230-2 asks (mm)."""
SLOPE = 5e-5
"""The axis's positioning error: 50 µm per metre of travel (it stops long)."""
BACKLASH = 0.020
"""Its lost motion at a reversal (mm): each target's reversal B_i is -0.020."""
NOISE = 0.002
"""Its repeatability, σ per stop (mm)."""
RUNS = 5


def analyze_json(path: Path, *args: str) -> dict:
    done = run_station("analyze", str(path), "--json", *args)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """A whole test: 5 runs of 10 stops, captured headless; the file and what capture said."""
    folder = tmp_path_factory.mktemp("positioning") / "sessions"
    model = AxisPositioningModel(TARGETS, slope=SLOPE, backlash=BACKLASH, noise=NOISE)
    simulator = Simulator(get_protocol("idh"), model, seed=3, channel_map={"1": "s"})
    url = simulator.start_pty()
    typed = [f"target_{i}={t}" for i, t in enumerate(TARGETS, start=1)]
    try:
        done, player = play_capture(
            simulator,
            RUNS * model.stops_per_run,
            [
                *STATION, "capture", "--procedure", "positioning",
                "--trigger", "poll", "--every", "0.05",
                "--port", url, "--protocol", "idh", "--robot", "KSC-7",
                "--sessions", str(folder),
                *(arg for value in typed for arg in ("--input", value)),
            ],
        )  # fmt: skip
    finally:
        simulator.stop()
    assert done.returncode == 0, done.stderr
    assert player.cycles == RUNS * model.stops_per_run
    return next(folder.glob("*.jsonl")), done.stdout


def test_the_summary_is_the_iso_230_2_report(session: tuple[Path, str]):
    path, summary = session
    assert "AXIS POSITIONING (ISO 230-2): 5 targets, 50 approaches" in summary
    assert "R = " in summary and "systematic error" in summary
    assert analyze_session_file(path).count == "5 targets, 50 approaches"


def test_the_injected_reversal_and_error_are_recovered(session: tuple[Path, str]):
    path, _ = session
    figures = analyze_json(path)["iso230_2"]
    targets = figures["targets"]
    assert [t["target"] for t in targets] == list(TARGETS)
    assert all(t["n_up"] == t["n_down"] == RUNS for t in targets)
    # Each mean of 5 stops lies within 3 standard errors (and the scale's step) of the axis's.
    mean_error = 3 * NOISE / math.sqrt(RUNS) + 0.001
    for t in targets:
        assert abs(t["mean_up"] - (SLOPE * t["target"] - BACKLASH / 2)) <= mean_error
        assert abs(t["mean_down"] - (SLOPE * t["target"] + BACKLASH / 2)) <= mean_error
    # The mean reversal of 5 targets, each the difference of two means of 5.
    reversal_error = 3 * NOISE * math.sqrt(2 / RUNS / len(TARGETS)) + 0.001
    assert abs(figures["B_mean"] + BACKLASH) <= reversal_error
    assert abs(figures["B"] - BACKLASH) <= 3 * NOISE * math.sqrt(2 / RUNS) + 0.001
    # The error grows by SLOPE along the travel: E↑, E↓ and M are its span; E adds the
    # backlash (the largest mean is the last target's down, the smallest the first's up).
    span = SLOPE * (TARGETS[-1] - TARGETS[0])
    for name in ("E_up", "E_down", "M"):
        assert abs(figures[name] - span) <= 2 * mean_error, name
    assert abs(figures["E"] - (span + BACKLASH)) <= 2 * mean_error
    # Repeatability: R_i ≈ 2s↑ + 2s↓ + |B_i| ≈ 4σ + backlash; loosely, s of 5 stops varies.
    assert BACKLASH < figures["R"] < BACKLASH + 12 * NOISE
    assert figures["R"] > max(figures["R_up"], figures["R_down"])


def test_the_wide_export_is_the_table_the_analysis_reads(session: tuple[Path, str], tmp_path):
    path, _ = session
    table = tmp_path / "axis.csv"
    exported = run_station("export", str(path), "--csv", "-o", str(table))  # fmt: skip
    assert exported.returncode == 0, exported.stderr
    lines = [line for line in table.read_text().splitlines() if not line.startswith("#")]
    assert lines[0] == "target,direction,cycle,actual"
    assert lines[1].startswith("10.3,up,1,") and lines[10].startswith("10.3,down,1,")
    assert len(lines) == 1 + RUNS * 2 * len(TARGETS)
    again = analyze_json(table, "--procedure", "positioning")["iso230_2"]
    figures = analyze_json(path)["iso230_2"]
    for name in ("B", "B_mean", "R", "E", "M", "A"):
        assert again[name] == pytest.approx(figures[name]), name


def test_the_html_report_draws_the_deviations_up_and_down(session: tuple[Path, str], tmp_path):
    path, _ = session
    page = tmp_path / "report.html"
    done = run_station("report", str(path), "--format", "html", "-o", str(page))  # fmt: skip
    assert done.returncode == 0, done.stderr
    html = page.read_text()
    assert "Deviation against the target, approached up and down" in html
    assert "mean up ± 2s" in html and "mean down ± 2s" in html
    assert "AXIS POSITIONING (ISO 230-2): 5 targets, 50 approaches" in html
