"""Settings for the whole suite."""

import signal

# A shell that starts the suite as a background job (`pytest &`, some CI runners) sets SIGINT
# to "ignored", and every subprocess a test starts would inherit that: the tests that press
# Ctrl-C on `station read` or `station simulate` would then wait forever. Python's own handler
# here makes the children start with the default action again (a caught signal is reset on
# exec; an ignored one is not).
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


import pytest  # noqa: E402

# Procedure files name the methods: the loader knows them once station.methods is imported, as
# every front end and the engine do before loading one (tests load procedures directly).
import station.methods  # noqa: E402, F401


@pytest.fixture(autouse=True)
def _station_config_home(tmp_path_factory: pytest.TempPathFactory, monkeypatch) -> None:
    """Every test (and every process it starts) keeps the station's signing key and its
    remembered set-up in a temporary config folder of its own, never in the real home (and a
    set-up remembered by one test never pre-fills another's form), and its gauge register in a
    temporary file."""
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path_factory.mktemp("config-home")))
    # A gauge register of the test's own: a finished gauge check writes to it, and a new
    # session reads it; never the real one in the data folder.
    monkeypatch.setenv("STATION_GAUGES", str(tmp_path_factory.mktemp("gauges") / "gauges.json"))
