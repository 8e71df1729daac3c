"""A writer that hits the file-size limit (RLIMIT_FSIZE) fails clearly and loses nothing.

The child is a real process with a real limit: it appends readings and prints each seq only
after ``append`` has returned (acknowledged); the parent then loads the file and finds them all.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

from station.session.model import load_session
from station.session.verify import verify_session

CHILD = textwrap.dedent(
    """
    import resource, sys
    sys.path.insert(0, sys.argv[2])
    from child_helpers import header, reading
    from station.commands._remedies import CLI_REMEDIES
    from station.errors import StationError
    from station.session.journal import SessionWriter

    import signal
    # Restore the kernel's default (death) for SIGXFSZ, as an embedding program might: the
    # writer must set it back to ignored so the write fails with EFBIG instead.
    signal.signal(signal.SIGXFSZ, signal.SIG_DFL)
    limit = int(sys.argv[3])
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    writer = SessionWriter.create(sys.argv[1], header())
    print("path", writer.path, flush=True)
    try:
        for cycle in range(1, 100_000):
            event = writer.append("reading", **reading(cycle))
            print("ack", event["seq"], cycle, flush=True)
    except StationError as error:
        print("error", error.worded(CLI_REMEDIES), flush=True)
        sys.exit(3)
    """
)

HELPER = textwrap.dedent(
    """
    from station.procedures import discover_procedures
    from station.run import PortSetup, SessionSetup

    def header():
        procedure = discover_procedures(use_env=False).get("repeatability")
        port = PortSetup("loop://", "mitutoyo", {"1": "x", "2": "y", "3": "z"})
        return SessionSetup(procedure, "r2", "ana", (port,)).header_fields()

    def reading(cycle):
        return {
            "cycle": cycle,
            "step": "cycles",
            "channels": {c: {"value": 0.0001 * (cycle % 7), "raw": "x" * 40} for c in "xyz"},
        }
    """
)


def test_the_file_size_limit_is_a_clear_error_and_nothing_acknowledged_is_lost(
    tmp_path: Path,
) -> None:
    (tmp_path / "child_helpers.py").write_text(HELPER)
    limit = 20_000
    child = subprocess.run(
        [sys.executable, "-c", CHILD, str(tmp_path / "sessions"), str(tmp_path), str(limit)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert child.returncode == 3, child.stderr  # not killed by SIGXFSZ, not a traceback
    lines = child.stdout.splitlines()
    path = Path(lines[0].split(" ", 1)[1])
    acknowledged = [int(line.split()[1]) for line in lines if line.startswith("ack")]
    cycles = [int(line.split()[2]) for line in lines if line.startswith("ack")]
    error = lines[-1]
    assert len(acknowledged) > 10
    assert error.startswith("error the file-size limit was reached")
    assert f"nothing was lost up to cycle {cycles[-1]}" in error
    assert "station capture --resume" in error  # the command line's wording of the remedy
    assert path.stat().st_size <= limit

    session = load_session(path)
    assert session.torn is None  # the writer cut its partial line itself
    assert [event["seq"] for event in session.events] == acknowledged
    assert sorted(session.cycles) == cycles
    assert verify_session(path).ok
