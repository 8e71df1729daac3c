"""The Gage R&R end to end, headless: ``station capture --procedure gage_rr`` (a real process)
against the simulated gauge bench on a real pty, played as the appraisers would: each step's
parts in the order the station drew and printed, seated by the appraiser whose step it is, one
of whom reads high and one low. The session records the order and each reading's part; the
study recovers the injected offsets and the gauge's repeatability, and its wide export is the
table ``station analyze --procedure gage_rr`` reads back to the same figures."""

from __future__ import annotations

import json
import os
import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from helpers import STATION, run_station
from scipy import stats

from station.instruments.gauge_bench import GageRRBenchModel
from station.instruments.protocols import get_protocol
from station.instruments.simulator import GaugeSpec, Simulator
from station.session.gauge_register import load_register
from station.session.model import load_session

PACE = "0.15"
"""Seconds ``station capture`` waits after each cycle: the player seats the next part."""
PARTS = (0.2480, 0.2512, 0.2497, 0.2525, 0.2469, 0.2503, 0.2538, 0.2490, 0.2516, 0.2476)
OFFSETS = {"A": 0.0, "B": 0.0004, "C": -0.0003}
NOISE = 0.00006
TRIALS = 2

ORDER = re.compile(r"^note: Parts in this order for step (\w+), (\d+) of (\d+): ([\d, ]+)\.$")
CYCLE = re.compile(r"^cycle (\d+) part (\d+) x=")


@dataclass
class Appraisers:
    """Seat each part the station asks for, as the appraiser whose step it is."""

    simulator: Simulator
    model: GageRRBenchModel
    appraiser: str = ""
    queue: list[int] = field(default_factory=list)
    seating: int = 0
    orders: list[tuple[str, int, list[int]]] = field(default_factory=list)
    read: list[tuple[str, int]] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)

    def seat_next(self) -> None:
        self.seating += 1
        if self.queue:
            rest = self.model.rest_of_part(self.queue[0], self.appraiser, self.seating)
        else:
            rest = 0  # the gauge back on the plate between two appraisers
        self.simulator.move_to_rest(rest)

    def heard(self, line: str) -> None:
        self.lines.append(line)
        if found := ORDER.match(line):
            self.appraiser = found.group(1)
            self.queue = [int(part) for part in found.group(4).split(", ")]
            self.orders.append((self.appraiser, int(found.group(2)), list(self.queue)))
            self.seat_next()
        elif found := CYCLE.match(line):
            part = int(found.group(2))
            assert part == self.queue.pop(0), "the station asked for the part seated"
            self.read.append((self.appraiser, part))
            self.seat_next()


def play(simulator: Simulator, model: GageRRBenchModel, arguments: list[str]) -> tuple:
    appraisers = Appraisers(simulator, model)
    process = subprocess.Popen(arguments, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, bufsize=1)  # fmt: skip
    try:
        for line in process.stdout:
            appraisers.heard(line.rstrip("\n"))
        _, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    return process.returncode, err, appraisers


