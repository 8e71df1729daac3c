"""Settings and isolation for the whole suite.

Every test starts from the same process state, whatever ran before it and on whichever worker:

* its own home, config, data, state and cache folders (``HOME`` and ``XDG_*``), so the signing
  key, the remembered set-up, the baselines, the default sessions folder and the gauge register
  (``STATION_GAUGES``) are the test's alone, for it and every process it starts;
* none of the developer's ``STATION_*`` settings, nor ``NO_COLOR``;
* temporary folders on tmpfs (``/dev/shm``), where durability is not what a test can see;
* every station module imported once (so the procedure loader knows the methods, which
  ``station.methods`` tells it); the methods and the step kinds are explicit tuples, and a site's
  own come from entry points scanned per ``sys.path``, so a test that installs one (on its own
  ``sys.path``) leaves nothing behind;
* no simulated set-up left followed from an earlier test (``station.tui.instruments``).
"""

from __future__ import annotations

import importlib
import os
import pkgutil
import signal
import tempfile
from collections.abc import Iterator

import pytest
from hypothesis import settings

from tests.properties import THOROUGH

pytest_plugins = ["pytester"]

# The long property run: each property test's own count (tests/properties.py), and 1000
# examples where a test names none.
settings.register_profile(THOROUGH, max_examples=1000)

# A shell that starts the suite as a background job (`pytest &`, some CI runners) sets SIGINT
# to "ignored", and every subprocess a test starts would inherit that: the tests that press
# Ctrl-C on `station read` or `station simulate` would then wait forever. Python's own handler
# here makes the children start with the default action again (a caught signal is reset on
# exec; an ignored one is not).
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


# Temporary folders (every tmp_path, and those of the processes the tests start) in memory, on
# tmpfs: a session's fsync there costs nothing, and no test can tell a disk from it (a process
# killed with SIGKILL leaves its written data in either; the disk-limit tests mount their own
# small tmpfs). A TMPDIR the developer set is kept.
SHARED_MEMORY = "/dev/shm"
if "TMPDIR" not in os.environ and os.access(SHARED_MEMORY, os.W_OK | os.X_OK):
    os.environ["TMPDIR"] = SHARED_MEMORY
    tempfile.tempdir = None  # read TMPDIR again


def _import_every_station_module() -> None:
    """Import all of ``station`` once (``station.methods`` among it tells the procedure loader
    the methods' needs), as a running station has by the time it loads a procedure."""
    import station

    for module in pkgutil.walk_packages(station.__path__, "station."):
        if not module.name.endswith("__main__"):
            importlib.import_module(module.name)


_import_every_station_module()

from station.tui import instruments as _demo_instruments  # noqa: E402

PRIVATE_ENVIRONMENT = ("STATION_SESSIONS", "STATION_PROCEDURES", "STATION_THEME", "NO_COLOR")
"""The developer's settings that would change what a test sees; unset for every test."""


def _stop_followed_fixtures() -> None:
    for fixture in list(_demo_instruments._RUNNING.values()):
        fixture.stop()
    _demo_instruments._RUNNING.clear()


@pytest.fixture(scope="session", autouse=True)
def _matplotlib_folder(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    """One matplotlib folder (its font cache) per worker, outside the real home; built once,
    not in every test's fresh home."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MPLCONFIGDIR", str(tmp_path_factory.mktemp("matplotlib")))
        yield


@pytest.fixture(autouse=True)
def _private_process_state(
    tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch
) -> Iterator[None]:
    """The test's own folders and settings and no followed simulator (see the module); set
    for the test and every process it starts. The folders are beside the test's ``tmp_path``,
    not in it, so a test that lists its ``tmp_path`` sees only its own files."""
    home = tmp_path_factory.mktemp("home")
    monkeypatch.setenv("HOME", str(home))
    for variable, folder in (
        ("XDG_CONFIG_HOME", ".config"),
        ("XDG_DATA_HOME", ".local/share"),
        ("XDG_STATE_HOME", ".local/state"),
        ("XDG_CACHE_HOME", ".cache"),
    ):
        monkeypatch.setenv(variable, str(home / folder))
    # Named, so a test can read the register a finished gauge check wrote.
    monkeypatch.setenv("STATION_GAUGES", str(home / "gauges.json"))
    for variable in PRIVATE_ENVIRONMENT:
        monkeypatch.delenv(variable, raising=False)
    _stop_followed_fixtures()
    yield
    _stop_followed_fixtures()
