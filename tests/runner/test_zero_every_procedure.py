"""Every zero of every built-in procedure is a mean of several readings, under every trigger.

One reading is no zero: its noise shifts every later reading. The engine walks each built-in
procedure that zeroes against its simulated set-up on a real pty (the robot at rest where the
procedure says: still, its indicators scattering by their own noise about one rest position),
polled; the repeatability procedure also with DATA presses (push) and with a robot that leaves
and returns by itself (arrival). Each session's zero events must carry n > 1 per channel, and
the readings of one zero must be of one rest (spread within the step's ``still``)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from station.instruments.gauge_bench import GaugeBenchModel
from station.instruments.joint_model import JointModel
from station.instruments.motion import CycleMotion
from station.instruments.protocols import get_protocol
from station.instruments.simulator import (
    AxisModel,
    BarModel,
    GaugeSpec,
    Simulator,
    TwoFixtureModel,
    fixture_model,
)
from station.instruments.zeroing import GaugesMoving
from station.procedures import discover_procedures
from station.run import PortSetup, Runner, SessionSetup
from station.session.model import load_session

INDICATOR = GaugeSpec(0.0001, -0.5, 1.0, "in", noise=0.00003)
"""The report's 0.0001 in indicators, their own noise 0.3 of a resolution."""
ANSWERS = {"gauge": "MIT-0042", "reference": "0.1", "tolerance": "0.004", "lever": "20"}


def model_for(procedure: str):
    """The simulated set-up of ``procedure`` (the fixture for repeatability)."""
    if procedure == "relative_accuracy":
        return TwoFixtureModel(preload=0.05, gauge=INDICATOR, seed=3)
    if procedure == "linearity":
        return BarModel(points=50, dwell=5, indicator=INDICATOR)
    if procedure == "gauge_check":
        return GaugeBenchModel(0.1, noise=0.00005, gauge=INDICATOR)
    if procedure == "joint_troubleshooting":
        return JointModel(cycles=25, home_readings=1, gauge=INDICATOR)
    return fixture_model("xyz", axis=AxisModel(noise=0.0003), gauge=INDICATOR)


def place_robot(simulator: Simulator, state) -> None:
    """Where the operator has brought the still robot: home or the taught position for a
    zero, a new return for each capture (the demo does the same from the engine's notices)."""
    model = simulator.model
    capturing = state.action.kind == "capture"
    if isinstance(model, TwoFixtureModel):
        rest = model.rest_of(state.placement or 1, 1 if capturing else 0)
    elif isinstance(model, JointModel):
        block = ((state.placement or 1) - 1) * model.readings_per_joint
        rest = block + (state.progress.done + 1 if capturing and state.progress else 0)
    else:
        rest = state.next_cycle if capturing else 0
    simulator.move_to_rest(rest)


@pytest.fixture
def serve() -> Iterator[Callable[..., Simulator]]:
    started: list[Simulator] = []

    def start(model, protocol: str = "mitutoyo", **options) -> Simulator:
        simulator = Simulator(get_protocol(protocol), model, seed=5, **options)
        simulator.start_pty()
        started.append(simulator)
        return simulator

    yield start
    for simulator in started:
        simulator.stop()


def walk_zeros(simulator: Simulator, setup: SessionSetup, gauges, folder: Path, moves: bool):
    """Walk the session through its zero steps (capturing what comes between them) and return
    its zero events; stops at the first stream or once only the cycles are left."""
    runner = Runner.start(setup, gauges, folder)
    try:
        while (state := runner.state()).current is not None:
            if not moves:
                place_robot(simulator, state)
            kind = state.action.kind
            if kind == "confirm":
                runner.confirm()
            elif kind == "input":
                runner.submit_input(
                    {f.name: ANSWERS.get(f.name, "12.5") for f in state.action.fields if f.required}
                )
            elif kind == "zero":
                if setup.trigger == "push":
                    assert "Press DATA 3 times, the robot still" in state.action.prompt
                try:
                    runner.zero(timeout=10.0)
                except GaugesMoving:
                    assert moves, "a robot at rest was refused as moving"
            elif kind == "capture" and state.progress and state.progress.complete:
                runner.confirm()
            elif kind == "capture" and (state.placement or state.current.kind == "capture"):
                # A capture between two zeros (a placement's return, a joint's returns).
                assert runner.capture(5.0).recorded
            else:
                break  # the cycles or the strokes: every zero is behind
    finally:
        runner.close()
    return load_session(runner.path).zeroes


def assert_zeros_of_several_readings(zeroes, channels, expected_count: int) -> None:
    assert len(zeroes) == expected_count
    for zero in zeroes:
        for channel in channels:
            entry = zero["channels"][channel]
            assert entry["n"] > 1, (channel, entry)
            assert len(entry["values"]) == entry["n"]


def setup_of(procedure: str, simulator: Simulator, trigger: str = "poll") -> SessionSetup:
    """A session of the built-in ``procedure`` on ``simulator``'s line, short counts."""
    return SessionSetup(
        procedure=discover_procedures(use_env=False).get(procedure),
        robot="KSC-7",
        operator="tester",
        ports=(PortSetup(simulator.url, simulator.protocol.name, dict(simulator.channel_map)),),
        trigger=trigger,
        placements=2,
        cycles=2,
    )


@pytest.mark.parametrize(
    ("procedure", "zeros"),
    [
        ("repeatability", 1),
        ("relative_accuracy", 2),
        ("linearity", 2),
        ("gauge_check", 1),
        ("joint_troubleshooting", 2),
    ],
)
def test_every_zero_of_a_polled_session_is_a_mean_of_several_readings(
    tmp_path: Path, serve, gauges_for, procedure: str, zeros: int
) -> None:
    simulator = serve(model_for(procedure))
    setup = setup_of(procedure, simulator)
    zeroes = walk_zeros(simulator, setup, gauges_for(setup), tmp_path, moves=False)
    assert_zeros_of_several_readings(zeroes, setup.procedure.channels, zeros)


def test_a_zero_by_data_presses_is_the_mean_of_three(tmp_path: Path, serve, gauges_for) -> None:
    # A push gauge the operator presses DATA on: the simulator presses 20 times a second.
    simulator = serve(model_for("repeatability"), "uwave", push_rate=20.0)
    setup = setup_of("repeatability", simulator, "push")
    zeroes = walk_zeros(simulator, setup, gauges_for(setup), tmp_path, moves=False)
    assert_zeros_of_several_readings(zeroes, "xyz", 1)
    assert all(entry["n"] >= 3 for entry in zeroes[0]["channels"].values())


def test_a_zero_under_arrival_waits_for_the_moving_robot_at_rest(
    tmp_path: Path, serve, gauges_for
) -> None:
    motion = CycleMotion(1.5, -0.375, 0.002)
    simulator = serve(model_for("repeatability"), motion=motion)
    setup = setup_of("repeatability", simulator, "arrival")
    zeroes = walk_zeros(simulator, setup, gauges_for(setup), tmp_path, moves=True)
    assert_zeros_of_several_readings(zeroes, "xyz", 1)
