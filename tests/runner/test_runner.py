"""The runner walking real procedures against the simulator on a real pty: every event lands
in a session file that verifies, and the live analysis equals the batch analysis of the file."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from station.analysis.document import to_json
from station.analysis.monitor import replay_live_alarms
from station.analysis.summary import analyze
from station.errors import StationError
from station.instruments.simulator import Faults
from station.run import Runner, RunnerNotice
from station.session.alarms import live_events
from station.session.header import analysis_config
from station.session.model import load_session
from station.session.verify import verify_session

from .conftest import (
    cycles_only_procedure,
    every_kind_procedure,
    make_simulator,
    setup_for,
)


def wait_until_inside(thread: threading.Thread, function: str, timeout: float = 30.0) -> bool:
    """True once ``thread`` runs inside ``function`` (a frame of its stack has that name): e.g.
    a capture blocked waiting for the device's next set. False if it ended or the time ran
    out. A push sent before the waiter waits would be taken by someone else."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and thread.is_alive():
        frame = sys._current_frames().get(thread.ident)
        while frame is not None:
            if frame.f_code.co_name == function:
                return True
            frame = frame.f_back
        time.sleep(0.002)
    return False


def batch_analysis(path: Path):
    """What `station analyze` computes from the file: accepted cycles, the header's config."""
    session = load_session(path, recover=False)
    return analyze(
        session.channel_values(),
        analysis_config(session.header, session.zeroes),
        excluded_cycles=session.excluded_cycles,
        cycles=session.channel_cycles(),
        # The reading times the live analysis' drift trend runs on, as `station analyze` does.
        times=session.channel_times(),
    )


def test_repeatability_walk_poll(simulator, gauges_for, tmp_path):
    setup = setup_for(simulator.url)
    gauges = gauges_for(setup)
    notices: list[RunnerNotice] = []
    on_disk: list[bool] = []

    def listener(notice: RunnerNotice) -> None:
        notices.append(notice)
        if notice.event is not None:
            # Called only once the event is on disk: its line is in the file already.
            on_disk.append(notice.event["hash"].encode() in Path(runner_path[0]).read_bytes())

    runner_path: list[Path] = []
    runner = Runner.start(setup, gauges, tmp_path, listener=listener)
    runner_path.append(runner.path)
    state = runner.state()
    assert [view.mark for view in state.steps][:2] == ["current", "pending"]
    assert state.current is not None and state.current.id == "fixture"

    with pytest.raises(StationError, match="does not capture"):
        runner.capture(1.0)
    while runner.state().current.kind == "check":
        runner.confirm()
    assert runner.state().current.kind == "zero"
    runner.confirm()  # a zero step's confirm zeroes
    runner.confirm()  # teach B
    state = runner.state()
    assert state.current.kind == "cycles" and (state.progress.done, state.progress.target) == (
        0,
        30,
    )
    assert "Cycle 1 of 30" in runner.prompt()

    with pytest.raises(StationError, match="capture at least 25 more"):
        runner.confirm()
    outcomes = []
    while runner.state().progress.done < 30:
        outcome = runner.capture(3.0)
        assert outcome.recorded, outcome.message
        outcomes.append(outcome)
        if outcome.cycle.cycle == 12:
            runner.reject(12, "the cube slipped on the end effector")
            runner.note("re-seated the cube")
            runner.pause()
            assert runner.state().status == "paused" and not runner.state().can_capture
            with pytest.raises(StationError, match="paused"):
                runner.capture(1.0)
            runner.resume_capture()
    state = runner.state()
    assert state.progress.done == 30 and state.accepted == 30 and len(state.cycles) == 31
    assert [c.cycle for c in state.cycles if c.rejected] == [12]
    # The live analysis already equals the batch analysis of what is on disk.
    assert to_json(runner.analysis()) == to_json(batch_analysis(runner.path))
    extra = runner.capture(3.0)
    assert not extra.recorded and extra.message.startswith("All 30 cycles are recorded")
    runner.confirm()
    assert runner.state().complete
    analysis = runner.finish()

    assert all(on_disk) and len(on_disk) > 40
    result = verify_session(runner.path)
    assert result.ok, result.message
    assert result.last_hash == runner.last_hash
    session = load_session(runner.path, recover=False)
    assert session.status == "finished"
    assert session.rejected == {12: "the cube slipped on the end effector"}
    assert session.excluded_cycles == (12,) and len(session.accepted_cycles) == 30
    assert [n["text"] for n in session.notes] == [
        "re-seated the cube",
        "capture paused",
        "capture resumed",
    ]
    assert session.zeroes and set(session.zeroes[0]["channels"]) == {"x", "y", "z"}
    confirmed_by = {e["step"]: e["by"] for e in session.events if e["type"] == "step"}
    assert set(confirmed_by) == {s.id for s in setup.procedure.steps}
    assert analysis.excluded_cycles == (12,)
    assert to_json(analysis) == to_json(batch_analysis(runner.path))
    # The recorded values are what the simulator sent, less the software zero.
    first = session.cycles[1].readings["x"]
    assert first.value == pytest.approx(first.raw_value - first.zero, abs=1e-12)
    # Alarms: the live ones (phase II, frozen limits) are written, each marked live; the
    # retrospective chart's alarms are the report's to compute, not the journal's.
    assert all(a["live"] is True for a in session.alarms)
    replayed = replay_live_alarms(live_events(session), analysis_config(session.header))
    assert [a.event_fields()["text"] for a in replayed] == [a["text"] for a in session.alarms]
    with pytest.raises(StationError, match="finished"):
        runner.capture(1.0)


