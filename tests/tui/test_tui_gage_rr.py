"""The Gage R&R through the TUI at 80×24, by keyboard (Pilot), against the simulated gauge bench
on a real pty that follows the steps as the demo's does: the checklist names each appraiser's
block, the dashboard asks for each part in the order the station drew, the bench seats that
part as that appraiser reads it, and the summary's verdict is the study's own."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from station.instruments.gauge_bench import GageRRBenchModel
from station.instruments.protocols import get_protocol
from station.instruments.simulator import GaugeSpec, Simulator
from station.session.model import load_session
from station.tui.instruments import DemoFixture, track
from station.tui.widgets.step_list import steps_text
from tests.tui.test_tui_method_procedures import PROTOCOL, run_procedure, text_of, tui_app

PARTS = (0.2480, 0.2512, 0.2497, 0.2525, 0.2469, 0.2503, 0.2538, 0.2490, 0.2516, 0.2476)
OFFSETS = {"A": 0.0, "B": 0.0004, "C": -0.0003}


@pytest.fixture
def bench() -> Iterator[str]:
    """The Gage R&R bench on a pty, tracked: the session's steps seat its parts."""
    gauge = GaugeSpec(0.0001, -0.5, 1.0, "in", noise=0.00002)
    model = GageRRBenchModel(PARTS, OFFSETS, noise=0.00006, gauge=gauge)
    simulator = Simulator(get_protocol(PROTOCOL), model, seed=7, channel_map={"1": "x"})
    url = simulator.start_pty()
    fixture = track(DemoFixture(url, PROTOCOL, {"1": "x"}, simulator))
    try:
        yield url
    finally:
        fixture.stop()


async def test_gage_rr_through_the_tui(tmp_path: Path, bench: str, tui) -> None:
    app = tui_app(tmp_path)
    asked: list[tuple[str, int]] = []

    def typed(placement: int | None) -> dict[str, str]:
        return {"gauge": "MIT-0042", "tolerance": "0.02", "A": "Ann", "B": "Bo", "C": "Cy"}

    def seen(app, state) -> None:
        # The dashboard asks for the part the step presents next, by the appraiser's step.
        part, appraiser = state.action.part, state.current.step.id
        assert f"Appraiser {appraiser}, part {part} (" in text_of(app, "#dash-prompt")
        asked.append((appraiser, part))

    async with app.run_test(size=(80, 24)) as pilot:
        await run_procedure(pilot, tui, "gage_rr", bench, "1=x", "2", typed, seen)
        report = text_of(app, "#summary-report")
        assert "GAGE R&R (CROSSED):" in report and "ANOVA METHOD" in report
        assert "AVERAGE AND RANGE METHOD" in report
        assert "3 appraisers x 10 parts x 2 trials" in text_of(app, "#summary-title")
        verdict = text_of(app, "#summary-verdict")
        view = app.screen.view
        steps = str(steps_text(app.runner.state().steps))
    assert "Appraiser A measures the parts (1)" in steps
    assert "Hand the gauge to appraiser B (2)" in steps
    session = load_session(view.path)
    orders = [note["order"] for note in session.notes if note.get("order")]
    # Each appraiser's trial was asked in its own drawn order, and read so.
    assert [p for _, p in asked] == [part for order in orders for part in order]
    assert [(c.step, c.part) for _, c in sorted(session.cycles.items())] == asked
    done = subprocess.run(
        [sys.executable, "-m", "station", "analyze", str(view.path), "--json"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    study = json.loads(done.stdout)["gage_rr"]
    assert f"Verdict: {study['verdict']}" in verdict
    means = study["xbar_r"]["appraiser_means"]
    assert means["B"] - means["A"] == pytest.approx(0.0004, abs=0.0001)
    assert means["C"] - means["A"] == pytest.approx(-0.0003, abs=0.0001)
