"""Readings per second through a real pty with zero loss, against the parse-only rate.

The simulator pushes U-WAVE frames of a :class:`RampModel` (every value distinct within the
run) at a fixed rate onto a pseudo-terminal; a :class:`GaugeReader` reads them. At the end the
received frames are compared with the sent ones: lost, duplicated, invented. The in-run baseline
is the parse-only rate (splitter + parser over the same frames in memory); the ratio says how
much head-room the reader thread leaves.

Target: 1,000 readings/s sustained for 60 s with zero loss.

    .venv/bin/python tests/benchmarks/bench_reader.py [--seconds 60] [--rate 1000]
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from station.instruments.framing import FrameSplitter  # noqa: E402
from station.instruments.protocols import get_protocol  # noqa: E402
from station.instruments.reader import GaugeReader  # noqa: E402
from station.instruments.simulator import GaugeSpec, RampModel, Simulator  # noqa: E402


def parse_only_rate(frames: list[bytes], protocol, repeat: int = 5) -> float:
    """Frames per second through splitter + parser, in memory (best of ``repeat``)."""
    stream = b"".join(frames)
    chunk = 4096
    best = 0.0
    for _ in range(repeat):
        splitter = FrameSplitter(protocol.terminator)
        parse = protocol.parse
        began = time.perf_counter()
        count = 0
        for start in range(0, len(stream), chunk):
            for frame in splitter.feed(stream[start : start + chunk]):
                parse(frame)
                count += 1
        best = max(best, count / (time.perf_counter() - began))
    return best


def run(seconds: float, rate: float) -> int:
    protocol = get_protocol("uwave")
    model = RampModel(["x"], GaugeSpec(resolution=0.0001, low=-99.0, high=99.0))
    sim = Simulator(protocol, model, seed=0)
    url = sim.start_pty()
    received: list[str] = []
    lock = threading.Lock()

    def keep(reading) -> None:
        with lock:
            received.append(reading.raw)

    reader = GaugeReader(url, protocol, {"1": "x"}, on_reading=keep)
    reader.start()
    if not reader.wait_connected(5.0):
        print("reader did not connect", file=sys.stderr)
        return 1
    time.sleep(0.1)
    began = time.monotonic()
    sim.push_rate = rate  # the serving thread starts pushing on its schedule
    time.sleep(seconds)
    sim.push_rate = 0
    pushed_for = time.monotonic() - began
    time.sleep(0.5)  # let the last frames land
    reader.stop()
    sim.stop()

    sent = [frame.frame.strip().decode() for frame in sim.sent["x"]]
    sent_count, received_count = Counter(sent), Counter(received)
    lost = sum((sent_count - received_count).values())
    duplicated = sum(max(0, n - 1) for n in received_count.values())
    invented = sum(n for raw, n in received_count.items() if raw not in sent_count)
    in_order = received == [raw for raw in sent if raw in received_count]
    achieved = len(received) / pushed_for
    baseline = parse_only_rate([frame.frame for frame in sim.sent["x"]], protocol)

    print(f"pty push at {rate:,.0f}/s for {pushed_for:.1f} s (U-WAVE frames, GaugeReader thread)")
    print(f"  sent      {len(sent):>9,}")
    print(f"  received  {len(received):>9,}   ({achieved:,.0f} readings/s)")
    print(f"  lost      {lost:>9,}")
    print(f"  duplicated{duplicated:>9,}")
    print(f"  invented  {invented:>9,}")
    print(f"  in order  {in_order!s:>9}")
    print(f"  rejected  {reader.rejected_count:>9,}")
    print(f"baseline: parse-only (splitter + parser, in memory) {baseline:,.0f} frames/s")
    print(f"ratio: parse-only / through-pty = {baseline / max(achieved, 1e-9):,.0f}x")
    target_met = lost == 0 and duplicated == 0 and invented == 0 and achieved >= 0.98 * rate
    print(f"target 1,000/s with zero loss: {'met' if target_met and rate >= 1000 else 'NOT met'}")
    return 0 if target_met else 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="push duration (60)")
    parser.add_argument("--rate", type=float, default=1000.0, help="readings per second (1000)")
    args = parser.parse_args()
    return run(args.seconds, args.rate)


if __name__ == "__main__":
    sys.exit(main())
