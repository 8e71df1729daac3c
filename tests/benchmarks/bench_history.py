"""Benchmark: ``station history`` over a plant's worth of sessions, with and without the
session index (issue 23, items 6 and 8).

Run on demand (not part of the test suite):

    .venv/bin/python tests/benchmarks/bench_history.py [--sessions N] [--robots R]

Writes N finished repeatability sessions (default 2,000) of R robots (default 20), 30 cycles
of x, y, z each, through the real SessionWriter (its fsync per event skipped while generating:
the bytes are the journal's), then measures in fresh processes, each the best of a few runs,
CPU seconds (user + system) and peak memory:

- the file scan (the baseline: every file read, as history did before the index);
- the index cold (an empty index: every file read and analysed, its figures kept);
- the index warm (nothing changed: the figures come from the index; every file is stat'ed);

for ``history ROBOT`` and ``history --all``, with the ratios against the scan. Target:
history of 2,000 sessions <= 5 s warm. A second folder of half the sessions gives the warm
index's time per doubling (about 2 is linear; target <= 2.5).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from datetime import UTC, datetime, timedelta
from pathlib import Path

PYTHON = sys.executable
RUNS = 3
TIME = "/usr/bin/time"
START = datetime(2025, 1, 6, 8, 0, tzinfo=UTC)


def write_sessions(folder: Path, count: int, robots: int) -> None:
    """``count`` sessions, round-robin over ``robots`` robots, a day apart per robot, x's bias
    growing slowly (a worn robot's history)."""
    import numpy as np

    import station.session.journal as journal
    from station.procedures import discover_procedures
    from station.run import PortSetup, SessionSetup
    from station.session.journal import SessionWriter

    journal.os.fsync = lambda fd: None  # type: ignore[attr-defined]  # generation only
    procedure = discover_procedures(use_env=False).get("repeatability")
    port = PortSetup("loop://", "mitutoyo", {"1": "x", "2": "y", "3": "z"})
    rng = np.random.default_rng(23)
    for number in range(count):
        robot = f"R{number % robots:02d}"
        round_ = number // robots
        header = SessionSetup(procedure, robot, "bench", (port,)).header_fields()
        created = START + timedelta(days=round_, minutes=number % robots)
        with SessionWriter.create(folder, header, now=created) as writer:
            writer.append("step", step="fixture", action="confirmed", by="operator")
            for cycle in range(1, 31):
                values = rng.normal(0.0, 0.0002, 3) + (0.000002 * round_, 0.0, 0.0)
                writer.append(
                    "reading",
                    cycle=cycle,
                    step="cycles",
                    channels={
                        axis: {"value": round(float(v), 4), "unit": "in", "raw": f"{v:+.4f}"}
                        for axis, v in zip("xyz", values, strict=True)
                    },
                )
            writer.append("finish", verdict="done")


def measured(mode: str, folder: Path, data: Path) -> tuple[float, float]:
    """The least CPU seconds and the largest peak MiB of fresh processes running ``mode``
    (see :func:`run_mode`), the index in ``data``; a cold mode empties it first. The warm
    index is run ``RUNS`` times, the long scans once (their noise is a small part of them)."""
    best, peak = float("inf"), 0.0
    for _ in range(RUNS if mode.startswith("warm") else 1):
        if "cold" in mode:
            shutil.rmtree(data, ignore_errors=True)
        done = subprocess.run(
            [TIME, "-f", "%U %S %M", PYTHON, __file__, "--run", mode, str(folder)],
            env={**os.environ, "XDG_DATA_HOME": str(data)},
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            check=True,
        )
        user, system, kib = done.stderr.split()[-3:]
        best = min(best, float(user) + float(system))
        peak = max(peak, int(kib) / 1024)
    return best, peak


def run_mode(mode: str, folder: Path) -> None:
    """One measured run: ``files-robot``, ``cold-robot``, ``warm-robot`` (history of R00) or
    the same with ``-all`` (history --all)."""
    from station.record.history import fleet_history, robot_history
    from station.record.index import SessionIndex

    with SessionIndex.open() as index:
        chosen = None if mode.startswith("files") else index
        if mode.endswith("-all"):
            fleet_history(folder, index=chosen)
        else:
            robot_history(folder, "R00", index=chosen)
        if index.warnings:
            raise SystemExit("\n".join(index.warnings))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=2000)
    parser.add_argument("--robots", type=int, default=20)
    parser.add_argument("--run", nargs=2, metavar=("MODE", "FOLDER"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.run:
        run_mode(args.run[0], Path(args.run[1]))
        return 0
    with tempfile.TemporaryDirectory(prefix="station-bench-") as temporary:
        root = Path(temporary)
        os.environ["XDG_CONFIG_HOME"] = str(root / "config")  # a station key of its own
        full, half = root / "full", root / "half"
        write_sessions(full, args.sessions, args.robots)
        half.mkdir()
        for path in sorted(full.glob("*.jsonl"))[: args.sessions // 2]:
            shutil.copy2(path, half / path.name)
        print(f"{args.sessions} sessions of {args.robots} robots (30 cycles each)")
        for what in ("robot", "all"):
            name = "history R00" if what == "robot" else "history --all"
            scan, scan_peak = measured(f"files-{what}", full, root / "data")
            cold, cold_peak = measured(f"cold-{what}", full, root / "data")
            warm, warm_peak = measured(f"warm-{what}", full, root / "data")
            print(
                f"{name}: file scan {scan:.2f} s CPU ({scan_peak:.0f} MiB); "
                f"index cold {cold:.2f} s (x{cold / scan:.2f} the scan, {cold_peak:.0f} MiB); "
                f"warm {warm:.2f} s (x{warm / scan:.3f} the scan, {warm_peak:.0f} MiB; "
                f"target <= 5 s: {'met' if warm <= 5 else 'NOT met'})"
            )
        measured("cold-robot", half, root / "half-data")
        small, _ = measured("warm-robot", half, root / "half-data")
        large, _ = measured("warm-robot", full, root / "data")
        doubling = large / max(small, 0.01)
        print(
            f"warm history R00: {args.sessions // 2} sessions {small:.2f} s, "
            f"{args.sessions} sessions {large:.2f} s: x{doubling:.2f} per doubling "
            f"(target <= 2.5: {'met' if doubling <= 2.5 else 'NOT met'})"
        )
    print(f"load: {os.getloadavg()[0]:.2f} (1 min), {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("STATION_PROCEDURES", "")
    sys.exit(main())
