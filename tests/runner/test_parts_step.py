"""The ``parts`` step kind on the real engine (a simulated gauge on a pty): every part once, in
an order drawn afresh for each appraiser and trial and on disk before its first reading; each
reading records its part; a rejected reading's part comes back; the step goes on only once
every part is read; a resumed session presents the rest of the same order."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from station.errors import StationError
from station.run import Runner
from station.run.steps.parts import PartsStep
from station.session.model import load_session
from station.session.verify import verify_session

from .conftest import setup_for, written_procedure

STUDY = b"""
id = "small-grr"
title = "A small Gage R&R"
version = "1"
report_section = "2.4"
channels = ["x"]
unit = "in"
resolution = 0.0001
analysis = "gage_rr"
[[steps]]
id = "trials"
kind = "repeat"
title = "Trials"
label = "trial"
target = 2
[[steps.steps]]
id = "A"
kind = "parts"
title = "Appraiser A measures the parts"
prompt = "Appraiser A: part {part} ({cycle} of {count})."
target = 3
[[steps.steps]]
id = "B"
kind = "parts"
title = "Appraiser B measures the parts"
target = 3
"""


@pytest.fixture
def seeded(monkeypatch) -> None:
    """The orders drawn from a seeded generator: the same test every run."""
    monkeypatch.setattr(PartsStep, "shuffle", random.Random(25).shuffle)


def start(simulator, gauges_for, tmp_path: Path) -> tuple[Runner, object]:
    procedure = written_procedure(tmp_path / "small-grr.toml", STUDY)
    setup = setup_for(simulator.url, procedure, channel_map={"1": "x"})
    gauges = gauges_for(setup)
    return Runner.start(setup, gauges, tmp_path / "sessions"), (setup, gauges)


def orders(path: Path) -> list[tuple[str, int, list[int]]]:
    notes = load_session(path, recover=False).notes
    return [(n["step"], n["placement"], n["order"]) for n in notes if n.get("order")]


def test_every_part_once_in_its_drawn_order(simulator, gauges_for, tmp_path, seeded):
    runner, _ = start(simulator, gauges_for, tmp_path)
    # Entered, the step has drawn its order and written it before any reading.
    ((step, placement, order),) = orders(runner.path)
    assert (step, placement) == ("A", 1) and sorted(order) == [1, 2, 3]
    state = runner.state()
    assert state.action.kind == "capture" and state.action.part == order[0]
    assert state.action.prompt == f"Appraiser A: part {order[0]} (1 of 3)."
    assert (state.progress.done, state.progress.target, state.progress.noun) == (0, 3, "part")
    first = runner.capture(3.0)
    assert first.recorded and first.cycle.part == order[0]
    assert first.message.startswith(f"cycle 1 part {order[0]} x=")
    with pytest.raises(StationError, match=r"2 of 3 parts are not read yet \(part \d is next\)"):
        runner.confirm()
    # A rejected reading's part is asked for again, before the rest of the order.
    second = runner.capture(3.0)
    runner.reject(second.cycle.cycle, "the part was not seated")
    assert runner.state().action.part == order[1]
    for expected in order[1:]:
        assert runner.capture(3.0).cycle.part == expected
    state = runner.state()
    assert state.action.part is None and state.action.may_confirm
    refused = runner.capture(3.0)
    assert not refused.recorded and "All 3 parts are read" in refused.message
    runner.confirm()
    # The next appraiser (and later the next trial) gets an order of its own.
    assert runner.state().current.id == "B"
    for _ in range(3):
        runner.capture(3.0)
    runner.confirm()
    for _ in range(2):
        for _ in range(3):
            runner.capture(3.0)
        runner.confirm()
    runner.finish()
    drawn = orders(runner.path)
    assert [(s, p) for s, p, _ in drawn] == [("A", 1), ("B", 1), ("A", 2), ("B", 2)]
    assert len({tuple(o) for _, _, o in drawn}) > 1
    session = load_session(runner.path, recover=False)
    accepted = [session.cycles[n] for n in session.accepted_cycles]
    for step, placement, drawn_order in drawn:
        read = [c.part for c in accepted if (c.step, c.placement) == (step, placement)]
        assert read == drawn_order
    assert session.cycles[2].part == order[1] and 2 in session.rejected
    assert verify_session(runner.path).ok


def test_a_resumed_session_keeps_the_order(simulator, gauges_for, tmp_path, seeded):
    runner, (setup, gauges) = start(simulator, gauges_for, tmp_path)
    ((_, _, order),) = orders(runner.path)
    runner.capture(3.0)
    runner.interrupt("SIGTERM")
    resumed = Runner.resume(runner.path, gauges, setup=setup)
    state = resumed.state()
    # No second order is drawn for the step; the next part is the order's second.
    assert len(orders(runner.path)) == 1
    assert state.action.part == order[1] and state.progress.done == 1
    assert resumed.capture(3.0).cycle.part == order[1]
    resumed.interrupt("SIGTERM")
