"""Heavy imports happen once, on one thread, before the threads that need them start (issue 27,
finding 10): under load ``station capture`` exited 70 when the engine's warm-up thread imported
scipy while another thread imported it too."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from .conftest import REPO, capture_args

# Runs ``station capture`` in a fresh interpreter (scipy not yet imported) and notes, for every
# thread started, whether scipy was fully imported by then.
WATCHED_CAPTURE = r"""
import json, sys, threading
started = []
original = threading.Thread.start
def start(self):
    started.append((self.name, "scipy.stats" in sys.modules and "scipy.signal" in sys.modules))
    original(self)
threading.Thread.start = start
from station.cli import main
code = main(sys.argv[1:])
print("THREADS " + json.dumps(started), file=sys.stderr)
sys.exit(code)
"""


def test_scipy_is_imported_before_the_engines_threads_start(simulators, tmp_path):
    url = simulators(10).url
    env = {**os.environ, "STATION_PROCEDURES": ""}
    done = subprocess.run(
        [sys.executable, "-c", WATCHED_CAPTURE, "capture", *capture_args(url, tmp_path, 25)],
        capture_output=True,
        text=True,
        cwd=REPO,
        env=env,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    line = next(x for x in done.stderr.splitlines() if x.startswith("THREADS "))
    started = dict(json.loads(line.removeprefix("THREADS ")))
    for name in ("runner intake", "runner analysis", "station capture"):
        assert started[name], f"thread {name!r} started before scipy was imported"
    assert not any("warm-up" in name for name in started)  # no second importer racing
