"""The alarm list: full texts, scrollable, acknowledged with a cause from the procedure."""

from __future__ import annotations

from textual.app import App
from textual.widgets import Input, ListView

from station.session.alarms import AckRequest, RecordedAlarm
from station.tui.screens.alarms import AckDialog, AlarmsScreen

LONG = (
    "Cycles 14 to 22: the EWMA (+0.00031 in) is above its upper limit (+0.00019 in): the "
    "mean is drifting up; let the robot warm up, look for a loose fixture or gauge, and repeat."
)


def alarms() -> list[RecordedAlarm]:
    return [
        RecordedAlarm(
            seq=40 + i,
            channel="z",
            rule="ewma" if i % 2 else "report-1",
            rule_name="drift rule" if i % 2 else "report rule 1 (a point beyond the limits)",
            text=f"{LONG} [{i}]" if i % 2 else f"Cycle {i} is above the upper control limit.",
            cycles=(i,),
            live=True,
            t="",
        )
        for i in range(1, 13)
    ]


class AlarmsApp(App):
    def __init__(self, causes=("fixture moved", "gauge", "temperature", "robot", "other")):
        super().__init__()
        self.requests: list[AckRequest] = []
        self.causes = causes

    def on_mount(self) -> None:
        self.push_screen(AlarmsScreen(alarms(), self.causes, self.requests.append))


def screen_text(app) -> str:
    return "\n".join(str(item.children[0].render()) for item in app.screen.query("AlarmItem"))


async def test_the_list_shows_full_texts_and_scrolls():
    app = AlarmsApp()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        screen = app.screen
        assert isinstance(screen, AlarmsScreen)
        # The whole sentence, wrapped, never cut at 80 columns.
        assert LONG.replace(" ", "") in screen_text(app).replace(" ", "").replace("\n", "")
        view = screen.query_one(ListView)
        for _ in range(11):
            await pilot.press("down")
        assert view.index == 11 and view.scroll_y > 0


async def test_an_alarm_is_acknowledged_with_a_cause_text_and_action():
    app = AlarmsApp()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        await pilot.press("down", "a")
        await pilot.pause()
        assert isinstance(app.screen, AckDialog)
        await pilot.press("down", "down", "enter")  # temperature
        await pilot.press(*"door open", "enter")
        await pilot.press(*"waited 30 min", "enter")
        await pilot.pause()
        assert app.requests == [AckRequest(42, "temperature", "door open", "waited 30 min")]
        assert isinstance(app.screen, AlarmsScreen)
        text = screen_text(app)
        assert "acknowledged: temperature (door open); corrective action: waited 30 min" in text
        assert "Alarms: 12, 11 not acknowledged" in str(
            app.screen.query_one("#alarm-title").render()
        )


async def test_other_needs_a_text_and_escape_cancels():
    app = AlarmsApp(causes=("gauge", "other"))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        await pilot.press("a", "down", "enter", "enter", "enter")
        await pilot.pause()
        dialog = app.screen
        assert isinstance(dialog, AckDialog)
        assert "'other' needs a short text" in str(dialog.query_one("#ack-error").render())
        assert app.focused is dialog.query_one("#ack-text", Input)
        await pilot.press("escape")
        await pilot.pause()
        assert isinstance(app.screen, AlarmsScreen) and app.requests == []


async def test_a_recorded_sessions_list_is_read_only():
    class ReadOnly(App):
        def on_mount(self) -> None:
            self.push_screen(AlarmsScreen(alarms(), read_only=True))

    app = ReadOnly()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        await pilot.press("a")
        await pilot.pause()
        assert isinstance(app.screen, AlarmsScreen)
        text = screen_text(app)
        assert "not acknowledged" in text and "press a" not in text
