"""The gauge check, per-joint troubleshooting and gain schedule through the TUI at 80×24, by
keyboard, against ``station simulate``'s set-ups (on a real pty): set-up, every step of
the checklist, the captures, finish, and the summary with the kind's own report. The gauge
check then stands in the gauge register, and a repeatability session's summary names it."""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from textual.widgets import Input, Static

from station.commands import simulate
from station.session.gauge_register import load_register
from station.tui.app import StationApp, StationConfig
from station.tui.instruments import DemoFixture, track
from station.tui.screens.checklist import ChecklistScreen
from station.tui.screens.dashboard import DashboardScreen
from station.tui.screens.summary import SummaryScreen, SummaryView

STATION = [sys.executable, "-m", "station"]
PROTOCOL = "mitutoyo"
"""The set-up screen's first protocol (no zero command: the station zeroes in software)."""


@pytest.fixture
def simulator(request) -> Iterator[str]:
    """The simulated set-up ``station simulate`` builds from the test's arguments
    (``request.param``), served on a real pty in this process so that the session moves its
    robot where the steps say, as the demo does (the operator re-seats the block, moves the
    joint); its URL."""
    parser = argparse.ArgumentParser()
    simulate.add_parser(parser.add_subparsers())
    args = parser.parse_args(["simulate", "--protocol", PROTOCOL, *request.param])
    simulator = simulate.build_simulator(args)
    url = simulator.start_pty()
    fixture = track(DemoFixture(url, PROTOCOL, dict(simulator.channel_map), simulator))
    try:
        yield url
    finally:
        fixture.stop()


def text_of(app: StationApp, selector: str) -> str:
    return str(app.screen.query_one(selector, Static).render())


async def run_procedure(
    pilot, tui, procedure: str, url: str, channel_map: str, count: str | None, values, seen=None
) -> None:
    """Set up ``procedure`` on ``url`` and walk it by keyboard to the summary: Enter on
    checks and zeros, the fields typed (``values(placement)``) at inputs, Space at captures,
    ``f`` once every step is done. ``seen(app, state)`` looks at the screen before each
    capture."""
    app = pilot.app
    await pilot.pause()
    app.screen.open_new(procedure)
    await tui.wait_until(pilot, lambda: app.screen.query("#port"))
    await pilot.pause()
    await pilot.press(*"R1")
    app.screen.query_one("#port", Input).value = url
    app.screen.query_one("#map", Input).value = channel_map
    if count is not None:
        app.screen.query_one("#cycles", Input).value = count
    for field in app.screen.query("Input"):
        if str(field.id).startswith("limits-"):  # the report's ± 0.001 in, where asked
            field.value = "±0.001"
    await pilot.press("f2")
    await pilot.pause()
    errors = [str(w.render()) for w in app.screen.query(".field-error")]
    assert app.runner is not None or not any(errors), errors
    await tui.wait_until(pilot, lambda: app.runner is not None)
    while (state := app.runner.state()).action.kind != "finish":
        kind, step = state.action.kind, state.current
        if kind == "capture":
            await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
            if state.progress.done < state.progress.target:
                if seen is not None:
                    await pilot.pause()
                    seen(app, app.runner.state())
                await tui.capture_one(pilot)
                continue
            # Every cycle of the step is in: Go on (the next joint, or the finish).
            await tui.wait_until(pilot, lambda: app.screen.check_action("go_on", ()))
            await pilot.press("g")
            await tui.wait_until(
                pilot,
                lambda state=state: (
                    app.runner.state().current is None
                    or app.runner.state().current.index != state.current.index
                ),
            )
            continue
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        screen = app.screen
        await tui.wait_until(pilot, lambda screen=screen: not screen.busy)
        if kind == "input":
            fields = state.action.fields
            await tui.wait_until(
                pilot,
                lambda fields=fields: len(app.screen.query("#step-inputs Input")) == len(fields),
            )
            typed = values(step.placement)
            for field in fields:
                app.screen.query_one(f"#input-{field.name}", Input).value = typed.get(
                    field.name, ""
                )
            app.screen.query_one(f"#input-{fields[-1].name}", Input).focus()
        await pilot.press("enter")
        await tui.wait_until(
            pilot,
            lambda state=state: (
                app.runner.state().current is None
                or app.runner.state().current.index != state.current.index
                or len(app.runner.state().cycles) != len(state.cycles)
            ),
            timeout=30,
        )
    await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
    await pilot.pause()
    await pilot.press("f")
    await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen), timeout=30)
    await pilot.pause()


