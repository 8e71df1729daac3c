"""Frames parsed per second per gauge protocol, frame splitter included.

Run: ``.venv/bin/python tests/benchmarks/bench_protocols.py [--frames N] [--repeat R]``

For each protocol a stream of encoded frames (realistic values at 0.001 resolution, the
multiplexed protocols cycling over three channels) is fed to a :class:`FrameSplitter` in
4096-byte reads and every frame is parsed, as the reader thread does. Printed per protocol:

* frames per CPU second (``time.process_time``, best of ``--repeat`` runs) against the target
  500,000 frames/s, and frames per wall-clock second: on a shared machine the wall figure
  falls with the load of other processes (printed), the CPU figure much less;
* the ratio to what a 115200-baud line can carry of that protocol's frames (10 bits a byte);
* the ratio to an in-run baseline: the least a parser can do, ``stream.split(terminator)`` and
  ``float()`` of a fixed slice, measured on the same stream in the same run.
"""

from __future__ import annotations

import argparse
import functools
import os
import random
import time

from station.instruments.base import Value
from station.instruments.framing import FrameSplitter
from station.instruments.protocols import get_protocol, protocol_names

TARGET = 500_000
BAUD = 115_200
READ_SIZE = 4096
CHANNELS = {"mitutoyo": "123", "uwave": "123", "idh": "123", "ascii": "xyz"}


def build_stream(name: str, frames: int, seed: int = 1) -> bytes:
    """``frames`` encoded frames of values around a fixture reading, back to back."""
    protocol = get_protocol(name)
    rng = random.Random(seed)
    channels = CHANNELS.get(name, "1")
    return b"".join(
        protocol.encode(channels[i % len(channels)], rng.gauss(0.0, 2.0), 0.001, "mm")
        for i in range(frames)
    )


def split_and_parse(name: str, stream: bytes) -> int:
    """Readings parsed from ``stream`` the way the reader does it; returns their count."""
    protocol = get_protocol(name)
    splitter = FrameSplitter(protocol.terminator)
    parse = protocol.parse
    count = 0
    for start in range(0, len(stream), READ_SIZE):
        for frame in splitter.feed(stream[start : start + READ_SIZE]):
            if isinstance(parse(frame), Value):  # type: ignore[arg-type]
                count += 1
    return count


def naive(stream: bytes, terminator: bytes, value_slice: slice) -> int:
    """The baseline: split the whole stream and ``float()`` a fixed slice of every line."""
    count = 0
    for line in stream.split(terminator):
        if line:
            try:
                float(line[value_slice])
            except ValueError:
                continue
            count += 1
    return count


# Where the number sits in each protocol's frame, for the baseline only.
VALUE_SLICES = {
    "mitutoyo": slice(3, None),
    "uwave": slice(7, -1),
    "sylvac": slice(None),
    "cdi": slice(0, 9),
    "idh": slice(5, None),
    "ascii": slice(2, None),
    "digimatic": slice(5, 11),
}


def best_rate(function, frames: int, repeat: int) -> tuple[float, float, int]:
    """Frames per CPU second and per wall second of the fastest of ``repeat`` runs, and what
    the last run returned."""
    best_cpu = best_wall = float("inf")
    result = 0
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        result = function()
        best_cpu = min(best_cpu, time.process_time() - cpu)
        best_wall = min(best_wall, time.perf_counter() - wall)
    return frames / best_cpu, frames / best_wall, result


def main() -> int:
    """Measure and print; exit 1 when a protocol misses the target."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()

    load = os.getloadavg()[0]
    print(
        f"{args.frames} frames per protocol, {READ_SIZE}-byte reads, best of {args.repeat}; "
        f"load average {load:.1f} on {os.cpu_count()} CPUs"
    )
    print(
        f"{'protocol':<10} {'frames/CPU s':>12} {'target':>7} {'frames/wall s':>13} "
        f"{'x line':>8} {'x naive':>8}   (line = 115200 baud full of this protocol's frames)"
    )
    missed = []
    for name in protocol_names():
        stream = build_stream(name, args.frames)
        terminator = get_protocol(name).terminator
        rate, wall_rate, parsed = best_rate(
            functools.partial(split_and_parse, name, stream), args.frames, args.repeat
        )
        if parsed != args.frames:
            raise SystemExit(f"{name}: parsed {parsed} of {args.frames} frames")
        naive_rate, _, _ = best_rate(
            functools.partial(naive, stream, terminator, VALUE_SLICES[name]),
            args.frames,
            args.repeat,
        )
        frame_bytes = len(stream) / args.frames
        line_rate = BAUD / 10 / frame_bytes
        verdict = "ok" if rate >= TARGET else "MISSED"
        if rate < TARGET:
            missed.append(name)
        print(
            f"{name:<10} {rate:>12,.0f} {verdict:>7} {wall_rate:>13,.0f} "
            f"{rate / line_rate:>7,.0f}x "
            f"{rate / naive_rate:>7.2f}x   ({frame_bytes:.0f} B/frame, line {line_rate:,.0f}/s, "
            f"naive {naive_rate:,.0f}/s)"
        )
    if missed:
        print(f"below {TARGET:,} frames per CPU second: {', '.join(missed)}")
        return 1
    print(f"all protocols at or above {TARGET:,} frames per CPU second")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
