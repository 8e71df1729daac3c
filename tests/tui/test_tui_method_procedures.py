"""The gauge check, per-joint troubleshooting and gain schedule through today's TUI at 80×24, by
keyboard, against simulators on a real pty: the procedures run with the existing step kinds and
screens, and ``station analyze FILE --json`` on the saved session gives their analysis."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from textual.widgets import Input, Select, Static

from station.instruments.gauge_bench import GaugeBenchModel
from station.instruments.joint_model import faulty_arm
from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec, Simulator
from station.tui.app import StationApp, StationConfig
from station.tui.screens.checklist import ChecklistScreen
from station.tui.screens.dashboard import DashboardScreen
from station.tui.screens.setup import SetupScreen
from station.tui.screens.summary import SummaryScreen


async def test_gauge_check_through_the_tui(tmp_path: Path, tui) -> None:
    # idh zeroes the indicator itself (on the plate); the block reads 0.1 + 0.0002 in.
    simulator = Simulator(get_protocol("idh"), GaugeBenchModel(0.1, bias=0.0002, noise=0.00005))
    url = simulator.start_pty()
    app = StationApp(StationConfig(sessions_dir=tmp_path, sessions_reason="test folder"))
    try:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("n")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
            await pilot.pause()
            app.screen.query_one("#procedure", Select).value = "gauge_check"
            await tui.wait_until(
                pilot,
                lambda: (
                    isinstance(app.screen, SetupScreen)
                    and app.screen.procedure_id == "gauge_check"
                    and bool(app.screen.query("#robot"))
                ),
            )
            await pilot.pause()
            screen = app.screen
            screen.query_one("#robot", Input).value = "bench"
            screen.query_one("#port", Input).value = url
            screen.query_one("#protocol", Select).value = "idh"
            screen.query_one("#map", Input).value = "1=x"
            screen.query_one("#cycles", Input).value = "25"
            await pilot.pause()
            # Today's set-up asks every procedure for limits per channel; the gauge check's own
            # tolerance is typed at its input step (the limits are not used by its analysis).
            screen.query_one("#limits-x", Input).value = "0.098:0.102"
            await pilot.press("f2")
            await tui.wait_until(pilot, lambda: app.runner is not None)
            while app.runner.state().current is not None:
                state = app.runner.state()
                step = state.current
                if step.kind == "input":
                    await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
                    await tui.wait_until(
                        pilot, lambda: len(app.screen.query("#step-inputs Input")) == 4
                    )
                    fields = {f.id: f for f in app.screen.query("#step-inputs Input")}
                    fields["input-gauge"].value = "MIT-0042"
                    fields["input-reference"].value = "0.1"
                    fields["input-tolerance"].value = "0.01"
                    fields["input-calibration_due"].value = "2099-01-01"
                    fields["input-gauge"].focus()
                    await pilot.press("enter", "enter", "enter", "enter")
                elif step.kind == "cycles":
                    await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
                    await pilot.pause()
                    while len(app.runner.state().cycles) < 25:
                        await tui.capture_one(pilot)
                    break
                else:
                    await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
                    screen = app.screen
                    await tui.wait_until(pilot, lambda screen=screen: not screen.busy)
                    await pilot.press("enter")
                await tui.wait_until(
                    pilot,
                    lambda state=state: (
                        app.runner.state().current is None
                        or app.runner.state().current.index != state.current.index
                    ),
                )
            await pilot.pause()
            await pilot.press("f")
            await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
            path = app.screen.view.path
    finally:
        simulator.stop()
    result = subprocess.run(
        [sys.executable, "-m", "station", "analyze", str(path), "--json"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    study = json.loads(result.stdout)["gauge_check"]
    assert study["n"] == 25 and study["reference"] == 0.1 and study["tolerance"] == 0.01
    assert abs(study["bias"] - 0.0002) < 0.00004, study
    # Cgk = (0.001 - 0.0002) / (3 s), s about 0.00007 (noise and the 0.0001 in display): ~3.8.
    assert study["capable"] is True, study


async def set_up(pilot, tui, procedure: str, url: str, channel_map: str, count: str) -> None:
    """Home → n → the set-up of ``procedure`` on ``url`` (idh) → F2."""
    app = pilot.app
    await pilot.press("n")
    await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
    await pilot.pause()
    app.screen.query_one("#procedure", Select).value = procedure
    await tui.wait_until(
        pilot,
        lambda: (
            isinstance(app.screen, SetupScreen)
            and app.screen.procedure_id == procedure
            and bool(app.screen.query("#robot"))
        ),
    )
    await pilot.pause()
    screen = app.screen
    screen.query_one("#robot", Input).value = "arm"
    screen.query_one("#port", Input).value = url
    screen.query_one("#protocol", Select).value = "idh"
    screen.query_one("#map", Input).value = channel_map
    screen.query_one("#cycles", Input).value = count
    # Today's set-up asks every procedure for limits per channel (unused by these analyses).
    for field in screen.query("Input"):
        if (field.id or "").startswith("limits-"):
            field.value = "-0.01:0.01"
    await pilot.pause()
    await pilot.press("f2")
    await tui.wait_until(pilot, lambda: app.runner is not None)


async def walk(pilot, tui, inputs) -> Path:
    """Every step to the end: Enter on checks and zeroes, ``inputs(step)`` typed at input steps,
    Space until a cycles step is done; then f and the summary. The session file's path."""
    app = pilot.app
    while app.runner.state().current is not None:
        state = app.runner.state()
        step = state.current
        if step.kind == "input":
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
            values = inputs(step)
            wanted = len(values)
            await tui.wait_until(
                pilot, lambda n=wanted: len(app.screen.query("#step-inputs Input")) == n
            )
            fields = {f.id: f for f in app.screen.query("#step-inputs Input")}
            for name, value in values.items():
                fields[f"input-{name}"].value = value
            fields[f"input-{next(iter(values))}"].focus()
            await pilot.press(*["enter"] * len(values))
        elif step.kind == "cycles":
            await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
            await pilot.pause()
            prompt = str(app.screen.query_one("#dash-prompt", Static).render())
            if "Every cycle asked for is captured" in prompt:
                pytest.fail(
                    f"step {step.id} (placement {step.placement}) has all its cycles, more steps "
                    "follow, and the dashboard offers only 'f to finish'"
                )
            await tui.capture_one(pilot)
        else:
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
            screen = app.screen
            await tui.wait_until(pilot, lambda screen=screen: not screen.busy)
            await pilot.press("enter")
        await tui.wait_until(
            pilot,
            lambda state=state: (
                app.runner.state().current is None
                or app.runner.state().current.index != state.current.index
                or len(app.runner.state().cycles) != len(state.cycles)
            ),
        )
    # With every step done the app shows the dashboard, where f finishes.
    await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
    await pilot.pause()
    await pilot.press("f")
    await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
    return app.screen.view.path