def tui_app(tmp_path: Path) -> StationApp:
    return StationApp(
        StationConfig(
            sessions_dir=tmp_path / "sessions",
            sessions_reason="test folder",
            capture_timeout=3.0,
        )
    )


def analyze_json(path: Path) -> dict:
    done = subprocess.run(
        [*STATION, "analyze", str(path), "--json"], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.mark.parametrize(
    "simulator", [("--model", "gauge-bench", "--reference", "0.1", "--seed", "3")], indirect=True
)
async def test_gauge_check_through_the_tui(tmp_path: Path, simulator: str, tui) -> None:
    app = tui_app(tmp_path)
    typed = {"gauge": "MIT-0042", "reference": "0.1", "tolerance": "0.004"}
    async with app.run_test(size=(80, 24)) as pilot:
        await run_procedure(pilot, tui, "gauge_check", simulator, "1=x", "25", lambda _: typed)
        report = text_of(app, "#summary-report")
        assert "GAUGE CHECK (TYPE-1 STUDY): CAPABLE" in report
        assert f"gauge register: MIT-0042, passed on {dt.date.today().isoformat()}" in report
        assert "25 readings" in text_of(app, "#summary-title")
        verdict = text_of(app, "#summary-verdict")
        assert "Verdict: CAPABLE" in verdict and "lower bound ≥ 1.33" in verdict
        view = app.screen.view
    document = analyze_json(view.path)
    study = document["gauge_check"]
    assert study["capable"] is True and study["n"] == 25
    # The summary's verdict is the study's: Cp is Cg, Cpk is Cgk.
    x = view.analysis.channels["x"].capability
    assert x.cp == pytest.approx(study["cg"]) and x.cpk == pytest.approx(study["cgk"])
    # Finished, the check filed itself in the gauge register, with the line it was read on.
    entry = load_register(Path(os.environ["STATION_GAUGES"]))["gauges"]["MIT-0042"]["checks"][-1]
    assert entry["result"] == "passed" and entry["port"] == {"url": simulator, "device": "1"}


MASTERS = ("0.1", "0.3", "0.5", "0.7", "0.9")
"""The linearity study's gauge blocks (in)."""


@pytest.mark.parametrize(
    "simulator",
    [("--model", "gauge-bench", "--reference", ",".join(MASTERS), "--slope", "0.001",
      "--noise", "0.00003", "--seed", "3")],
    indirect=True,
)  # fmt: skip
async def test_gauge_linearity_study_through_the_tui(tmp_path: Path, simulator: str, tui) -> None:
    """The five masters guided in turn (the set-up counts masters, each master's size typed,
    twelve seatings each, the bench following the steps), and the summary's verdict is the
    study's own; the study stands in the gauge register."""
    app = tui_app(tmp_path)

    def typed(placement: int | None) -> dict[str, str]:
        if placement is None:
            return {"gauge": "MIT-0042", "tolerance": "0.004"}
        return {"reference": MASTERS[placement - 1]}

    async with app.run_test(size=(80, 24)) as pilot:
        await run_procedure(pilot, tui, "gauge_linearity", simulator, "1=x", "5", typed)
        report = text_of(app, "#summary-report")
        assert "GAUGE LINEARITY AND BIAS STUDY: NOT ACCEPTABLE" in report
        assert "5 masters" in text_of(app, "#summary-title")
        verdict = text_of(app, "#summary-verdict")
        assert "Verdict: NOT ACCEPTABLE" in verdict and "proven at" in verdict
        view = app.screen.view
    study = analyze_json(view.path)["gauge_linearity"]
    assert [b["reference"] for b in study["biases"]] == [float(m) for m in MASTERS]
    assert all(b["n"] == 12 for b in study["biases"])
    assert study["slope"] == pytest.approx(0.001, abs=3 * study["slope_se"])
    register = load_register(Path(os.environ["STATION_GAUGES"]))
    entry = register["gauges"]["MIT-0042"]["studies"]["gauge_linearity"][-1]
    assert entry["result"] == "not acceptable" and entry["port"] == {
        "url": simulator,
        "device": "1",
    }


@pytest.mark.parametrize(
    "simulator",
    [("--model", "joints", "--faulty-joint", "3", "--joint-fault", "noise", "--seed", "4")],
    indirect=True,
)
async def test_joint_troubleshooting_through_the_tui(tmp_path: Path, simulator: str, tui) -> None:
    app = tui_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await run_procedure(
            pilot, tui, "joint_troubleshooting", simulator, "1=x,2=y,3=z", "3", lambda _: {}
        )
        report = text_of(app, "#summary-report")
        assert "SUSPECT: joint 3." in report
        # Wrapped to the summary's column, not cropped at its edge.
        assert max(len(line) for line in app.screen.view.report.lines) <= 74
        assert "3 joints" in text_of(app, "#summary-title")
        view = app.screen.view
    document = analyze_json(view.path)
    assert document["suspect"] == 3 and len(document["joints"]) == 3


@pytest.mark.parametrize("simulator", [("--channels", "q")], indirect=True)
async def test_gain_schedule_through_the_tui(tmp_path: Path, simulator: str, tui) -> None:
    app = tui_app(tmp_path)

    def gains(placement: int) -> dict[str, str]:
        q = -30 + 15 * (placement - 1)
        return {"q": str(q), "kp": repr(2 - 0.03 * q + 4e-4 * q * q), "ki": "0.4", "kd": "0.07"}

    async with app.run_test(size=(80, 24)) as pilot:
        await run_procedure(pilot, tui, "gain_schedule", simulator, "1=q", "5", gains)
        report = text_of(app, "#summary-report")
        assert "GAIN SCHEDULE: 5 positions" in report
        assert "5 positions" in text_of(app, "#summary-title")
        assert "judges no readings" in text_of(app, "#summary-verdict")
        view = app.screen.view
        # The text report exports without a capability analysis.
        await pilot.press("e")
        await tui.wait_until(pilot, lambda: app.screen.exported)
    document = analyze_json(view.path)
    assert document["gains"]["kp"]["order"] == 2
    assert document["gains"]["kp"]["coefficients"] == pytest.approx([2, -0.03, 4e-4], rel=1e-6)
    exported = view.path.with_name(view.path.stem + ".report.txt").read_text()
    assert exported.startswith("GAIN SCHEDULE REPORT ON") and "kp: order 2" in exported


async def test_a_repeatability_summary_names_its_gauge_check(tmp_path: Path, tui) -> None:
    """A session whose header recorded a passed check: the summary's report block says so."""
    from station.analysis.gauge_check import gauge_check
    from station.session.gauge_register import record_check
    from station.session.journal import SessionWriter
    from tests.session.conftest import reading_fields, session_header_fields

    today = dt.date.today()
    study = gauge_check([0.1, 0.1001, 0.0999, 0.1] * 7, 0.1, 0.004, resolution=0.0001)
    register = Path(os.environ["STATION_GAUGES"])
    record_check(register, "MIT-0042", study, when=today, port={"url": "loop://", "device": "1"})
    with SessionWriter.create(tmp_path, session_header_fields()) as writer:
        for cycle in range(1, 6):
            writer.append("reading", **reading_fields(cycle))
        path = writer.path
    register.unlink()  # the header's snapshot speaks, not the register as it is now
    app = tui_app(tmp_path)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        app.push_screen(SummaryScreen(SummaryView.from_file(path), reviewing=True))
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        await pilot.pause()
        report = text_of(app, "#summary-report")
    assert f"x: gauge MIT-0042: gauge check passed on {today.isoformat()}" in report
    assert "y: WARNING: no gauge check covers this channel" in report
