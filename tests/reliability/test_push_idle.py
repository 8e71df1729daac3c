"""``station capture --trigger push`` waits for the operator: time without a DATA press is not
a refused set, however short ``--timeout`` and ``--attempts`` are."""

from __future__ import annotations

from helpers import CYCLES_ONLY

from station.session.model import load_session

from .conftest import Capture


def test_push_waiting_for_data_is_not_a_refusal(simulators, tmp_path):
    simulator = simulators(31)  # sends only when pushed: nobody presses DATA for a while
    procedures = tmp_path / "procedures"
    procedures.mkdir()
    (procedures / "cycles-only.toml").write_bytes(CYCLES_ONLY)
    capture = Capture(
        ["--procedure", "cycles-only", "--procedures", str(procedures), "--port",
         simulator.url, "--protocol", "mitutoyo", "--robot", "r", "--sessions",
         str(tmp_path / "s"), "--trigger", "push", "--cycles", "3", "--timeout", "0.2",
         "--attempts", "1"]
    )  # fmt: skip
    # Several --timeout periods pass without a press: the command says it waits, and waits.
    assert capture.wait_line(lambda line: "waiting for the gauges" in line, 60.0, stderr=True), (
        capture.errors
    )
    assert capture.wait_line(lambda line: line.startswith("session file: "), 5.0)
    for cycle in range(1, 4):
        simulator.push(1)  # a set that arrives outside a capture call is recorded all the same
        assert capture.wait_line(lambda line, n=cycle: line.startswith(f"cycle {n} "), 60.0), (
            capture.errors
        )
    assert capture.finish() == 0, capture.errors
    session = load_session(capture.session_path)
    assert session.status == "finished" and sorted(session.cycles) == [1, 2, 3]
    # One waiting line per stretch of waiting, not one per --timeout period.
    waiting = [line for line in capture.errors if "waiting for the gauges" in line]
    assert 1 <= len(waiting) <= 3, capture.errors
