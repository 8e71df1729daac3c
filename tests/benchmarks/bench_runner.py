"""Reading -> acknowledged latency through the runner, against the bare journal append.

A simulator on a pseudo-terminal pushes complete x/y/z reading sets at a fixed rate: 100 and
1000 readings per second (33 and 333 sets), and 3000 readings/s as a stress. The runner records
each set as a cycle (``reading`` event written and fsynced) and calls its listener. The latency
of a set is from the moment the reader stamped its last frame (``t_mono``) to the listener call,
i.e. to "acknowledged". The baseline, measured in the same run on the same disk, is
``SessionWriter.append`` of the same event alone: what the journal costs without the reader,
the grouping, the live analysis and the alarms.

Run: ``.venv/bin/python tests/benchmarks/bench_runner.py [--seconds 5]``
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, GaugeSpec, Simulator, fixture_model
from station.procedures import parse_procedure
from station.run import PortSetup, Runner, RunnerNotice, SessionSetup, open_gauges
from station.session.journal import SessionWriter

PROCEDURE = b"""
id = "bench"
title = "One long cycles step"
version = "1"
report_section = "2.6"
channels = ["x", "y", "z"]
unit = "in"
resolution = 0.0001
[limits]
tolerance = 0.001
[[steps]]
id = "cycles"
kind = "cycles"
title = "Cycles"
"""


def percentile(values: list[float], fraction: float) -> float:
    """The value below which ``fraction`` of ``values`` lie (nearest rank)."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, round(fraction * len(ordered)) - 1))]


def through_runner(rate: float, seconds: float, folder: Path) -> dict[str, float]:
    """Push ``rate`` sets per second for ``seconds``; latency of each acknowledged set."""
    procedure = parse_procedure(PROCEDURE, folder / "bench.toml")
    model = fixture_model(
        ("x", "y", "z"),
        axis=AxisModel(noise=0.0003),
        gauge=GaugeSpec(resolution=0.0001, unit="in", low=-1.0, high=1.0),
    )
    sim = Simulator(get_protocol("mitutoyo"), model, seed=1)
    url = sim.start_pty()
    setup = SessionSetup(
        procedure=procedure,
        robot="bench",
        operator="bench",
        ports=(PortSetup(url, "mitutoyo", {"1": "x", "2": "y", "3": "z"}),),
        trigger="push",
        cycles=1_000_000,  # the most a header takes
    )
    gauges = open_gauges(setup, backoff=(0.05, 0.2))
    assert gauges.wait_connected(5.0)
    latencies: list[float] = []

    def listener(notice: RunnerNotice) -> None:
        event = notice.event
        if event is not None and event["type"] == "reading":
            stamped = max(spec["t_mono"] for spec in event["channels"].values())
            latencies.append(time.monotonic() - stamped)

    runner = Runner.start(setup, gauges, folder, listener=listener)
    sets = int(rate * seconds)
    start = time.monotonic()
    for index in range(sets):
        # Paced by the clock, not by sleeps that add up: a steady rate whatever each push costs.
        delay = start + index / rate - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        sim.push(1)
    sent_for = time.monotonic() - start
    deadline = time.monotonic() + 10.0
    while len(latencies) < sets and time.monotonic() < deadline:
        time.sleep(0.05)
    runner.interrupt("benchmark over")
    gauges.stop()
    sim.stop()
    return {
        "sent": sets,
        "acknowledged": len(latencies),
        "achieved_rate": sets / sent_for,
        "p50": percentile(latencies, 0.50),
        "p95": percentile(latencies, 0.95),
        "max": max(latencies),
    }


def bare_append(count: int, folder: Path) -> dict[str, float]:
    """The journal alone: append + fsync of the same reading event, back to back."""
    procedure = parse_procedure(PROCEDURE, folder / "bench.toml")
    header = {
        "procedure": {"id": procedure.id, "version": procedure.version, "sha256": procedure.sha256},
        "robot": "baseline",
        "channels": ["x", "y", "z"],
        "unit": "in",
    }
    channels = {
        ch: {
            "value": 0.0001,
            "unit": "in",
            "raw_value": 0.0003,
            "zero": 0.0002,
            "raw": "01A+0.0003",
            "t_wall": time.time(),
            "t_mono": time.monotonic(),
        }
        for ch in ("x", "y", "z")
    }
    latencies = []
    with SessionWriter.create(folder, header) as writer:
        for cycle in range(1, count + 1):
            started = time.perf_counter()
            writer.append("reading", cycle=cycle, step="cycles", channels=channels)
            latencies.append(time.perf_counter() - started)
    return {
        "p50": percentile(latencies, 0.50),
        "p95": percentile(latencies, 0.95),
        "rate": count / sum(latencies),
    }


def main() -> None:
    """Measure and print the figures and their ratios to the baseline."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0, help="seconds per rate (5)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        baseline = bare_append(1000, folder / "baseline")
        print(
            f"baseline: journal append + fsync alone: p50 {baseline['p50'] * 1e3:.2f} ms, "
            f"p95 {baseline['p95'] * 1e3:.2f} ms ({baseline['rate']:.0f} events/s back to back)"
        )
        # Readings per second: three per set (x, y, z). 3000/s is a stress beyond the target.
        for readings_per_second in (100, 1000, 3000):
            rate = readings_per_second / 3
            figures = through_runner(rate, args.seconds, folder / f"rate{readings_per_second}")
            lost = figures["sent"] - figures["acknowledged"]
            print(
                f"{readings_per_second:>5} readings/s ({rate:.0f} sets/s, achieved "
                f"{figures['achieved_rate']:.0f}): reading -> acknowledged "
                f"p50 {figures['p50'] * 1e3:.2f} ms, p95 {figures['p95'] * 1e3:.2f} ms, "
                f"max {figures['max'] * 1e3:.1f} ms; {figures['acknowledged']}/{figures['sent']} "
                f"sets acknowledged ({lost} not); p50 {figures['p50'] / baseline['p50']:.1f}x, "
                f"p95 {figures['p95'] / baseline['p95']:.1f}x the bare append"
            )


if __name__ == "__main__":
    main()
