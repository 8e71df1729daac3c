"""Issue 26, item 5: every built-in procedure reachable by a newcomer. ``station demo
--procedure NAME`` offered three of the procedures; another opened on the repeatability's
fixture, with the repeatability's channel map, trigger and prompts as its set-up's defaults.
Each procedure now starts on its own simulated set-up, with the set-up's defaults from the
chosen procedure, and the demo's autopilot walks it at 80×24 to its summary verdict (a short
count: a trial run)."""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Iterator
from pathlib import Path

import pytest
from textual.widgets import Input, Select, Static

import station.methods  # noqa: F401 - procedure files name the methods
from station.commands import demo
from station.errors import StationError
from station.procedures import discover_procedures
from station.tui.app import StationApp
from station.tui.autopilot import run_autopilot
from station.tui.instruments import DemoLab, demo_methods
from station.tui.screens.setup import SetupScreen
from station.tui.screens.setup_form import count_field
from station.tui.screens.summary import SummaryScreen

CATALOG = discover_procedures(())
# Every built-in procedure whose method the demo simulates; the others are refused (below).
PROCEDURES = [i for i in CATALOG.ids() if CATALOG.get(i).analysis in demo_methods()]
WITHOUT_DEMO = [i for i in CATALOG.ids() if i not in PROCEDURES]


@pytest.mark.parametrize("procedure", WITHOUT_DEMO or ["stabilisation"])
def test_a_procedure_without_a_simulated_set_up_is_refused_with_a_sentence(procedure: str) -> None:
    """Never a demo on another method's simulator: the sentence says how to run it instead."""
    if procedure not in CATALOG.ids() or procedure in PROCEDURES:
        pytest.skip(f"{procedure} is not a built-in procedure without a demo any more")
    with pytest.raises(StationError, match="no simulated set-up in the demo yet"):
        demo._demo_choice(demo_args(procedure))


def short_count(procedure: str) -> int:
    """A short trial run: 2 cycles, placements or strokes, or the fewest the procedure's
    method can judge (a gain schedule's fit: 3 positions)."""
    return max(2, count_field(CATALOG.get(procedure)).minimum)


@pytest.fixture
def lab() -> Iterator[DemoLab]:
    """The demo's simulators; a short bar stroke (80 points)."""
    simulators = DemoLab(1990, stroke_points=80)
    try:
        yield simulators
    finally:
        simulators.stop()


def demo_args(procedure: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    demo.add_parser(parser.add_subparsers())
    return parser.parse_args(
        [
            "demo",
            "--procedure",
            procedure,
            "--count",
            str(short_count(procedure)),
            "--autopilot",
            "--pace",
            "0.01",
        ]
    )


def test_every_built_in_procedure_is_offered_by_the_demo() -> None:
    """``--procedure``'s help names every built-in procedure (none is left for a newcomer to
    guess), and every one is accepted."""
    parser = argparse.ArgumentParser()
    demo.add_parser(parser.add_subparsers())
    text = " ".join(parser._subparsers._group_actions[0].choices["demo"].format_help().split())  # type: ignore[union-attr]
    for procedure in PROCEDURES:
        assert procedure in text
        assert demo._demo_choice(demo_args(procedure)).id == procedure


@pytest.mark.parametrize("procedure", PROCEDURES)
async def test_the_demo_walks_each_procedure_to_its_verdict(
    procedure: str, lab: DemoLab, tmp_path: Path, tui
) -> None:
    args = demo_args(procedure)
    chosen = demo._demo_choice(args)
    config = demo.demo_config(args, chosen, lab, tmp_path, "a test folder")
    # Its own simulated set-up: the method's, not the repeatability fixture in its place.
    fixture = lab.by_url(config.demo.url)
    assert fixture is not None and fixture.method == chosen.analysis
    assert set(fixture.channel_map.values()) <= set(chosen.channels)
    assert config.autopilot
    # The set-up is looked at before the autopilot takes over from there.
    app = StationApp(dataclasses.replace(config, autopilot=False))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen), timeout=20)
        await pilot.pause()
        setup = app.screen
        # The set-up's defaults are the chosen procedure's (and its simulator's line).
        assert setup.query_one("#procedure", Select).value == procedure
        assert setup.query_one("#cycles", Input).value == str(short_count(procedure))
        assert setup.query_one("#port", Input).value == fixture.url
        mapped = setup.query_one("#map", Input).value
        assert {pair.split("=")[1] for pair in mapped.split(",")} <= set(chosen.channels)
        app.run_worker(run_autopilot(app), group="autopilot", exclusive=True)
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen), timeout=60)
        await pilot.pause()
        verdict = str(app.screen.query_one("#summary-verdict", Static).render())
        assert "Verdict" in verdict or "judges no readings" in verdict, verdict
        assert app.screen.view.path.is_file()


