"""Benchmark: ``station analyze`` end to end on a 1,000,000-row, three-channel CSV (issues 12
and 23).

Run on demand (not part of the test suite):

    .venv/bin/python tests/benchmarks/bench_analyze_e2e.py [--rows N] [--channels C]
        [--scaling-rows N] [--memory-rows N]

Every figure is CPU seconds (user + system), the least of a few runs (the machine is shared),
measured in the same run as its baseline:

* whole process: the bare baseline ``python -c "import numpy; numpy.loadtxt(F, ...)"`` and
  ``station analyze F --json --lsl ... --usl ...`` (stdout to a file), with the peak resident
  memory of each (``/usr/bin/time``); target <= 4x the baseline's CPU.
* in process: :func:`station.analysis.summary.analyze` of the same readings with every
  figure worked out (the checks of normality, autocorrelation and drift are computed on first
  use), then the JSON document of it (every alarm, as ``--json`` prints it); target analyze
  <= 1 s.
* scaling: ``station analyze`` of a periodic signal that raises an alarm at nearly every
  point (the issue's quadratic case) on ``--scaling-rows`` rows and twice as many, start-up
  (an 8-row file) subtracted; about 2 per doubling is linear, 4 quadratic; target <= 2.5.

``--memory-rows`` (e.g. 10000000) also reports the peak resident memory of ``station analyze``
on that many rows (target <= 2 GB).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

PYTHON = sys.executable
RUNS = 3
TIME = "/usr/bin/time"
LIMITS = ["--lsl", "-0.001", "--usl", "0.001", "--resolution", "0.0001"]


def write_csv(path: Path, rows: int, channels: int = 1, seed: int = 1990) -> None:
    """Gauge-like readings (0.0001 steps), one column per channel (x, y, z, ...), in blocks."""
    rng = np.random.default_rng(seed)
    names = "xyzuvw"[:channels]
    with path.open("w") as out:
        out.write(",".join(names) + "\n")
        block = 1_000_000
        for start in range(0, rows, block):
            values = np.round(rng.normal(0.0, 0.0003, (min(block, rows - start), channels)), 4)
            np.savetxt(out, values, fmt="%.4f", delimiter=",")


def write_periodic_csv(path: Path, rows: int) -> None:
    """Three channels of periods 11, 7 and 5 steps: a run rule fires at nearly every point."""
    i = np.arange(rows)
    table = np.column_stack([(i % 11 - 5) * 1e-4, (i % 7 - 3) * 1e-4, (i % 5 - 2) * 1e-4])
    np.savetxt(path, table, fmt="%.4f", delimiter=",", header="x,y,z", comments="")


def cpu_and_memory(command: list[str], output: Path | None = None) -> tuple[float, float]:
    """The least CPU seconds of ``RUNS`` runs of ``command`` (stdout to ``output``) and the
    largest peak resident memory in MiB, as ``/usr/bin/time`` reports them for the command
    alone."""
    best, peak = float("inf"), 0.0
    for _ in range(RUNS):
        with open(output or os.devnull, "w") as out:
            done = subprocess.run(
                [TIME, "-f", "%U %S %M", *command],
                stdout=out,
                stderr=subprocess.PIPE,
                text=True,
                check=True,
            )
        user, system, kib = done.stderr.split()[-3:]
        best = min(best, float(user) + float(system))
        peak = max(peak, int(kib) / 1024)
    return best, peak


def analyze_command(table: Path) -> list[str]:
    return [PYTHON, "-m", "station", "analyze", str(table), "--json", *LIMITS]


def in_process(table: Path) -> tuple[float, float, int]:
    """CPU seconds of analyze() on the table's readings and of its JSON document, and the
    number of alarms in the document (the least of ``RUNS`` runs)."""
    from station.analysis.capability import SpecLimits
    from station.analysis.diagnostics import import_scipy
    from station.analysis.document import to_json
    from station.analysis.summary import AnalysisConfig, analyze
    from station.session.tables import read_table

    import_scipy()
    channels = read_table(table).channels
    config = AnalysisConfig(default_limits=SpecLimits(-0.001, 0.001), resolution=0.0001)
    best_analysis = best_document = float("inf")
    alarms = 0
    for _ in range(RUNS):
        start = time.process_time()
        analysis = analyze(channels, config)
        for channel in analysis.channels.values():
            # Worked out on first use: counted here, where they were computed before.
            channel.normality, channel.autocorrelation, channel.drift  # noqa: B018
        middle = time.process_time()
        document = json.dumps(to_json(analysis))
        end = time.process_time()
        best_analysis = min(best_analysis, middle - start)
        best_document = min(best_document, end - middle)
        alarms = document.count('"rule_name"')
    return best_analysis, best_document, alarms


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--channels", type=int, default=3)
    parser.add_argument("--scaling-rows", type=int, default=20_000)
    parser.add_argument("--memory-rows", type=int, default=0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="station-bench-") as folder:
        table = Path(folder) / "readings.csv"
        write_csv(table, args.rows, args.channels)
        output = Path(folder) / "out.json"
        baseline, base_peak = cpu_and_memory(
            [PYTHON, "-c", f"import numpy; numpy.loadtxt({str(table)!r}, skiprows=1, ndmin=2, "
             "delimiter=',')"]
        )  # fmt: skip
        ours, peak = cpu_and_memory(analyze_command(table), output)
        size = output.stat().st_size
        print(
            f"rows: {args.rows:,} x {args.channels} channels "
            f"({table.stat().st_size / 1e6:.1f} MB CSV)"
        )
        print(f"bare numpy.loadtxt process: {baseline:.2f} s CPU, {base_peak:.0f} MiB")
        print(
            f"station analyze --json:     {ours:.2f} s CPU, {peak:.0f} MiB "
            f"(JSON {size / 1e6:.1f} MB)"
        )
        ratio = ours / baseline
        print(f"ratio: {ratio:.2f}x  (target <= 4x: {'met' if ratio <= 4 else 'NOT met'})")
        analysis, document, alarms = in_process(table)
        print(
            f"in process: analyze() {analysis:.2f} s CPU (target <= 1 s: "
            f"{'met' if analysis <= 1 else 'NOT met'}); its JSON document, {alarms:,} alarms, "
            f"{document:.2f} s"
        )

        small, large, tiny = (Path(folder) / f"periodic-{n}.csv" for n in ("1", "2", "0"))
        write_periodic_csv(small, args.scaling_rows)
        write_periodic_csv(large, 2 * args.scaling_rows)
        write_periodic_csv(tiny, 8)
        start_up, _ = cpu_and_memory(analyze_command(tiny))
        once, _ = cpu_and_memory(analyze_command(small))
        twice, _ = cpu_and_memory(analyze_command(large))
        doubling = max(twice - start_up, 0.05) / max(once - start_up, 0.05)
        print(
            f"scaling, periodic signal: {args.scaling_rows:,} rows {once:.2f} s CPU, "
            f"{2 * args.scaling_rows:,} rows {twice:.2f} s (start-up {start_up:.2f} s): "
            f"x{doubling:.2f} per doubling (target <= 2.5: "
            f"{'met' if doubling <= 2.5 else 'NOT met'})"
        )
        if args.memory_rows:
            big = Path(folder) / "big.csv"
            write_csv(big, args.memory_rows)
            _, big_peak = cpu_and_memory(analyze_command(big))
            print(
                f"{args.memory_rows:,} rows: peak resident memory {big_peak:.0f} MiB "
                f"(target <= 2048 MiB: {'met' if big_peak <= 2048 else 'NOT met'})"
            )
    print(f"load: {os.getloadavg()[0]:.2f} (1 min), {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("STATION_PROCEDURES", "")
    sys.exit(main())
