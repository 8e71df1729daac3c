"""The dashboard's control chart once the limits are frozen (phase II): it draws the frozen
limits the live alarms are judged against, and marks those alarms, not the phase-I limits that
kept moving with every reading."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from station.analysis.capability import SpecLimits
from station.analysis.summary import AnalysisConfig, analyze
from station.text import format_figure
from station.tui.app import StationApp, StationConfig
from station.tui.widgets.control_chart import chart_data, render_chart

RESOLUTION = 0.0001
SAVED = Path(__file__).resolve().parent / "snapshots" / "sessions"


def _gutter(lines: list[str], name: str) -> str:
    """The value written beside the control line ``name`` (UCL, CL, LCL)."""
    row = next(line for line in lines if line.lstrip().startswith(f"{name} "))
    return row.split()[1]


def test_after_the_freeze_the_chart_draws_the_frozen_limits_and_their_alarms() -> None:
    rng = np.random.default_rng(5)
    steady = np.round(rng.normal(0.0, 0.0001, 20) / RESOLUTION) * RESOLUTION
    # After the freeze the robot shifts by 0.0008: the moving limits follow it, the frozen
    # ones do not, and the live alarms are judged against the frozen ones.
    shifted = steady[:10] + 0.0008
    config = AnalysisConfig(
        limits={"x": SpecLimits(lsl=-0.002, usl=0.002, nominal=0.0)},
        resolution=RESOLUTION,
        unit="in",
        freeze_after=20,
    )
    channel = analyze({"x": np.concatenate([steady, shifted])}, config).channels["x"]
    frozen = channel.frozen
    assert frozen is not None and channel.live_alarms
    moving = channel.chart
    assert format_figure(moving.ucl, RESOLUTION) != format_figure(frozen.ucl, RESOLUTION)

    lines = render_chart(chart_data(channel, list(range(1, 31)), RESOLUTION), 60, 16).plain
    rows = lines.splitlines()
    assert "frozen limits" in rows[0]
    assert _gutter(rows, "UCL") == format_figure(frozen.ucl, RESOLUTION), lines
    assert _gutter(rows, "CL") == format_figure(frozen.center, RESOLUTION), lines
    # The shifted points raise live alarms against the frozen limits: marked on the chart.
    assert "✖" in lines


async def test_the_dashboard_of_a_frozen_session_shows_its_frozen_limits(tui) -> None:
    """Pilot: a saved session of 30 cycles (limits frozen after 20 points), its charts from
    the summary's ``d``: the UCL beside the chart is the frozen one, not the phase-I one."""
    from station.tui.screens.dashboard import DashboardScreen
    from station.tui.screens.summary import SummaryScreen, SummaryView
    from station.tui.widgets.control_chart import ControlChartView

    view = SummaryView.from_file(SAVED / "2026-11-23T175031Z_R1_repeatability.jsonl")
    x = view.analysis.channels["x"]
    frozen_ucl = format_figure(x.frozen.ucl, RESOLUTION)
    assert frozen_ucl != format_figure(x.chart.ucl, RESOLUTION)
    app = StationApp(StationConfig(sessions_dir=SAVED, sessions_reason="the tests' sessions"))
    async with app.run_test(size=(80, 24)) as pilot:
        app.push_screen(SummaryScreen(view, reviewing=True))
        await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
        await pilot.pause(0.2)
        await pilot.press("d")
        await tui.wait_until(pilot, lambda: isinstance(app.screen, DashboardScreen))
        await pilot.pause(0.3)
        chart = str(app.screen.query_one(ControlChartView).render())
        assert "frozen limits" in chart, chart
        assert f"UCL {frozen_ucl}" in chart, chart
