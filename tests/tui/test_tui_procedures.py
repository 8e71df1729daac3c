"""Relative accuracy and linearity through the TUI at 80×24, by keyboard, against the demo's
simulators (two fixtures with a teach pendant; a parallel bar streaming h, v, s at 200 sets/s).

Each walks its procedure to the summary with a small count set on the set-up screen (3
placements, 3 strokes), then checks that the session file verifies and that ``station analyze
FILE --json`` gives the figures the summary showed.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from textual.widgets import Input, Static

from station.analysis.document import to_json
from station.tui.app import REDRAW_INTERVAL, DemoPort, StationApp, StationConfig
from station.tui.instruments import DemoLab
from station.tui.screens.checklist import ChecklistScreen
from station.tui.screens.dashboard import DashboardScreen
from station.tui.screens.home import HomeScreen
from station.tui.screens.setup import SetupScreen
from station.tui.screens.strokes import StrokeDashboardScreen
from station.tui.screens.summary import SummaryScreen

ROOT = Path(__file__).resolve().parents[2]
SEED = 7


@pytest.fixture
def lab() -> Iterator[DemoLab]:
    """The demo's simulators; a short bar stroke (80 points + dwell: 0.5 s at 200 sets/s)."""
    demo = DemoLab(SEED, stroke_points=80)
    try:
        yield demo
    finally:
        demo.stop()


def demo_app(tmp_path: Path, lab: DemoLab, procedure: str) -> StationApp:
    fixture = lab.fixture(procedure)
    port = DemoPort(
        url=fixture.url,
        protocol=fixture.protocol,
        channel_map=fixture.channel_map,
        procedure=procedure,
        description=fixture.description,
        trigger=fixture.trigger,
    )
    config = StationConfig(
        sessions_dir=tmp_path, sessions_reason="test folder", demo=port, demo_lab=lab
    )
    return StationApp(config)


def station(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "station", *args], capture_output=True, text=True, cwd=ROOT
    )


def text_of(app: StationApp, selector: str) -> str:
    return str(app.screen.query_one(selector, Static).render())


async def start(pilot, tui, count: int) -> None:
    """Home → n → the pre-filled set-up with ``count`` placements or strokes → F2."""
    app = pilot.app
    await pilot.press("n")
    await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
    await pilot.pause()
    app.screen.query_one("#cycles", Input).value = str(count)
    await pilot.press("f2")
    await tui.wait_until(pilot, lambda: app.runner is not None)


def assert_agrees(shown: object, path: Path) -> dict:
    """The file verifies and ``station analyze --json`` holds every figure the summary
    showed, equal; returns the command's document."""
    verify = station("verify", str(path))
    assert verify.returncode == 0, verify.stdout + verify.stderr
    analyze = station("analyze", str(path), "--json")
    assert analyze.returncode == 0, analyze.stderr
    document = json.loads(analyze.stdout)
    shown_document = json.loads(json.dumps(to_json(shown)))
    assert shown_document == {key: document[key] for key in shown_document}
    return document


