"""The live analysis goes to the listener on the engine's own thread: a slow analysis never holds
up a reading set, and the analysis the notices carry is the batch analysis of the file."""

from __future__ import annotations

import threading

import station.analysis.live as live_module
from station.analysis.document import to_json
from station.methods import analyze_session_file
from station.run import Runner, RunnerNotice

from .conftest import cycles_only_procedure, setup_for


def test_a_slow_live_analysis_never_holds_up_a_capture(
    simulator, gauges_for, tmp_path, monkeypatch
):
    gate = threading.Event()
    combine = live_module.combine

    def gated_combine(*args, **kwargs):
        gate.wait(60)  # the analysis of the snapshot waits until the test lets it go on
        return combine(*args, **kwargs)

    monkeypatch.setattr(live_module, "combine", gated_combine)
    notices: list[RunnerNotice] = []
    analysed = threading.Event()

    def listener(notice: RunnerNotice) -> None:
        notices.append(notice)
        if notice.analysis is not None and notice.analysis.channels["x"].descriptive.n == 3:
            analysed.set()

    setup = setup_for(simulator.url, cycles_only_procedure(tmp_path))
    runner = Runner.start(setup, gauges_for(setup), tmp_path / "sessions", listener=listener)
    outcomes = []
    try:
        capturing = threading.Thread(
            target=lambda: outcomes.extend(runner.capture(5.0) for _ in range(3)), daemon=True
        )
        capturing.start()
        capturing.join(30)
        # Recorded and told while the analysis still waits.
        assert [outcome.recorded for outcome in outcomes] == [True, True, True]
        readings = [n for n in notices if n.event is not None and n.event["type"] == "reading"]
        assert [n.event["cycle"] for n in readings] == [1, 2, 3]
        assert all(n.analysis is None for n in readings)
        gate.set()
        assert analysed.wait(30), "no notice carried the analysis of the three cycles"
        carried = next(n.analysis for n in reversed(notices) if n.analysis is not None)
        batch = analyze_session_file(runner.path).analysis
        assert to_json(carried) == to_json(batch) == to_json(runner.analysis())
    finally:
        gate.set()
        runner.interrupt("test over")
