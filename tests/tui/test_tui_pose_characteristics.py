"""The ISO 9283 pose test through the TUI at 80×24, by keyboard, against the simulated test
cube on a real pty (the robot following the steps, as in the demo): the conditions and each
pose's pendant typed, the captures, and the summary with the pose characteristics."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import pytest

from station.instruments.protocols import get_protocol
from station.instruments.simulator import GaugeSpec, Simulator
from station.instruments.simulator.cube import POSE_BIAS, POSE_NOISE, CubePosesModel
from station.tui.instruments import DemoFixture, track
from tests.tui.test_tui_method_procedures import (
    PROTOCOL,
    analyze_json,
    run_procedure,
    text_of,
    tui_app,
)

CYCLES = 30


@pytest.fixture
def cube() -> Iterator[tuple[str, CubePosesModel]]:
    """The simulated test cube on a pty, followed by the session's steps; its URL and model."""
    model = CubePosesModel(captures=CYCLES, gauge=GaugeSpec(0.0001, -0.5, 0.5, "in"), seed=4)
    simulator = Simulator(get_protocol(PROTOCOL), model, seed=4)
    url = simulator.start_pty()
    fixture = track(DemoFixture(url, PROTOCOL, dict(simulator.channel_map), simulator))
    try:
        yield url, model
    finally:
        fixture.stop()


async def test_the_pose_test_through_the_tui(tmp_path: Path, cube, tui) -> None:
    """Two poses of the cube (the set-up counts poses), 30 cycles each: the summary holds the
    pose characteristics, the conditions and their departures, and the session's figures
    recover each pose's bias."""
    url, model = cube
    app = tui_app(tmp_path)

    def typed(placement: int | None) -> dict[str, str]:
        if placement is None:
            return {
                "load": "100",
                "speed": "100",
                "warm_up": "20",
                "temperature_start": "20.5",
                "temperature_end": "21",
            }
        return dict(zip("xyz", map(str, model.placement_of(placement).pendant), strict=True))

    async with app.run_test(size=(80, 24)) as pilot:
        await run_procedure(pilot, tui, "pose_characteristics", url, "1=x,2=y,3=z", "2", typed)
        report = " ".join(text_of(app, "#summary-report").split())
        assert "ISO 9283 POSE CHARACTERISTICS (2 poses)" in report
        assert "2 poses" in text_of(app, "#summary-title")
        assert "P3, P4, P5 not measured: the standard measures P1 to P5." in report
        view = app.screen.view
    poses = analyze_json(view.path)["iso9283"]["poses"]
    for number, pose in enumerate(poses.values(), start=1):
        allowed = 3 * POSE_NOISE[number - 1] / math.sqrt(CYCLES) + 0.0001
        assert pose["n"] == CYCLES and pose["ap_relative"] is False
        assert pose["ap_axes"] == pytest.approx(list(POSE_BIAS[number - 1]), abs=allowed)
        # A new return for every capture (the robot followed the steps): RP about 3.6 sigma.
        assert 2.5 * POSE_NOISE[number - 1] < pose["rp"] < 5 * POSE_NOISE[number - 1]
