"""SVG snapshots of every screen of the three procedures at 80×24 (issue 13), and the dashboard
and summary without colour (``NO_COLOR``) and at 120×40.

Deterministic by construction: each test runs in a folder of its own with relative paths, the
seeded demo simulators behind fixed link names (``gauges-<procedure>``), a fixed session clock
(the checklist names the session file, whose name holds its creation time), the operator named,
and the summaries reviewing session files kept with the tests. Update the baselines after a
deliberate change with ``pytest tests/tui/snapshots --snapshot-update`` and look at them.
"""

from __future__ import annotations

from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path

import pytest
from textual.widgets import Input

from station.session.journal import SessionWriter
from station.tui.app import DemoPort, StationApp, StationConfig
from station.tui.instruments import DemoLab

HERE = Path(__file__).resolve().parent
SESSIONS = HERE / "sessions"
FIXED_CLOCK = datetime(2026, 11, 23, 9, 30, 0, tzinfo=UTC)
SAVED = {
    "repeatability": "2026-11-23T175031Z_R1_repeatability.jsonl",
    "relative_accuracy": "2026-11-29T211527Z_demo-robot_relative_accuracy.jsonl",
    "linearity": "2026-11-29T211526Z_demo-robot_linearity.jsonl",
}


@pytest.fixture
def lab(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[DemoLab]:
    """The demo's simulators behind fixed names, in the test's own folder, with the session
    clock fixed and the operator named."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sessions").mkdir()
    monkeypatch.setenv("USER", "operator-1")
    monkeypatch.setenv("LOGNAME", "operator-1")
    create = SessionWriter.create.__func__  # type: ignore[attr-defined]

    def at_fixed_time(cls, folder, header_fields, *, now=None):
        return create(cls, folder, header_fields, now=FIXED_CLOCK)

    monkeypatch.setattr(SessionWriter, "create", classmethod(at_fixed_time))
    demo = DemoLab(1990, stroke_points=80, link_prefix="gauges")
    try:
        yield demo
    finally:
        demo.stop()


def _demo_app(lab: DemoLab, procedure: str, count: int) -> StationApp:
    fixture = lab.fixture(procedure)
    port = DemoPort(
        url=fixture.url,
        protocol=fixture.protocol,
        channel_map=dict(fixture.channel_map),
        procedure=procedure,
        description=fixture.description,
        trigger=fixture.trigger,
        count=count,
    )
    return StationApp(
        StationConfig(
            sessions_dir=Path("sessions"),
            sessions_reason="the working directory's sessions folder",
            demo=port,
            demo_lab=lab,
            capture_timeout=3.0,
        )
    )


async def _setup(pilot, tui) -> None:
    from station.tui.screens.setup import SetupScreen

    await pilot.press("n")
    await tui.wait_until(pilot, lambda: isinstance(pilot.app.screen, SetupScreen))
    pilot.app.screen.query_one("#operator", Input).value = "operator-1"
    await pilot.pause(0.2)


async def _start(pilot, tui) -> None:
    from station.tui.screens.checklist import ChecklistScreen

    await _setup(pilot, tui)
    await pilot.press("f2")
    await tui.wait_until(pilot, lambda: isinstance(pilot.app.screen, ChecklistScreen))
    await pilot.pause(0.2)


async def _until_action(pilot, tui, kind: str) -> None:
    """Enter through the checklist until the runner asks for ``kind`` (pendant values are
    copied from the simulated pendant, as the demo says)."""
    from station.tui.screens.checklist import ChecklistScreen

    app = pilot.app
    while app.runner.state().action.kind != kind:
        state = app.runner.state()
        before = state.current.index
        await tui.wait_until(pilot, lambda: isinstance(app.screen, ChecklistScreen))
        await tui.wait_until(pilot, lambda: not app.screen.busy)
        if state.action.kind == "input":
            await tui.wait_until(pilot, lambda: len(app.screen.query("#step-inputs Input")) == 3)
            pendant = app.demo_fixture.simulator.model.placement_of(state.current.placement).pendant
            for axis, value in zip("xyz", pendant, strict=True):
                app.screen.query_one(f"#input-{axis}", Input).value = str(value)
            app.screen.query_one("#input-z", Input).focus()
        await pilot.press("enter")
        await tui.wait_until(
            pilot, lambda before=before: app.runner.state().current.index != before
        )
    await pilot.pause(0.3)


def _review(procedure: str):
    async def review(pilot) -> None:
        from station.tui.screens.summary import SummaryScreen, SummaryView

        view = SummaryView.from_file(Path("sessions") / SAVED[procedure])
        pilot.app.push_screen(SummaryScreen(view, reviewing=True))
        await pilot.pause(0.5)

    return review


def _saved_app(monkeypatch: pytest.MonkeyPatch) -> StationApp:
    monkeypatch.chdir(HERE)
    return StationApp(
        StationConfig(
            sessions_dir=Path("sessions"),
            sessions_reason="the working directory's sessions folder",
        )
    )


# ---- repeatability ------------------------------------------------------------------------


def test_repeatability_setup(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _setup(pilot, tui)

    assert snap_compare(_demo_app(lab, "repeatability", 30), terminal_size=(80, 24), run_before=run)


def test_repeatability_checklist(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _start(pilot, tui)

    assert snap_compare(_demo_app(lab, "repeatability", 30), terminal_size=(80, 24), run_before=run)


def test_repeatability_zero_step(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _start(pilot, tui)
        await _until_action(pilot, tui, "zero")

    assert snap_compare(_demo_app(lab, "repeatability", 30), terminal_size=(80, 24), run_before=run)


def test_repeatability_review_list(snap_compare, monkeypatch) -> None:
    async def run(pilot) -> None:
        await pilot.press("v")
        await pilot.pause(1.0)  # the verdict column is worked out on a thread

    assert snap_compare(_saved_app(monkeypatch), terminal_size=(80, 24), run_before=run)


def test_help_lists_the_screens_keys(snap_compare, monkeypatch) -> None:
    async def run(pilot) -> None:
        await pilot.press("question_mark")
        await pilot.pause(0.3)

    assert snap_compare(_saved_app(monkeypatch), terminal_size=(80, 24), run_before=run)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
@pytest.mark.parametrize("colour", ["colour", "no_color"])
def test_repeatability_summary(snap_compare, monkeypatch, size, colour) -> None:
    if colour == "no_color":
        monkeypatch.setenv("NO_COLOR", "1")
    app = _saved_app(monkeypatch)
    assert snap_compare(app, terminal_size=size, run_before=_review("repeatability"))


@pytest.mark.parametrize(
    ("size", "colour"), [((80, 24), "no_color"), ((120, 40), "colour")], ids=["no_color", "120x40"]
)
def test_repeatability_dashboard_variants(snap_compare, lab, tui, monkeypatch, size, colour):
    if colour == "no_color":
        monkeypatch.setenv("NO_COLOR", "1")
    app = _demo_app(lab, "repeatability", 30)

    async def run(pilot) -> None:
        await _start(pilot, tui)
        await _until_action(pilot, tui, "capture")
        for _ in range(20):
            await tui.capture_one(pilot)
        await pilot.press("z")  # the warming-up axis, with its alarms
        await pilot.pause(0.3)

    assert snap_compare(app, terminal_size=size, run_before=run)


# ---- relative accuracy ----------------------------------------------------------------------


def test_relative_accuracy_setup(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _setup(pilot, tui)

    app = _demo_app(lab, "relative_accuracy", 2)
    assert snap_compare(app, terminal_size=(80, 24), run_before=run)


def test_relative_accuracy_checklist(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _start(pilot, tui)

    app = _demo_app(lab, "relative_accuracy", 2)
    assert snap_compare(app, terminal_size=(80, 24), run_before=run)


def test_relative_accuracy_pendant_step(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _start(pilot, tui)
        await _until_action(pilot, tui, "input")
        await tui.wait_until(pilot, lambda: len(pilot.app.screen.query("#step-inputs Input")) == 3)
        screen = pilot.app.screen
        for field in screen.query("#step-inputs Input"):
            field.cursor_blink = False  # a blinking cursor is not the same picture twice
        # Focused, its row marked, and the fields scrolled into view (however slow the machine).
        await tui.wait_until(
            pilot,
            lambda: (
                screen.focused is not None
                and screen.focused.id == "input-x"
                and screen.focused.parent.has_class("-has-focus")
            ),
            timeout=30.0,
        )
        panel = screen.query_one("#step-panel")
        last = screen.query("#step-inputs Input").last()
        await tui.wait_until(pilot, lambda: panel.region.contains_region(last.region), timeout=30.0)
        await pilot.pause(0.3)

    app = _demo_app(lab, "relative_accuracy", 2)
    assert snap_compare(app, terminal_size=(80, 24), run_before=run)


def test_relative_accuracy_capture(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _start(pilot, tui)
        await _until_action(pilot, tui, "capture")

    app = _demo_app(lab, "relative_accuracy", 2)
    assert snap_compare(app, terminal_size=(80, 24), run_before=run)


def test_relative_accuracy_after_a_capture(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        from station.tui.screens.checklist import ChecklistScreen

        await _start(pilot, tui)
        await _until_action(pilot, tui, "capture")
        await pilot.press("space")
        await tui.wait_until(pilot, lambda: isinstance(pilot.app.screen, ChecklistScreen))
        await pilot.pause(0.3)

    app = _demo_app(lab, "relative_accuracy", 2)
    assert snap_compare(app, terminal_size=(80, 24), run_before=run)


def test_relative_accuracy_summary(snap_compare, monkeypatch) -> None:
    app = _saved_app(monkeypatch)
    assert snap_compare(app, terminal_size=(80, 24), run_before=_review("relative_accuracy"))


# ---- linearity ------------------------------------------------------------------------------


def test_linearity_setup(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _setup(pilot, tui)

    assert snap_compare(_demo_app(lab, "linearity", 3), terminal_size=(80, 24), run_before=run)


def test_linearity_checklist(snap_compare, lab, tui) -> None:
    async def run(pilot) -> None:
        await _start(pilot, tui)

    assert snap_compare(_demo_app(lab, "linearity", 3), terminal_size=(80, 24), run_before=run)


def test_linearity_strokes_of_a_saved_session(snap_compare, monkeypatch) -> None:
    """The stroke dashboard (deviation plot, straightness chart), from the summary's ``d``.
    The live one is not pinned: the simulated bar shuttles from the moment the step begins, so
    what is drawn depends on when the picture is taken."""
    review = _review("linearity")

    async def run(pilot) -> None:
        await review(pilot)
        await pilot.press("d")
        await pilot.pause(0.5)

    app = _saved_app(monkeypatch)
    assert snap_compare(app, terminal_size=(80, 24), run_before=run)


def test_linearity_summary(snap_compare, monkeypatch) -> None:
    app = _saved_app(monkeypatch)
    assert snap_compare(app, terminal_size=(80, 24), run_before=_review("linearity"))
