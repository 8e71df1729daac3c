"""``station demo --autopilot``: walk the procedure by itself, through the operator's own actions.

Each move is what a key would do on the screen in front (Enter on the home screen's first new
session, F2 on the set-up, Enter on each checklist step, typing what the simulated set-up shows
at an input step (the teach pendant's X, Y, Z, a master's size), Space for each cycle or
capture, ``r`` with a reason once, streaming the strokes of a linearity run, ``f`` at the end),
at a watchable pace, and the walk stops on the summary. Nothing
is faked: the runner, the instruments and the session file are the real ones.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

from textual.widgets import Input

if TYPE_CHECKING:
    from station.tui.app import StationApp

REJECT_AT_CYCLE = 7
REJECT_REASON = "autopilot: the robot was bumped during this cycle (a demonstration reject)"
STEP_PAUSES = 5
"""A checklist step stays on screen this many paces (1 s at the default pace), to be read."""


async def run_autopilot(app: StationApp) -> None:
    """Drive the screens until the summary is up (or the app exits)."""
    # Deferred: the screens load when first shown (and the set-up imports the app).
    from station.tui.screens.checklist import ChecklistScreen
    from station.tui.screens.dashboard import DashboardScreen
    from station.tui.screens.home import HomeScreen
    from station.tui.screens.setup import SetupScreen
    from station.tui.screens.strokes import StrokeDashboardScreen
    from station.tui.screens.summary import SummaryScreen

    pace = app.config.autopilot_pace
    step_pause = pace * STEP_PAUSES
    rejected = False
    opened = False
    while app.is_running:
        await asyncio.sleep(pace)
        screen = app.screen
        if isinstance(screen, SummaryScreen):
            return
        if not screen.is_mounted or not screen.query("Footer"):
            continue  # switched to, not composed yet: its keys would find no widgets
        if isinstance(screen, HomeScreen) and not opened:
            await asyncio.sleep(step_pause)
            opened = True
            screen.action_new()
        elif isinstance(screen, SetupScreen):
            await asyncio.sleep(step_pause)
            if _still_shown(app, screen):
                screen.action_start()
        elif isinstance(screen, ChecklistScreen):
            await asyncio.sleep(step_pause)
            if _still_shown(app, screen) and not screen.busy:
                _fill_inputs(app, screen)
                screen.action_confirm()
        elif isinstance(screen, StrokeDashboardScreen):
            state = app.current_state()
            if state is None or screen.streaming or state.status != "running":
                continue
            if state.progress is not None and state.progress.complete:
                screen.action_finish()
            else:
                screen.action_stream()
        elif isinstance(screen, DashboardScreen) and screen.live:
            state = app.current_state()
            if state is None or screen.busy:
                continue
            last = state.last_cycle
            if (
                not rejected
                and last is not None
                and last.cycle == REJECT_AT_CYCLE
                and last.rejected is None
            ):
                rejected = True
                screen.action_reject(REJECT_REASON)
            elif state.action.kind == "finish":
                screen.action_finish()
            elif state.action.kind != "capture" or state.status != "running":
                continue
            elif state.progress is None or not state.progress.complete:
                screen.action_capture()
            elif state.current is not None and state.current.index < len(state.steps) - 1:
                screen.action_go_on()  # a block's cycles step: the next placement's steps
            else:
                screen.action_finish()


def _still_shown(app: StationApp, screen: object) -> bool:
    """Whether ``screen`` is still the one shown (the pause before acting may have let the
    operator or the engine move on)."""
    return app.screen is screen


def _fill_inputs(app: StationApp, screen: object) -> None:
    """Type into the empty input fields what the simulated set-up shows (the teach pendant's
    X, Y, Z into the fields named x, y, z; a master's size); where it shows nothing, a demo
    value."""

    state = app.current_state()
    fixture = app.demo_fixture
    placement = state.current.placement if state is not None and state.current else None
    unit = str(app.session_header.get("unit") or "in")
    display = fixture.shows(placement, unit) if fixture is not None else None
    values = dict(display.values) if display is not None else {}
    for widget in screen.query("#step-inputs Input"):  # type: ignore[attr-defined]
        if isinstance(widget, Input) and not widget.value:
            name = str(widget.id).removeprefix("input-")
            if name in values:
                widget.value = str(values[name])
            elif display is None:
                widget.value = "0"  # nothing shown to copy: a demo value
            # else: a field the set-up shows nothing for is left empty (an optional one)