def test_a_gage_rr_study_headless_recovers_the_appraisers_and_the_gauge(tmp_path: Path):
    gauge = GaugeSpec(0.0001, -0.5, 1.0, "in", noise=0.00002)
    model = GageRRBenchModel(PARTS, OFFSETS, noise=NOISE, gauge=gauge)
    simulator = Simulator(get_protocol("idh"), model, seed=25, channel_map={"1": "x"})
    url = simulator.start_pty()
    folder = tmp_path / "sessions"
    try:
        code, err, appraisers = play(
            simulator,
            model,
            [
                *STATION, "capture", "--trigger", "poll", "--every", PACE,
                "--procedure", "gage_rr", "--port", url, "--protocol", "idh",
                "--robot", "bench", "--sessions", str(folder), "--placements", str(TRIALS),
                "--input", "gauge=MIT-0042", "--input", "tolerance=0.02",
                "--input", "A=Ann", "--input", "B=Bo", "--input", "C=Cy",
            ],
        )  # fmt: skip
    finally:
        simulator.stop()
    assert code == 0, err
    # Each appraiser, each trial: every part once, in an order of its own, said before the
    # first reading (AIAG's trial order: A, B, C, then A, B, C again).
    assert [(a, t) for a, t, _ in appraisers.orders] == [
        (a, t) for t in range(1, TRIALS + 1) for a in OFFSETS
    ]
    assert all(sorted(order) == list(range(1, 11)) for _, _, order in appraisers.orders)
    assert len({tuple(order) for _, _, order in appraisers.orders}) == len(appraisers.orders)
    assert len(appraisers.read) == len(OFFSETS) * len(PARTS) * TRIALS
    text = "\n".join(appraisers.lines)
    assert "GAGE R&R (CROSSED):" in text
    # The session keeps the order (a note by the station) and each reading's part and step.
    path = next(folder.glob("*.jsonl"))
    session = load_session(path)
    notes = [note for note in session.notes if note.get("order")]
    assert [(n["step"], n["placement"], n["order"]) for n in notes] == appraisers.orders
    assert all(note["by"] == "station" for note in notes)
    assert {(c.step, c.part) for c in session.cycles.values()} == set(appraisers.read)
    done = run_station("analyze", path, "--json")
    assert done.returncode == 0, done.stderr
    study = json.loads(done.stdout)["gage_rr"]
    assert study["appraisers"] == ["A", "B", "C"] and study["trials"] == TRIALS
    assert study["appraiser_names"] == {"A": "Ann", "B": "Bo", "C": "Cy"}
    # The appraisers' averages differ by their offsets (the parts cancel in a crossed study):
    # each mean carries the gauge's noise over 20 readings and the display's rounding.
    means = study["xbar_r"]["appraiser_means"]
    spread = (NOISE**2 + 0.0001**2 / 12 + 0.00002**2) ** 0.5
    assert means["B"] - means["A"] == pytest.approx(0.0004, abs=4 * spread * (2 / 20) ** 0.5)
    assert means["C"] - means["A"] == pytest.approx(-0.0003, abs=4 * spread * (2 / 20) ** 0.5)
    # Repeatability: the seating noise, the indicator's own and the rounding, within the χ²
    # interval of its degrees of freedom (the interaction pooled: 10·3·(2 − 1) + 18).
    anova = study["anova"]
    df = 48 if anova["pooled"] else 30
    low, high = stats.chi2.ppf([0.0005, 0.9995], df) / df
    assert low * spread**2 <= anova["var_repeatability"] <= high * spread**2
    assert study["tolerance"] == 0.02 and anova["pct_tolerance"] is not None
    # The wide export is the table the study reads back, with the same figures.
    table = tmp_path / "grr.csv"
    exported = run_station("export", path, "--csv", "-o", table)
    assert exported.returncode == 0, exported.stderr
    assert table.read_text().splitlines()[1].startswith("cycle,part,appraiser,trial,value")
    again = run_station("analyze", table, "--procedure", "gage_rr", "--tolerance", "0.02", "--json")
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["gage_rr"]["anova"] == pytest.approx(anova)
    # Finished, the study filed itself in the gauge register beside the gauge's checks.
    word = study["verdict"]
    assert f"Gage R&R of MIT-0042: {word} on " in text
    register = load_register(Path(os.environ["STATION_GAUGES"]))
    (entry,) = register["gauges"]["MIT-0042"]["studies"]["gage_rr"]
    assert entry["result"] == word.lower() and entry["ndc"] == anova["ndc"]
    assert entry["pct_grr"] == pytest.approx(anova["pct_grr"])
    assert entry["appraisers"] == ["A", "B", "C"] and entry["trials"] == TRIALS
    assert entry["port"] == {"url": simulator.url, "device": "1"}
    listed = run_station("gauges", "list")
    assert f"  gage_rr: {word.lower()} on " in listed.stdout
    # Its report draws the four charts of the study.
    html = tmp_path / "grr.html"
    reported = run_station("report", path, "--format", "html", "-o", html)
    assert reported.returncode == 0, reported.stderr
    page = html.read_text()
    for caption in ("Readings by part", "Readings by appraiser", "Part x appraiser interaction",
                    "Range chart by appraiser"):  # fmt: skip
        assert caption in page