def test_every_step_kind_and_resume(simulator, gauges_for, tmp_path):
    procedure = every_kind_procedure(tmp_path)
    setup = setup_for(simulator.url, procedure)
    gauges = gauges_for(setup)
    runner = Runner.start(setup, gauges, tmp_path / "sessions")
    runner.confirm()
    with pytest.raises(StationError, match="needs values"):
        runner.confirm()
    for bad, match in (
        ({"x": "twelve"}, "Pendant X must be a number in in"),
        ({"x": ""}, "Pendant X is required"),
        ({"x": "1", "y": "2"}, "has no field y"),
    ):
        with pytest.raises(StationError, match=match):
            runner.submit_input(bad)
    runner.submit_input({"x": " 12.5 ", "remark": "pendant in mm mode"})
    runner.zero()
    placements = []
    for _ in range(2):
        state = runner.state()
        placements.append((state.placement, state.placements))
        runner.confirm()
        outcome = runner.capture(3.0)
        assert outcome.recorded and set(outcome.cycle.values) == {"x", "y"}
    assert placements == [(1, 2), (2, 2)]
    assert runner.state().current.kind == "cycles"
    runner.capture(3.0)
    # Interrupted mid-procedure: the file says so and stays resumable.
    runner.interrupt("SIGTERM")
    assert runner.state().status == "interrupted"
    with pytest.raises(StationError, match="interrupted"):
        runner.capture(1.0)
    session = load_session(runner.path, recover=False)
    assert session.status == "interrupted" and session.next_cycle == 4
    assert session.inputs["pendant"] == {"x": 12.5, "remark": "pendant in mm mode"}

    resumed = Runner.resume(runner.path, gauges, setup=setup)
    state = resumed.state()
    assert state.current.id == "cycles" and state.progress.done == 1
    assert [v.mark for v in state.steps].count("done") == 7
    outcome = resumed.capture(3.0)
    assert outcome.cycle.cycle == 4  # numbering continues
    resumed.capture(3.0)
    resumed.confirm()
    resumed.finish()
    session = load_session(runner.path, recover=False)
    assert [e["type"] for e in session.events].count("resume") == 1
    assert sorted(session.cycles) == [1, 2, 3, 4, 5]
    assert session.cycles[1].placement == 1 and session.cycles[2].placement == 2
    assert verify_session(runner.path).ok
    with pytest.raises(StationError, match="finished"):
        Runner.resume(runner.path, gauges, setup=setup)


def test_missing_channel_records_nothing(simulator, gauges_for, tmp_path):
    # Device channel 4 feeds z, and the simulator serves only 1 to 3: z never answers.
    procedure = cycles_only_procedure(tmp_path)
    setup = setup_for(simulator.url, procedure, channel_map={"1": "x", "2": "y", "4": "z"})
    runner = Runner.start(setup, gauges_for(setup), tmp_path)
    lines_before = runner.path.read_bytes().count(b"\n")
    outcome = runner.capture(0.5)
    assert not outcome.recorded
    assert "no reading from z" in outcome.message
    assert runner.path.read_bytes().count(b"\n") == lines_before
    assert runner.state().messages[-1].text == outcome.message


def test_duplicated_channel_is_refused(gauges_for, tmp_path):
    # Every frame is followed by late copies of earlier frames: sets are never clean.
    sim = make_simulator(faults=Faults(stale_rate=1.0, stale_count=3))
    sim.start_pty()
    try:
        procedure = every_kind_procedure(tmp_path)
        setup = setup_for(sim.url, procedure)
        runner = Runner.start(setup, gauges_for(setup), tmp_path / "s")
        runner.confirm()
        runner.submit_input({"x": "1"})
        runner.zero()  # a software zero takes the first fresh reading of each channel
        runner.confirm()
        # A set is clean only when the late copies happen to miss it; the capture step then
        # completes, and the next placement's check step comes first.
        outcomes = []
        while len(outcomes) < 10 and not any(not o.recorded for o in outcomes):
            if runner.state().current.step.kind == "check":
                runner.confirm()
            outcomes.append(runner.capture(0.5))
        refused = [o for o in outcomes if not o.recorded]
        assert refused, [o.message for o in outcomes]
        assert all("more than one reading" in o.message for o in refused)
        recorded = len(outcomes) - len(refused)
        assert len(load_session(runner.path, recover=False).cycles) == recorded
    finally:
        sim.stop()


