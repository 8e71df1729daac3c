"""Issue 13, finding 9: one number format per screen, and a table whose columns stand still.

Each test reads what the terminal shows (Pilot) and checks every figure on it with
``tui.odd_figures`` (conftest): no scientific notation, no signed spread, and every figure in
the session's unit at the same decimals. The stroke screen is checked in
``test_tui_procedures.py``'s linearity walk, the test connection's readings in
``test_operator.py``.
"""

from __future__ import annotations

from pathlib import Path

from station.tui.app import StationApp, StationConfig

SAVED = Path(__file__).resolve().parent / "snapshots" / "sessions"


def _saved_app() -> StationApp:
    return StationApp(
        StationConfig(sessions_dir=SAVED, sessions_reason="the tests' saved sessions")
    )


SESSIONS = {
    "repeatability": "2026-11-23T175031Z_R1_repeatability.jsonl",
    "relative_accuracy": "2026-11-29T211527Z_demo-robot_relative_accuracy.jsonl",
    "linearity": "2026-11-29T211526Z_demo-robot_linearity.jsonl",
}


async def _summary(pilot, tui, procedure: str) -> None:
    from station.tui.screens.summary import SummaryScreen, SummaryView

    app = pilot.app
    view = SummaryView.from_file(SAVED / SESSIONS[procedure])
    app.push_screen(SummaryScreen(view, reviewing=True))
    await tui.wait_until(pilot, lambda: isinstance(app.screen, SummaryScreen))
    await pilot.pause(0.3)


async def test_each_summary_writes_every_figure_one_way(tui) -> None:
    """Before: "Zero taken: x +0.0114" beside "X̄ -0.00043", "-4.69e-05" for the error per
    unit moved, "straightness tolerance 0.002" beside "upper limit 0.00200"."""
    for procedure in SESSIONS:
        app = _saved_app()
        # Tall enough that the whole summary is on screen at once.
        async with app.run_test(size=(80, 90)) as pilot:
            await _summary(pilot, tui, procedure)
            text = tui.screen_text(app)
            assert "Verdict" in text
            assert tui.odd_figures(text) == [], (procedure, text)


def _column_starts(header: str) -> dict[str, int]:
    return {word: header.index(word) for word in ("reading", "X̄", "σ", "range", "verdict")}


async def test_the_dashboard_writes_one_format_and_its_columns_stand_still(
    tmp_path: Path, fixture_pty, tui
) -> None:
    """Before: the zero line said ``-0.3750`` beside the table's ``+0.00000``, and the table's
    columns moved as σ and a₁ appeared (``n           X̄  σ`` at cycle 1, ``n          X̄
    σ`` at cycle 2)."""
    app = StationApp(
        StationConfig(sessions_dir=tmp_path, sessions_reason="test folder", capture_timeout=3.0)
    )
    async with app.run_test(size=(80, 24)) as pilot:
        await tui.open_setup(pilot, "R9", fixture_pty.url)
        await pilot.press("f2")
        await tui.walk_checklist(pilot)
        headers = []
        for _ in range(3):
            await tui.capture_one(pilot)
            app.redraw_live()
            await pilot.pause(0.2)
            text = tui.screen_text(app)
            header = next(line for line in text.splitlines() if "reading" in line)
            headers.append(_column_starts(header))
            assert "zero " in text  # the zero line, beside the table
            # Whole, never cut at 80 columns ("zero x +0.…" before): on its own line when the
            # port's status leaves no room beside it.
            (zero,) = [line for line in text.splitlines() if "zero x " in line]
            assert "…" not in zero and zero.rstrip().endswith("readings)"), zero
            assert tui.odd_figures(text) == [], text
        assert headers[0] == headers[1] == headers[2], headers
