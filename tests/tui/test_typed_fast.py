"""Issue 26, item 2: keys typed in one burst (a fast typist, a paste over SSH) were lost or
landed in the wrong field. At the pendant step ``26.650 Tab 20.062 Tab -32.068`` gave
Y = ``20.062-32068`` and an empty Z, and Tab past Z took the focus to the step list, where
digits vanish; at the gauge check's set-up step, '30' typed after backspaces came out wrong.
Every key lands, in order, in the field it was typed for; Enter moves to the next field, and
the screen says so. Each burst is queued whole before the app takes its first key
(``tui.burst``), against the demo's simulators."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from textual.widgets import Input, Static

from station.session.model import load_session
from station.tui.app import DemoPort, StationApp, StationConfig
from station.tui.instruments import DemoLab


@pytest.fixture
def lab() -> Iterator[DemoLab]:
    demo = DemoLab(7, stroke_points=80)
    try:
        yield demo
    finally:
        demo.stop()


def demo_app(folder: Path, lab: DemoLab, procedure: str) -> StationApp:
    fixture = lab.fixture(procedure)
    port = DemoPort(
        url=fixture.url,
        protocol=fixture.protocol,
        channel_map=dict(fixture.channel_map),
        procedure=procedure,
        trigger=fixture.trigger,
        count=2,
    )
    return StationApp(
        StationConfig(sessions_dir=folder, sessions_reason="test folder", demo=port, demo_lab=lab)
    )


async def start(pilot, tui) -> None:
    """The demo's pre-filled set-up started: the checklist's first step is up."""
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.setup import SetupScreen

    app = pilot.app
    await pilot.press("n")
    await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
    await pilot.pause()
    await pilot.press("f2")
    await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))


async def walk_to_the_fields(pilot, tui) -> None:
    """Enter on each step up to the first input step, whose first field has the focus."""
    from station.tui.screens.checklist import ChecklistScreen

    app = pilot.app
    while app.runner.state().current.kind != "input":
        before = app.runner.state().current.index
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        await tui.wait_until(pilot, lambda: not app.screen.busy)
        await pilot.press("enter")
        await tui.wait_until(
            pilot, lambda before=before: app.runner.state().current.index != before
        )
    await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
    first = app.runner.state().action.fields[0].name
    await tui.wait_until(pilot, lambda: focused_id(app) == f"input-{first}")


def field_values(app: StationApp) -> dict[str, str]:
    return {str(field.id): field.value for field in app.screen.query("#step-inputs Input")}


def focused_id(app: StationApp) -> str:
    return str(getattr(app.screen.focused, "id", None))


async def test_the_pendants_three_values_typed_in_one_burst_land_in_their_fields(
    tmp_path: Path, lab: DemoLab, tui
) -> None:
    app = demo_app(tmp_path, lab, "relative_accuracy")
    async with app.run_test(size=(80, 24)) as pilot:
        await start(pilot, tui)
        await walk_to_the_fields(pilot, tui)
        await tui.burst(pilot, *"26.650", "tab", *"20.062", "tab", *"-32.068")
        assert field_values(app) == {
            "input-x": "26.650",
            "input-y": "20.062",
            "input-z": "-32.068",
        }
        assert focused_id(app) == "input-z"
        # The screen says what Enter and Tab do in the fields.
        says = str(app.screen.query_one("#step-action", Static).render())
        assert "Enter or Tab goes to the next field" in says
        assert "Enter in the last one saves them" in says
        # Tab past Z comes back to X (the step list takes no digits), Shift+Tab goes back.
        await tui.burst(pilot, "tab")
        assert focused_id(app) == "input-x"
        await tui.burst(pilot, "shift+tab")
        assert focused_id(app) == "input-z"
        # Enter in the last field saves, with every key typed before it.
        await tui.burst(pilot, "enter")
        await tui.wait_until(pilot, lambda: app.runner.state().current.kind != "input")
        path = app.runner.path
        app.runner.interrupt("test over")
    session = load_session(path, recover=False)
    assert session.input_events[0]["values"] == {"x": 26.65, "y": 20.062, "z": -32.068}


async def test_backspaces_and_enter_in_a_burst_at_the_gauge_checks_set_up_step(
    tmp_path: Path, lab: DemoLab, tui
) -> None:
    from station.tui.screens.dialogs import TextPrompt

    app = demo_app(tmp_path, lab, "gauge_check")
    async with app.run_test(size=(80, 24)) as pilot:
        await start(pilot, tui)
        # A note first: its dialog's field keeps the order of the keys too.
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, TextPrompt))
        await tui.burst(pilot, *"cube slipt", "backspace", "backspace", *"pped")
        assert app.screen.query_one(Input).value == "cube slipped"
        await tui.burst(pilot, "enter")
        await tui.wait_until(pilot, lambda: not isinstance(app.screen, TextPrompt))
        await walk_to_the_fields(pilot, tui)
        assert focused_id(app) == "input-gauge"
        await tui.burst(
            pilot,
            *"mit-1",
            "enter",
            *"25",
            "backspace",
            "backspace",
            *"30",
            "enter",
            *"0.01",
            "enter",
            *"2027-01-31",
        )
        assert field_values(app) == {
            "input-gauge": "mit-1",
            "input-reference": "30",
            "input-tolerance": "0.01",
            "input-calibration_due": "2027-01-31",
        }
        await tui.burst(pilot, "enter")
        await tui.wait_until(pilot, lambda: app.runner.state().current.kind != "input")
        path = app.runner.path
        app.runner.interrupt("test over")
    session = load_session(path, recover=False)
    assert any(note.get("text") == "cube slipped" for note in session.notes)
    assert session.input_events[0]["values"] == {
        "gauge": "mit-1",
        "reference": 30.0,
        "tolerance": 0.01,
        "calibration_due": "2027-01-31",
    }


async def test_enter_in_a_set_up_field_in_a_burst_moves_on_before_the_next_keys(
    tmp_path: Path, tui
) -> None:
    from station.tui.screens.setup import SetupScreen

    app = StationApp(StationConfig(sessions_dir=tmp_path, sessions_reason="test folder"))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        await tui.wait_until(pilot, lambda: focused_id(app) == "robot")
        # The operator field is pre-filled (the login name) and selected as it takes the
        # focus: what is typed there replaces it.
        await tui.burst(pilot, *"r6", "enter", *"ana", "tab")
        assert app.screen.query_one("#robot", Input).value == "r6"
        assert app.screen.query_one("#operator", Input).value == "ana"
        assert focused_id(app) == "procedure"
