"""Append + fsync latency per session event, against a plain write without fsync.

Run: ``.venv/bin/python tests/benchmarks/bench_journal.py [--events N] [--dir DIR]``

The baseline is the same JSON line written with ``os.write`` and no fsync, in the same run and
folder, so the ratio shows what durability costs on this disk. Figures: p50, p95, p99, max per
event (microseconds) and events per second. A batch of 100 streamed points (``samples``) is
measured too: one event per batch keeps the fsync cost per point small.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

from station.procedures import discover_procedures
from station.run import PortSetup, SessionSetup
from station.session.journal import SessionWriter
from station.session.lines import decode_line, encode_line
from station.session.model import load_session


def reading(cycle: int) -> dict:
    return {
        "cycle": cycle,
        "step": "cycles",
        "channels": {
            c: {
                "value": 0.0001 * (cycle % 9),
                "raw_value": 0.375 + 0.0001 * (cycle % 9),
                "zero": 0.375,
                "unit": "in",
                "raw": f"01A+0.{3750 + cycle % 9:04d}",
                "t_mono": 1000.0 + cycle,
                "t_wall": 1.7e9 + cycle,
            }
            for c in ("x", "y", "z")
        },
    }


def percentiles(samples: list[float]) -> dict[str, float]:
    ordered = sorted(samples)
    pick = lambda q: ordered[min(len(ordered) - 1, int(q * len(ordered)))]  # noqa: E731
    return {
        "p50": pick(0.50) * 1e6,
        "p95": pick(0.95) * 1e6,
        "p99": pick(0.99) * 1e6,
        "max": ordered[-1] * 1e6,
        "mean": statistics.fmean(ordered) * 1e6,
    }


def show(name: str, figures: dict[str, float]) -> None:
    print(
        f"{name:<34} p50 {figures['p50']:9.1f} us  p95 {figures['p95']:9.1f} us  "
        f"p99 {figures['p99']:9.1f} us  max {figures['max']:9.1f} us  "
        f"({1e6 / figures['mean']:8.0f} events/s)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--events", type=int, default=2000)
    parser.add_argument("--dir", default=None, help="folder on the disk to measure (default: tmp)")
    args = parser.parse_args()
    procedure = discover_procedures(use_env=False).get("repeatability")
    port = PortSetup("loop://", "mitutoyo", {"1": "x", "2": "y", "3": "z"})
    header = SessionSetup(procedure, "bench", "", (port,)).header_fields()

    with tempfile.TemporaryDirectory(dir=args.dir) as folder:
        # Baseline: the same bytes, os.write without fsync.
        line = encode_line({"seq": 1, "t": "2026-11-23T00:00:00.000000Z", **reading(1)}, None)
        fd = os.open(Path(folder) / "plain.jsonl", os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o640)
        plain = []
        for _ in range(args.events):
            start = time.perf_counter()
            os.write(fd, line + b"\n")
            plain.append(time.perf_counter() - start)
        os.close(fd)

        # The CPU part of an append alone: encode, hash, decode back (no I/O).
        cpu = []
        for cycle in range(1, args.events + 1):
            start = time.perf_counter()
            decode_line(
                encode_line({"seq": cycle, "t": "x", "type": "reading", **reading(cycle)}, None)
            )
            cpu.append(time.perf_counter() - start)

        with SessionWriter.create(folder, header) as writer:
            journal = []
            for cycle in range(1, args.events + 1):
                start = time.perf_counter()
                writer.append("reading", **reading(cycle))
                journal.append(time.perf_counter() - start)
            batches = []
            rows = [[0.0001 * k, 0.0002 * k, 0.01 * k] for k in range(100)]
            for stroke in range(1, 201):
                start = time.perf_counter()
                writer.append(
                    "samples", step="stroke", stroke=stroke, channels=["x", "y", "z"], values=rows
                )
                batches.append(time.perf_counter() - start)
        start = time.perf_counter()
        session = load_session(writer.path, recover=False)
        load_seconds = time.perf_counter() - start
        size = writer.path.stat().st_size

    base, durable, batch = percentiles(plain), percentiles(journal), percentiles(batches)
    print(f"events: {args.events} readings (3 channels), {len(line) + 1} bytes per line")
    show("baseline: os.write, no fsync", base)
    show("encode+hash+decode only (no I/O)", percentiles(cpu))
    show("journal: append (check+write+fsync)", durable)
    show("journal: samples batch of 100 points", batch)
    print(
        f"ratio journal/baseline: p50 x{durable['p50'] / base['p50']:.0f}, "
        f"p95 x{durable['p95'] / base['p95']:.0f}; "
        f"per streamed point (batches of 100): {batch['p50'] / 100:.1f} us"
    )
    print(
        f"load + verify of the {size / 1e6:.1f} MB session ({len(session.events)} events): "
        f"{load_seconds * 1e3:.0f} ms"
    )


if __name__ == "__main__":
    main()
