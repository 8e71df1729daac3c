"""Resuming puts the recorded zero back on the gauges, and a runner lets go of the gauges it
hooked: a biased simulator on a real pty, a fresh gauge set per resume as after a restart."""

from __future__ import annotations

import threading

import pytest

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, GaugeSpec, Simulator, fixture_model
from station.run import Runner, open_gauges
from station.session.model import load_session

from .conftest import CHANNELS, every_kind_procedure, setup_for

BIAS = 0.05
"""Where the fixture sits on each gauge before zeroing (in): far above the noise."""


@pytest.fixture
def biased():
    model = fixture_model(
        CHANNELS,
        axis=AxisModel(bias=BIAS, noise=0.0002),
        gauge=GaugeSpec(resolution=0.0001, unit="in", low=-1.0, high=1.0),
    )
    sim = Simulator(get_protocol("mitutoyo"), model, seed=21)
    sim.start_pty()
    yield sim
    sim.stop()


def walk_to_cycles(runner: Runner) -> None:
    """Confirm, type, zero and capture until the cycles step is current."""
    while runner.state().current.kind != "cycles":
        kind = runner.state().current.kind
        if kind == "zero":
            runner.zero()
        elif kind == "input":
            runner.submit_input({"x": "1.5"})
        elif kind == "capture":
            assert runner.capture(10.0).recorded
        else:
            runner.confirm()


def test_resume_on_fresh_gauges_keeps_the_software_zero(biased, gauges_for, tmp_path):
    """Finding 1: cycles after a resume are zeroed like the ones before it."""
    setup = setup_for(biased.url, every_kind_procedure(tmp_path), cycles=4)
    first_gauges = gauges_for(setup)
    runner = Runner.start(setup, first_gauges, tmp_path / "sessions")
    walk_to_cycles(runner)
    before = runner.capture(10.0)
    assert before.recorded
    assert all(abs(v) < 0.005 for v in before.cycle.values.values()), before.message
    runner.interrupt("test")
    first_gauges.stop()

    fresh = gauges_for(setup)  # a new process: its readers know no offset
    resumed = Runner.resume(runner.path, fresh, setup=setup)
    try:
        after = resumed.capture(10.0)
        assert after.recorded
        assert all(abs(v) < 0.005 for v in after.cycle.values.values()), after.message
        assert fresh.zero_offsets() == pytest.approx(first_gauges.zero_offsets())
    finally:
        resumed.close()
    stored = load_session(runner.path).cycles
    last = stored[max(stored)]
    assert all(abs(r.value) < 0.005 for r in last.readings.values())
    assert all(r.zero == pytest.approx(BIAS, abs=0.002) for r in last.readings.values())


def test_resumes_on_the_same_gauges_do_not_chain_callbacks(biased, gauges_for, tmp_path):
    """Finding 18: every resume on one gauge set used to wrap the status callback again; now
    each engine holds a subscription while its file is open and cancels it on close."""
    setup = setup_for(biased.url, every_kind_procedure(tmp_path), cycles=4)
    gauges = gauges_for(setup)
    runner = Runner.start(setup, gauges, tmp_path / "sessions")
    assert gauges.listeners == 1  # port changes (poll: no set listener)
    runner.close()
    assert gauges.listeners == 0
    for _ in range(3):
        resumed = Runner.resume(runner.path, gauges, setup=setup)
        assert gauges.listeners == 1  # subscribed while open
        resumed.close()
        assert gauges.listeners == 0


class Stop(BaseException):
    """What a Ctrl-C at the wrong moment looks like to the runner."""


def test_a_failed_start_lets_go_of_the_gauges(biased, tmp_path):
    """Finding 18: when the start's first write fails, the gauges are unhooked and the
    runner's thread ends (nothing waits forever on a dead runner)."""
    setup = setup_for(biased.url, every_kind_procedure(tmp_path), trigger="push")
    gauges = open_gauges(setup, backoff=(0.05, 0.2))
    try:
        assert gauges.wait_connected(5.0)
        reader = gauges.readers[0]
        original = reader.on_status
        threads_before = set(threading.enumerate())

        def listener(notice) -> None:
            raise Stop

        with pytest.raises(Stop):
            Runner.start(setup, gauges, tmp_path / "sessions", listener=listener)
        assert gauges.on_set is None
        assert reader.on_status is original
        for thread in set(threading.enumerate()) - threads_before:
            thread.join(10)
            assert not thread.is_alive(), f"{thread.name} still runs"
    finally:
        gauges.stop()
