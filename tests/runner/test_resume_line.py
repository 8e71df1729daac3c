"""Issue 26, item 4: a session recorded on a pseudo-terminal (a simulator's ``/dev/pts/5``)
was resumed after that simulator had gone, on the same path: the kernel had given the number
to another program's pseudo-terminal, which opened ("connected") and never sent a frame. A
resumed pseudo-terminal that is not the recorded device is refused with a sentence, by every
front end, before anything is written."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import Terminal, open_terminal, reopen_number, run_station

from station.errors import StationError
from station.run import PortSetup, SessionSetup, resume_setup
from station.session.journal import SessionWriter

from .conftest import DEVICE_MAP, repeatability

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def terminals() -> Iterator[list[Terminal]]:
    """The pseudo-terminals a test opens; closed after it."""
    opened: list[Terminal] = []
    yield opened
    for terminal in opened:
        terminal.close()


def session_on(url: str, folder: Path) -> Path:
    """An unfinished session file whose line is ``url`` (its header written now)."""
    setup = SessionSetup(
        procedure=repeatability(),
        robot="KSC-7",
        operator="ana",
        ports=(PortSetup(url, "mitutoyo", DEVICE_MAP),),
    )
    writer = SessionWriter.create(folder, setup.header_fields())
    writer.append("interrupted", reason="SIGHUP")
    writer.close()
    return Path(writer.path)


def test_a_closed_pseudo_terminals_number_now_another_programs_is_refused(tmp_path, terminals):
    simulators_line = open_terminal(terminals)
    path = session_on(simulators_line.path, tmp_path)
    # The simulator stops with the program that ran it; someone logs in and gets its number.
    terminals.remove(simulators_line)
    simulators_line.close()
    someone = reopen_number(simulators_line.path, terminals)
    before = path.read_bytes()
    with pytest.raises(StationError) as refused:
        resume_setup(path)
    sentence = refused.value.message
    assert refused.value.field == "port"
    assert sentence.startswith(f"{someone.path} is not the pseudo-terminal this session recorded")
    assert "opened at" in sentence and "name the port of the running simulator" in sentence
    # The headless command says it too, on its port option, and writes nothing.
    done = run_station("capture", "--resume", str(path), "--every", "0.01", cwd=REPO)
    assert done.returncode == 2
    assert done.stderr.startswith(f"station: --port: {someone.path} is not the pseudo-terminal")
    assert path.read_bytes() == before


def test_the_recorded_pseudo_terminal_still_open_resumes(tmp_path, terminals):
    # `station simulate` kept running in another window while the station restarted.
    line = open_terminal(terminals)
    path = session_on(line.path, tmp_path)
    assert resume_setup(path).ports[0].url == line.path


def test_another_line_named_for_the_resume_is_taken(tmp_path, terminals):
    recorded = open_terminal(terminals)
    path = session_on(recorded.path, tmp_path)
    terminals.remove(recorded)
    recorded.close()
    reopen_number(recorded.path, terminals)
    # The operator names where the simulator runs now: a pseudo-terminal opened after the
    # session, at another path, is their choice.
    elsewhere = open_terminal(terminals)
    port = PortSetup(elsewhere.path, "mitutoyo", DEVICE_MAP)
    assert resume_setup(path, ports=(port,)).ports == (port,)
    # And a simulator this process started for the session (the demo's) is its line, even at
    # the recorded number.
    port = PortSetup(recorded.path, "mitutoyo", DEVICE_MAP)
    setup = resume_setup(path, ports=(port,), own_simulators=[recorded.path])
    assert setup.ports == (port,)


def test_a_line_is_judged_by_when_the_session_last_used_it(tmp_path, terminals):
    # Begun on line G; G closed; resumed on line S (the resume event records S). G's number
    # goes to another program after that resume, and the session writes on S later still:
    # G's last use was before the resume, so the pseudo-terminal at G now is not the line.
    first = open_terminal(terminals)
    path = session_on(first.path, tmp_path)
    second = open_terminal(terminals)
    terminals.remove(first)
    first.close()
    moved = PortSetup(second.path, "mitutoyo", DEVICE_MAP)
    writer, _ = SessionWriter.resume(
        path, by="operator", instruments={"trigger": "poll", "ports": [moved.header()]}
    )
    someone = reopen_number(first.path, terminals)
    writer.append("note", text="later, on the second line", by="operator")
    writer.append("interrupted", reason="SIGHUP")
    writer.close()
    with pytest.raises(StationError, match=f"^{someone.path} is not the pseudo-terminal"):
        resume_setup(path)  # the header's line
    assert resume_setup(path, ports=(moved,)).ports == (moved,)