@pytest.mark.parametrize(
    ("procedure", "label", "fewest"),
    [("gain_schedule", "Positions", 3), ("joint_troubleshooting", "Joints", 2)],
)
def test_the_set_up_counts_in_the_procedures_words_no_fewer_than_it_can_judge(
    procedure: str, label: str, fewest: int
) -> None:
    """The set-up counted a gain schedule's positions and a troubleshooting's joints as
    "fixture placements over the envelope", and took 2 positions, from which the fit cannot
    choose its order (the summary then said "No accepted cycles"): the demo's short trial run
    stops at what the method can judge."""
    count = count_field(CATALOG.get(procedure))
    assert (count.label, count.minimum) == (label, fewest)
    assert "fixture" not in count.hint
    args = demo_args(procedure)
    args.count = fewest - 1
    with pytest.raises(StationError, match=f"give at least {fewest} {label.lower()}"):
        demo._demo_choice(args)


def shown_map(app: StationApp) -> str | None:
    """The set-up's channel map, once the (new) set-up screen has it."""
    fields = app.screen.query("#map")
    return fields.first(Input).value if fields else None


async def test_a_gauge_check_takes_its_own_channel_map_and_trigger(tmp_path: Path, tui) -> None:
    """The gauge check's set-up offered the repeatability's channel map (1=x,2=y,3=z) and its
    arrival trigger, remembered from the last session or kept across a change of procedure;
    against a one-indicator bench it zeroed on the block (Cgk −814.56). The line is kept, the
    map and the trigger follow the procedure."""
    from station.session.remembered import RememberedSetup, save_remembered
    from station.tui.app import StationConfig

    save_remembered(
        RememberedSetup(
            robot="R1", port="/dev/ttyUSB7", channel_map="1=x,2=y,3=z", trigger="arrival"
        )
    )
    app = StationApp(StationConfig(sessions_dir=tmp_path, sessions_reason="test folder"))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        app.screen.open_new("gauge_check")
        await tui.wait_until(pilot, lambda: app.screen.query("#map"))
        await pilot.pause()
        assert app.screen.query_one("#port", Input).value == "/dev/ttyUSB7"
        assert app.screen.query_one("#map", Input).value == "1=x"
        assert app.screen.query_one("#trigger", Select).value == "poll"
        # To the repeatability (its three channels), then back to the gauge check.
        app.screen.query_one("#procedure", Select).value = "repeatability"
        await tui.wait_until(pilot, lambda: shown_map(app) == "1=x,2=y,3=z")
        await pilot.pause()
        app.screen.query_one("#trigger", Select).value = "arrival"
        app.screen.query_one("#procedure", Select).value = "gauge_check"
        await tui.wait_until(pilot, lambda: shown_map(app) == "1=x")
        await pilot.pause()
        assert app.screen.query_one("#trigger", Select).value == "poll"
        assert app.screen.query_one("#port", Input).value == "/dev/ttyUSB7"


async def test_the_gauge_checks_set_up_and_zero_speak_of_its_bench(
    lab: DemoLab, tmp_path: Path, tui
) -> None:
    """The gauge check's set-up showed the limits hint with no limits field, and its zero on a
    surface plate said "Keep the robot still"."""
    from station.tui.autopilot import _fill_inputs
    from station.tui.screens.checklist import ChecklistScreen

    args = demo_args("gauge_check")
    config = demo.demo_config(args, demo._demo_choice(args), lab, tmp_path, "a test folder")
    app = StationApp(dataclasses.replace(config, autopilot=False))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("n")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SetupScreen), timeout=20)
        await pilot.pause()
        assert not app.screen.query("Input#limits-x")
        assert "LSL:USL" not in tui.screen_text(app)
        await pilot.press("f2")
        while (state := app.runner.state()).action.kind != "zero":
            await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
            screen = app.screen
            await tui.wait_until(pilot, lambda screen=screen: not screen.busy)
            if state.action.kind == "input":
                await tui.wait_until(pilot, lambda: app.screen.query("#step-inputs Input"))
                _fill_inputs(app, app.screen)
            before = state.current.index
            app.screen.action_confirm()
            await tui.wait_until(
                pilot, lambda before=before: app.runner.state().current.index != before
            )
        await tui.wait_until(pilot, lambda: "zero the indicators" in tui.screen_text(app))
        assert "robot still" not in tui.screen_text(app).lower()
