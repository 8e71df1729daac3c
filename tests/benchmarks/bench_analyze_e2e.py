"""Benchmark: ``station analyze`` end to end on a 1,000,000-row one-column CSV (issue 12).

Run on demand (not part of the test suite):

    .venv/bin/python tests/benchmarks/bench_analyze_e2e.py [--rows N] [--memory-rows N]

Each measurement is a fresh process, the best of a few runs (the machine is shared): the bare
baseline ``python -c "import numpy; numpy.loadtxt(F, skiprows=1)"`` and ``station analyze F
--json --lsl ... --usl ...`` with stdout to a file, measured in the same run. Prints both times
and their ratio; target <= 4x. ``--memory-rows`` (e.g. 10000000) also reports the peak resident
memory of ``station analyze`` on that many rows (target <= 2 GB), read from the child's
``ru_maxrss``.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

PYTHON = sys.executable
RUNS = 3


def write_csv(path: Path, rows: int, seed: int = 1990) -> None:
    """One column ``x`` of gauge-like readings (0.0001 steps), written in blocks."""
    rng = np.random.default_rng(seed)
    with path.open("w") as out:
        out.write("x\n")
        block = 1_000_000
        for start in range(0, rows, block):
            values = np.round(rng.normal(0.0, 0.0003, min(block, rows - start)), 4)
            np.savetxt(out, values, fmt="%.4f")


def best_wall_time(command: list[str], output: Path) -> float:
    """The fastest of ``RUNS`` runs of ``command`` (stdout to ``output``), in seconds."""
    times = []
    for _ in range(RUNS):
        with output.open("w") as out:
            start = time.perf_counter()
            subprocess.run(command, stdout=out, check=True)
            times.append(time.perf_counter() - start)
    return min(times)


def peak_memory(command: list[str]) -> float:
    """The peak resident set of one run of ``command``, in MiB (Linux ru_maxrss is KiB)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    subprocess.run(command, stdout=subprocess.DEVNULL, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return max(before, after) / 1024


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--memory-rows", type=int, default=0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="station-bench-") as folder:
        table = Path(folder) / "readings.csv"
        write_csv(table, args.rows)
        output = Path(folder) / "out.json"
        baseline = best_wall_time(
            [PYTHON, "-c", f"import numpy; numpy.loadtxt({str(table)!r}, skiprows=1)"], output
        )
        analyze = [
            PYTHON, "-m", "station", "analyze", str(table), "--json",
            "--lsl", "-0.001", "--usl", "0.001", "--resolution", "0.0001",
        ]  # fmt: skip
        ours = best_wall_time(analyze, output)
        size = output.stat().st_size
        print(f"rows: {args.rows:,}  ({table.stat().st_size / 1e6:.1f} MB CSV)")
        print(f"bare numpy.loadtxt process: {baseline:.3f} s")
        print(f"station analyze --json:     {ours:.3f} s  (JSON {size / 1e6:.2f} MB)")
        ratio = ours / baseline
        print(f"ratio: {ratio:.2f}x  (target <= 4x: {'met' if ratio <= 4 else 'NOT met'})")
        if args.memory_rows:
            big = Path(folder) / "big.csv"
            write_csv(big, args.memory_rows)
            analyze[4] = str(big)
            peak = peak_memory(analyze)
            print(
                f"{args.memory_rows:,} rows: peak resident memory {peak:.0f} MiB "
                f"(target <= 2048 MiB: {'met' if peak <= 2048 else 'NOT met'})"
            )
    return 0


if __name__ == "__main__":
    os.environ.setdefault("STATION_PROCEDURES", "")
    sys.exit(main())