def test_push_trigger_records_sets_without_capture_calls(gauges_for, tmp_path):
    sim = make_simulator(seed=11)
    sim.start_pty()
    try:
        setup = setup_for(sim.url, cycles=5, trigger="push")
        gauges = gauges_for(setup)
        recorded = threading.Event()
        ignored = threading.Event()
        refused = threading.Event()
        cycles_seen: list[int] = []

        def listener(notice: RunnerNotice) -> None:
            if notice.event is not None and notice.event["type"] == "reading":
                cycles_seen.append(notice.event["cycle"])
                recorded.set()
            text = notice.message.text if notice.message is not None else ""
            if "no capture step is current" in text:
                ignored.set()
            if "this reading set was not" in text:
                refused.set()

        runner = Runner.start(setup, gauges, tmp_path, listener=listener)
        while runner.state().current.kind == "check":
            runner.confirm()
        assert runner.state().current.kind == "zero"
        sim.push(1)  # DATA pressed before the zero: not a cycle, and the runner says so
        assert ignored.wait(30), "the set never reached the runner"
        assert cycles_seen == []
        zeroing = threading.Thread(target=lambda: runner.zero(timeout=30.0))
        zeroing.start()
        # Three presses (the zero is their mean), once the zero listens for them: no set is
        # left over for the cycles.
        assert wait_until_inside(zeroing, "collect"), "the zero never listened for presses"
        for _ in range(3):
            sim.push(1)
            time.sleep(0.05)
        zeroing.join(30)
        assert not zeroing.is_alive() and runner.state().current.kind == "check"
        runner.confirm()
        assert runner.state().current.kind == "cycles"
        for expected in range(1, 6):
            recorded.clear()
            sim.push(1)
            assert recorded.wait(30), f"set {expected} was not recorded"
        sim.push(1)  # a sixth set: the step has its five, so it is refused
        assert refused.wait(30), "the sixth set was neither refused nor recorded"
        assert cycles_seen == [1, 2, 3, 4, 5]
        # capture() under push waits for the device's next set and returns its outcome.
        runner.reject(5, "pressed DATA twice")
        waiter: list = []
        thread = threading.Thread(target=lambda: waiter.append(runner.capture(30.0)))
        thread.start()
        assert wait_until_inside(thread, "wait_for"), "capture() never waited for the set"
        sim.push(1)
        thread.join(30)
        assert waiter and waiter[0].recorded and waiter[0].cycle.cycle == 6
        runner.confirm()
        analysis = runner.finish()
        assert analysis.excluded_cycles == (5,)
        assert to_json(analysis) == to_json(batch_analysis(runner.path))
        values = load_session(runner.path).channel_values()
        assert len(values["x"]) == 5
    finally:
        sim.stop()


def test_a_reject_rejects_the_cycle_it_names_not_the_last(simulator, gauges_for, tmp_path):
    # Issue 26, item 1: the operator names cycle 2 (the dialog's title); cycle 3 arrives
    # while the reason is typed; confirming rejects cycle 2, and cycle 3 stays.
    setup = setup_for(simulator.url, cycles_only_procedure(tmp_path), cycles=5)
    runner = Runner.start(setup, gauges_for(setup), tmp_path)
    for _ in range(2):
        assert runner.capture(3.0).recorded
    named = runner.state().last_cycle.cycle
    assert named == 2
    assert runner.capture(3.0).recorded  # arrives between naming and confirming
    runner.reject(named, "the cube slipped")
    state = runner.state()
    assert [(c.cycle, c.rejected) for c in state.cycles] == [
        (1, None),
        (2, "the cube slipped"),
        (3, None),
    ]
    assert state.accepted == 2
    # A cycle that does not exist, or one already rejected, is refused with nothing written.
    size = runner.path.stat().st_size
    with pytest.raises(
        StationError, match=r"no cycle 9 to reject \(the last recorded is cycle 3\)"
    ):
        runner.reject(9, "typo")
    with pytest.raises(StationError, match=r"cycle 2 is already rejected \(the cube slipped\)"):
        runner.reject(2, "again")
    with pytest.raises(StationError, match="reason"):
        runner.reject(3, "  ")
    assert runner.path.stat().st_size == size
    runner.interrupt("test over")
    session = load_session(runner.path, recover=False)
    assert session.rejected == {2: "the cube slipped"}
    assert to_json(runner.analysis()) == to_json(batch_analysis(runner.path))


def test_a_reject_before_any_cycle_is_refused(simulator, gauges_for, tmp_path):
    setup = setup_for(simulator.url, cycles_only_procedure(tmp_path), cycles=5)
    runner = Runner.start(setup, gauges_for(setup), tmp_path)
    with pytest.raises(StationError, match=r"no cycle 1 to reject \(no cycle is recorded yet\)"):
        runner.reject(1, "bumped")
    runner.interrupt("test over")


def test_runner_imports_no_ui():
    """The runner is domain code: importing it (and the capture command) loads no UI."""
    code = (
        "import sys, station.run, station.methods, station.commands.capture\n"
        "ui = [m for m in sys.modules if m.split('.')[0] in ('textual', 'plotext')"
        " or m.startswith('station.tui')]\n"
        "print(ui)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0 and done.stdout.strip() == "[]", done.stdout + done.stderr
