"""Benchmark: ``station verify`` on a long session file against ``sha256sum`` (issue 23, item 2).

Run on demand (not part of the test suite):

    .venv/bin/python tests/benchmarks/bench_verify.py [--cycles N]

Writes a signed, finished session of N cycles of three channels (default 100,000: about 60 MB),
with a reject, a note, an alarm and its acknowledgement every thousand cycles, then measures in
the same run, each the best of a few fresh processes: ``sha256sum FILE`` (the baseline: reading
and hashing the bytes once) and ``station verify FILE``, as CPU seconds (user + system) and
peak resident memory (the child's ``ru_maxrss``). Targets: verify <= 10x sha256sum's CPU, in
<= 100 MB. A second file of twice the cycles gives the scaling ratio per doubling (target
<= 2.5; about 2 is linear) and shows that the memory stays flat.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

PYTHON = sys.executable
RUNS = 3
TIME = "/usr/bin/time"


def write_session(folder: Path, cycles: int) -> Path:
    """A finished, signed session of ``cycles`` reading sets, written without the journal's
    fsync per event (the bytes are the journal's: same encoding, chain and signature)."""
    from station.procedures import discover_procedures
    from station.run import PortSetup, SessionSetup
    from station.session.journal import SessionWriter
    from station.session.lines import encode_line, line_hash
    from station.session.signing import finish_message, station_key

    procedure = discover_procedures(use_env=False).get("repeatability")
    port = PortSetup("loop://", "mitutoyo", {"1": "x", "2": "y", "3": "z"})
    header = SessionSetup(procedure, "bench", "", (port,)).header_fields()
    with SessionWriter.create(folder, header) as writer:
        writer.append("step", step="cycles", action="started")
        path = writer.path
    last = path.read_bytes().rstrip(b"\n").rsplit(b"\n", 1)[-1]
    session_id = json.loads(path.read_bytes().split(b"\n", 1)[0])["session"]
    prev, seq = line_hash(last), 1
    with path.open("ab") as out:

        def write(record: dict) -> None:
            nonlocal prev, seq
            seq += 1
            moment = f"2026-11-23T08:{seq % 60:02d}:00.000000Z"
            line = encode_line({"seq": seq, "t": moment, **record}, prev)
            out.write(line + b"\n")
            prev = line_hash(line)

        for cycle in range(1, cycles + 1):
            write(
                {
                    "type": "reading",
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
            )
            if cycle % 1000 == 0:
                write({"type": "reject", "cycle": cycle - 1, "reason": "bumped the fixture"})
                write({"type": "note", "text": f"cycle {cycle}: coffee"})
                write({"type": "alarm", "channel": "x", "rule": "report-1", "cycles": [cycle]})
                write({"type": "ack", "alarm": seq, "cause": "other", "text": "checked"})
        key = station_key()
        assert key is not None
        signature = key.sign(finish_message(session_id, prev, seq + 1))
        write({"type": "finish", "signature": signature})
    return path


def cpu_and_memory(command: list[str]) -> tuple[float, float]:
    """The least CPU seconds (user + system) of ``RUNS`` runs of ``command``, and the largest
    peak resident memory of them in MiB, as ``/usr/bin/time`` reports them: a small process
    that starts the command, so the peak is the command's own (a child forked from this
    Python process would report this process's size as its own)."""
    best, peak = float("inf"), 0.0
    for _ in range(RUNS):
        done = subprocess.run(
            [TIME, "-f", "%U %S %M", *command],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            check=True,
        )
        user, system, kib = done.stderr.split()[-3:]
        best = min(best, float(user) + float(system))
        peak = max(peak, int(kib) / 1024)
    return best, peak


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=100_000)
    args = parser.parse_args()
    sha256sum = shutil.which("sha256sum")
    if sha256sum is None:
        raise SystemExit("sha256sum is needed as the baseline")
    with tempfile.TemporaryDirectory(prefix="station-bench-") as folder:
        os.environ["XDG_CONFIG_HOME"] = folder  # a station key of the benchmark's own
        files = []
        for size in (10, args.cycles, 2 * args.cycles):
            (Path(folder) / str(size)).mkdir()
            files.append(write_session(Path(folder) / str(size), size))
        start_up, _ = cpu_and_memory([PYTHON, "-m", "station", "verify", str(files.pop(0))])
        verify_cpu = []
        for path in files:
            base, base_peak = cpu_and_memory([sha256sum, str(path)])
            ours, peak = cpu_and_memory([PYTHON, "-m", "station", "verify", str(path)])
            verify_cpu.append(ours)
            ratio = ours / max(base, 0.01)  # /usr/bin/time counts in hundredths
            print(
                f"{path.stat().st_size / 1e6:6.1f} MB session: sha256sum {base:.3f} s CPU "
                f"({base_peak:.0f} MiB); station verify {ours:.3f} s CPU ({peak:.0f} MiB): "
                f"x{ratio:.1f} (target <= 10x: {'met' if ratio <= 10 else 'NOT met'}; "
                f"memory target <= 100 MiB: {'met' if peak <= 100 else 'NOT met'})"
            )
        small, large = (max(c - start_up, 0.01) for c in verify_cpu)
        doubling = large / small
        print(
            f"start-up (a 10-cycle session) {start_up:.3f} s; "
            f"per doubling of the session x{doubling:.2f} "
            f"(target <= 2.5: {'met' if doubling <= 2.5 else 'NOT met'})"
        )
    print(f"load: {os.getloadavg()[0]:.2f} (1 min), {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("STATION_PROCEDURES", "")
    sys.exit(main())