async def test_relative_accuracy_through_the_tui(tmp_path: Path, lab: DemoLab, tui) -> None:
    app = demo_app(tmp_path, lab, "relative_accuracy")
    fixture = lab.fixture("relative_accuracy")
    refused = False
    async with app.run_test(size=(80, 24)) as pilot:
        await start(pilot, tui, 3)
        assert app.runner.state().current.kind == "check"
        while app.runner.state().current is not None:
            state = app.runner.state()
            step = state.current
            screen = app.screen
            if step.kind == "input":
                await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
                await tui.wait_until(
                    pilot, lambda: len(app.screen.query("#step-inputs Input")) == 3
                )
                shown = fixture.simulator.model.placement_of(step.placement)
                # The pendant display is on screen, and the placement p of P.
                assert shown.pendant_text() in text_of(app, "#step-text")
                assert f"placement {step.placement} of 3" in text_of(app, "#step-title")
                fields = {f.id: f for f in app.screen.query("#step-inputs Input")}
                if not refused:
                    refused = True
                    fields["input-x"].value = "twelve"
                    fields["input-z"].focus()  # Enter in the last field saves
                    await pilot.press("enter")
                    await tui.wait_until(pilot, lambda: not app.screen.busy)
                    await pilot.pause()
                    assert "must be a number" in text_of(app, "#step-message")
                    assert app.runner.state().current.index == step.index
                for axis, value in zip("xyz", shown.pendant, strict=True):
                    fields[f"input-{axis}"].value = str(value)
                fields["input-x"].focus()
                await pilot.press("enter", "enter", "enter")
            elif step.kind == "capture":
                await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
                await pilot.pause()
                assert f"placement {step.placement} of 3" in text_of(app, "#dash-title")
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
                ),
            )
        await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
        await pilot.pause()
        app.redraw_live()
        await pilot.pause()
        # Finding 9: the prompt said "Every cycle asked for is captured" of placements.
        prompt = text_of(app, "#dash-prompt")
        assert "Every placement asked for is captured" in prompt, prompt
        await pilot.press("f")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        await tui.wait_until(pilot, lambda: bool(app.screen.query("#summary-report")))
        view = app.screen.view
        report = text_of(app, "#summary-report")
        assert "RELATIVE ACCURACY" in report and "PENDANT" in report
        assert "3 placements" in text_of(app, "#summary-title")
        assert "Verdict:" in text_of(app, "#summary-verdict")

    document = assert_agrees(view.analysis, view.path)
    placements = document["accuracy"]["placements"]
    assert [p["placement"] for p in placements] == [1, 2, 3]
    for placement in placements:
        expected = fixture.simulator.model.placement_of(placement["placement"]).pendant
        assert placement["pendant"] == dict(zip("xyz", expected, strict=True))
        # The summary's per-placement block shows the same mean errors as the command.
        means = view.report.result.placements[placement["placement"] - 1].mean
        assert means == pytest.approx(placement["mean"])


async def test_linearity_through_the_tui(tmp_path: Path, lab: DemoLab, tui) -> None:
    app = demo_app(tmp_path, lab, "linearity")
    async with app.run_test(size=(80, 24)) as pilot:
        await start(pilot, tui, 3)
        # The checklist, step by step (the zero steps zero) until the strokes stream. The
        # screen's own Enter action, not pilot.press: the bar streams 200 sets/s in this
        # process, and pilot.press waits for the process to go idle (1 s twice) after each key.
        while app.runner.state().current.kind != "stroke":
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
            screen = app.screen
            before = app.runner.state().current.index
            await tui.wait_until(pilot, lambda screen=screen: not screen.busy)
            screen.action_confirm()
            await tui.wait_until(
                pilot,
                lambda before=before: app.runner.state().current.index != before,
                timeout=30,
            )
        await tui.wait_until(pilot, lambda: isinstance(app.screen, StrokeDashboardScreen))
        dashboard = app.screen
        redraws: list[float] = []
        app.redraw_hooks.append(lambda oldest: redraws.append(time.monotonic()))
        await tui.wait_until(pilot, lambda: dashboard.streaming, timeout=30)
        streaming_from = time.monotonic()
        # Points of the stroke under way are counted and drawn while it runs.
        await tui.wait_until(pilot, lambda: "points now" in text_of(app, "#dash-title"))
        await tui.wait_until(
            pilot,
            lambda: app.runner.state().progress.done >= 3 and not dashboard.streaming,
            timeout=60,
        )
        # 200 sets a second arrive, each a runner notice: the screen is redrawn at most once
        # per REDRAW_INTERVAL all the same (fewer on a slow machine, never more).
        streamed = time.monotonic() - streaming_from
        during = [t for t in redraws if t >= streaming_from]
        assert 1 <= len(during) <= streamed / REDRAW_INTERVAL + 2, (len(during), streamed)
        await tui.wait_until(pilot, lambda: dashboard.result is not None)
        await tui.wait_until(pilot, lambda: len(dashboard.result.strokes) == 3)
        await pilot.pause(0.3)
        assert "3 of 3 strokes done" in text_of(app, "#dash-title")
        assert "Press f to finish" in text_of(app, "#dash-prompt")
        # Finding 9: one number format on the screen (the plot's position axis read "s 0.00").
        assert tui.odd_figures(tui.screen_text(app)) == [], tui.screen_text(app)
        plot = str(dashboard.query_one("#stroke-plot").render())
        assert "h − LS line" in plot and "•" in plot
        # The position along the bar at the figures' decimals too (it read "s 0.00").
        assert re.search(r"s -?\d+\.\d{5} +-?\d+\.\d{5}$", plot.splitlines()[-1].rstrip()), plot
        chart = str(dashboard.query_one("#stroke-chart").render())
        assert "stroke " in chart and "CL" in chart
        live = [
            (r.number, r.direction, r.straightness["h"].mz, r.straightness["v"].mz)
            for r in dashboard.result.strokes
        ]
        await pilot.press("v")
        await pilot.pause()
        assert "v − LS line" in str(dashboard.query_one("#stroke-plot").render())
        await pilot.press("f")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        await tui.wait_until(pilot, lambda: bool(app.screen.query("#summary-report")))
        view = app.screen.view
        report = text_of(app, "#summary-report")
        assert "STRAIGHTNESS" in report.upper()
        assert "3 strokes" in text_of(app, "#summary-title")
        assert "Verdict:" in text_of(app, "#summary-verdict")

    document = assert_agrees(view.analysis, view.path)
    strokes = document["linearity"]["strokes"]
    # The dashboard analysed each stroke as it came: the same strokes, figures and directions
    # as the command reads back from the file.
    assert [(s["stroke"], s["direction"]) for s in strokes] == [(n, d) for n, d, _, _ in live]
    for stroke, (_, _, h, v) in zip(strokes, live, strict=True):
        assert stroke["h"]["mz"] == pytest.approx(h)
        assert stroke["v"]["mz"] == pytest.approx(v)


