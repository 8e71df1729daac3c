"""Issue 26, item 4: after a dropped link (the demo that ran the session is gone, with its
simulator), the next demo's Resume reopened the recorded ``/dev/pts/N``, which another program
now held: "connected", and never a frame. The demo resumes on its own running simulator; the
recorded pseudo-terminal, typed back in, is refused with a sentence under the port."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import Terminal, reopen_number
from textual.widgets import Input, Static

from station.session.model import load_session
from station.tui.app import DemoPort, StationApp, StationConfig
from station.tui.instruments import DemoLab


@pytest.fixture
def terminals() -> Iterator[list[Terminal]]:
    """The pseudo-terminals the test opens as other programs; closed after it."""
    opened: list[Terminal] = []
    yield opened
    for terminal in opened:
        terminal.close()


def demo_app(folder: Path, lab: DemoLab) -> StationApp:
    """The demo's app on ``lab``'s repeatability simulator (polled: Space captures)."""
    fixture = lab.fixture("repeatability")
    port = DemoPort(
        url=fixture.url,
        protocol=fixture.protocol,
        channel_map=dict(fixture.channel_map),
        trigger=fixture.trigger,
        count=30,
    )
    return StationApp(
        StationConfig(
            sessions_dir=folder,
            sessions_reason="test folder",
            demo=port,
            demo_lab=lab,
            capture_timeout=3.0,
        )
    )


async def test_the_demo_resumes_on_its_own_simulator_not_the_recorded_number(
    tmp_path: Path, tui, terminals: list[Terminal]
) -> None:
    from station.tui.screens.dashboard import DashboardScreen
    from station.tui.screens.setup import SetupScreen

    first = DemoLab(1990)
    try:
        app = demo_app(tmp_path, first)
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("n")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
            await pilot.press("f2")
            await tui.walk_checklist(pilot)
            await tui.capture_one(pilot)
            recorded = app.runner.state().instruments[0].url
            app.runner.interrupt("SIGHUP")  # the link dropped: the demo ends
    finally:
        first.stop()
    # The dropped demo's pseudo-terminal number goes to the next program (a new login).
    someone = reopen_number(recorded, terminals)
    second = DemoLab(1990)
    try:
        app = demo_app(tmp_path, second)
        own = second.fixture("repeatability").url
        assert own != recorded
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.pause()
            await pilot.press("r")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
            await pilot.pause()
            port = app.screen.query_one("#port", Input)
            assert port.value == own
            hint = str(app.screen.query_one("#setup-hint", Static).render())
            assert "resumes on its own running simulator" in hint
            # The recorded number, typed back in, is someone else's now: refused, said why.
            port.value = someone.path
            await pilot.press("f2")
            error = app.screen.query_one("#port-error", Static)
            await tui.wait_until(pilot, lambda: "not the pseudo-terminal" in str(error.render()))
            assert isinstance(app.screen, SetupScreen) and app.runner is None
            port.value = own
            await pilot.press("f2")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
            await pilot.pause()
            assert [state.url for state in app.runner.state().instruments] == [own]
            await tui.capture_one(pilot)  # the simulator answers: a cycle is recorded
            path = app.runner.path
            app.runner.interrupt("test over")
    finally:
        second.stop()
    session = load_session(path, recover=False)
    assert sorted(session.cycles) == [1, 2]
    assert [event["type"] for event in session.events].count("resume") == 1
