"""Shared pieces of the TUI tests: the simulated fixture on a real pty, and walking the screens
by keyboard in Pilot (set-up, checklist, cycles)."""

from __future__ import annotations

import time
import unicodedata
from collections.abc import Callable, Iterator
from types import SimpleNamespace

import pytest
from helpers import odd_figures
from textual import events
from textual.keys import REPLACED_KEYS, _character_to_key, _get_unicode_name_from_key
from textual.widgets import Input, Select

from station.tui.instruments import DemoFixture, start_demo_fixture


@pytest.fixture
def fixture_pty() -> Iterator[DemoFixture]:
    """The demo's seeded simulated fixture (x fine, y off-centre and noisy, z warming up, so
    a control-chart rule fires) on a real pseudo-terminal."""
    fixture = start_demo_fixture(1990)
    try:
        yield fixture
    finally:
        fixture.stop()


@pytest.fixture
def alarming_fixture() -> Iterator[DemoFixture]:
    """The demo's fixture with a seed whose first 30 cycles raise live alarms once the
    control limits freeze (after 25 cycles)."""
    fixture = start_demo_fixture(42)
    try:
        yield fixture
    finally:
        fixture.stop()


async def wait_until(pilot, condition: Callable[[], object], timeout: float = 10.0) -> None:
    """Let the app run until ``condition()`` is true; fail after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(
                f"timed out after {timeout} s waiting for {condition}; {app_state(pilot.app)}"
            )
        await pilot.pause(0.02)


def app_state(app) -> str:
    """What a failed wait saw: the screen stack, the focused widget and the runner's step
    (a flake under load then says where it stood, not just that it timed out)."""
    stack = " > ".join(type(screen).__name__ for screen in app.screen_stack)
    focused = app.screen.focused
    runner = getattr(app, "runner", None)
    step = "no runner"
    if runner is not None:
        state = runner.state()
        current = state.current
        step = f"step {current.index} {current.kind}" if current is not None else "no step"
        step += f", action {state.action.kind}"
    return f"screens {stack}; focus {focused!r}; {step}"


def key_event(key: str) -> events.Key:
    """The key event for ``key``, built as ``pilot.press`` builds it ("a", ".", "-", "tab",
    "shift+tab", "backspace", "enter"), with the character a terminal sends for it."""
    if len(key) == 1 and not key.isalnum():
        key = _character_to_key(key)  # "." is "full_stop"
    try:
        character = unicodedata.lookup(_get_unicode_name_from_key(REPLACED_KEYS.get(key, key)))
    except KeyError:
        character = key if len(key) == 1 else None
    return events.Key(key, character)


async def burst(pilot, *keys: str) -> None:
    """Type ``keys`` as one burst (a fast typist, a paste over SSH): every key is queued
    before the app takes the first, as the terminal driver queues the keys of one read.
    (``pilot.press`` waits for the app to be idle after each key, which hides what goes wrong
    in between.) Returns once the screen has taken them."""
    app = pilot.app
    for key in keys:
        event = key_event(key)
        event.set_sender(app)
        app.post_message(event)
    # Each key is handed from the app to a widget's queue, and may bubble on from there.
    for _ in range(3):
        await pilot.pause()


async def open_setup(pilot, robot: str, port: str, operator: str = "operator-1") -> None:
    """Home → ``n`` → the set-up, with the robot typed and the port and operator filled in."""
    from station.tui.screens.setup import SetupScreen

    app = pilot.app
    await pilot.press("n")
    await wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
    await pilot.pause()
    await pilot.press(*robot)
    app.screen.query_one("#port", Input).value = port
    app.screen.query_one("#operator", Input).value = operator
    app.screen.query_one("#map", Input).value = "1=x,2=y,3=z"
    # The static simulator shows a new rest position at every poll: Space paces its cycles.
    app.screen.query_one("#trigger", Select).value = "poll"


async def walk_checklist(pilot) -> int:
    """Enter on each checklist step until the dashboard is up; returns the steps done."""
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.dashboard import DashboardScreen

    app = pilot.app
    await wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen | DashboardScreen))
    done = 0
    # Ask the runner, not the screen: the screen follows the runner's state at the next redraw,
    # and an Enter pressed in between would land on the dashboard and confirm nothing.
    while app.runner.state().action.kind in ("confirm", "input", "zero"):
        await wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        before = app.runner.state().current.index
        await pilot.press("enter")
        await wait_until(pilot, lambda before=before: app.runner.state().current.index != before)
        done += 1
    await wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
    await pilot.pause()
    return done


async def capture_one(pilot) -> None:
    """Space on the dashboard, and wait until the cycle is recorded and drawn."""
    app = pilot.app
    dashboard = app.screen
    count = len(app.runner.state().cycles)
    await pilot.press("space")
    await wait_until(
        pilot, lambda: len(app.runner.state().cycles) > count and not dashboard.capturing
    )


def screen_text(app) -> str:
    """What the terminal shows, row by row."""
    return "\n".join(
        "".join(segment.text for segment in strip)
        for strip in app.screen._compositor.render_strips()
    )


@pytest.fixture
def tui() -> SimpleNamespace:
    """The walking helpers above, for the tests of this folder."""
    return SimpleNamespace(
        wait_until=wait_until,
        open_setup=open_setup,
        walk_checklist=walk_checklist,
        capture_one=capture_one,
        burst=burst,
        screen_text=screen_text,
        odd_figures=odd_figures,
    )