async def test_a_linearity_session_left_and_resumed_goes_on_from_its_strokes(
    tmp_path: Path, lab: DemoLab, tui
) -> None:
    app = demo_app(tmp_path, lab, "linearity")
    async with app.run_test(size=(80, 24)) as pilot:
        await start(pilot, tui, 4)
        while app.runner.state().current.kind != "stroke":
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
            screen = app.screen
            before = app.runner.state().current.index
            await tui.wait_until(pilot, lambda screen=screen: not screen.busy)
            screen.action_confirm()
            await tui.wait_until(
                pilot, lambda before=before: app.runner.state().current.index != before
            )
        await tui.wait_until(pilot, lambda: isinstance(app.screen, StrokeDashboardScreen))
        await tui.wait_until(pilot, lambda: app.runner.state().progress.done >= 2, timeout=60)
        # What Leave does once confirmed: the session is kept, interrupted.
        app.interrupt_session("operator left")
        app.go_home()
        await tui.wait_until(pilot, lambda: isinstance(app.screen, HomeScreen))
        await pilot.pause()
        app.screen.action_resume()
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen))
        await pilot.pause()
        app.screen.action_start()
        await tui.wait_until(pilot, lambda: isinstance(app.screen, StrokeDashboardScreen))
        dashboard = app.screen
        # The strokes recorded before the break are drawn again, and streaming goes on to 4.
        await tui.wait_until(pilot, lambda: dashboard.result is not None, timeout=30)
        assert len(dashboard.result.strokes) >= 2
        # The verdict so far is the table's (PROVISIONAL below 25 strokes), never a bare
        # CAPABLE beside rows that say PROVISIONAL.
        prompt = text_of(app, "#dash-prompt")
        assert "Verdict so far: PROVISIONAL: " in prompt, prompt
        await tui.wait_until(
            pilot,
            lambda: app.runner.state().progress.done >= 4 and not dashboard.streaming,
            timeout=60,
        )
        await tui.wait_until(pilot, lambda: len(dashboard.result.strokes) == 4)
        assert [r.number for r in dashboard.result.strokes] == [1, 2, 3, 4]
        dashboard.action_finish()
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        await tui.wait_until(pilot, lambda: bool(app.screen.query("#summary-report")))
        view = app.screen.view
        assert "4 strokes" in text_of(app, "#summary-title")

    document = assert_agrees(view.analysis, view.path)
    assert len(document["linearity"]["strokes"]) == 4