def analyze_json(path: Path) -> dict:
    result = subprocess.run(
        [sys.executable, "-m", "station", "analyze", str(path), "--json"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


@pytest.mark.xfail(
    strict=True,
    reason="today's TUI cannot go on from a cycles step inside a repeat block: after joint 1's "
    "25 returns the dashboard offers only 'f to finish' (station capture confirms the step and "
    "goes on). Remove this mark when the engine's cycles handler advances.",
)
async def test_joint_troubleshooting_through_the_tui(tmp_path: Path, tui) -> None:
    # Joint 3 has backlash; idh zeroes the indicators itself at each joint's zero step.
    arm = faulty_arm(3, "backlash")
    simulator = Simulator(get_protocol("idh"), arm, seed=2)
    url = simulator.start_pty()
    levers = arm.lever_arms()
    app = StationApp(StationConfig(sessions_dir=tmp_path, sessions_reason="test folder"))
    try:
        async with app.run_test(size=(80, 24)) as pilot:
            await set_up(pilot, tui, "joint_troubleshooting", url, "1=x,2=y,3=z", "3")
            path = await walk(
                pilot, tui, lambda step: {"lever": f"{levers[step.placement - 1]:.3f}"}
            )
    finally:
        simulator.stop()
    document = analyze_json(path)
    assert [j["n"] for j in document["joints"]] == [25, 25, 25]
    assert document["suspect"] == 3 and document["cause"] == "backlash", document["reason"]
    assert document["compared"] == "angular spread"


async def test_gain_schedule_through_the_tui(tmp_path: Path, tui) -> None:
    # No gauge is read, but today's set-up still wants a line for the procedure's channel q.
    model = FixtureModel({"q": AxisModel()}, GaugeSpec())
    simulator = Simulator(get_protocol("idh"), model)
    url = simulator.start_pty()
    app = StationApp(StationConfig(sessions_dir=tmp_path, sessions_reason="test folder"))

    def gains(step) -> dict[str, str]:
        q = -30 + 30 * (step.placement - 1)
        kp = 2 - 0.03 * q + 4e-4 * q**2 - 1e-6 * q**3
        return {"q": f"{q:g}", "kp": f"{kp:.9f}", "ki": f"{0.4 + 0.001 * q:.6f}", "kd": "0.07"}

    try:
        async with app.run_test(size=(80, 24)) as pilot:
            await set_up(pilot, tui, "gain_schedule", url, "1=q", "6")
            path = await walk(pilot, tui, gains)
    finally:
        simulator.stop()
    document = analyze_json(path)
    assert list(document["gains"]) == ["kp", "ki", "kd"]
    assert document["gains"]["kp"]["order"] == 3
    assert document["gains"]["ki"]["order"] == 1
