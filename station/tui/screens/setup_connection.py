"""The set-up's live "test connection" (F3): open the line the form names, show a few readings
at the gauge's resolution with their unit, judge the frames against the form's unit and
resolution. Nothing is recorded.

:class:`ConnectionTestScreen` is the set-up screen's base: the screen gives it the form
(``form_value``, ``refuse``, ``clear_errors``, ``show_buttons``).
"""

from __future__ import annotations

from typing import Any

from textual import work
from textual.screen import Screen
from textual.widgets import Static

from station.errors import StationError
from station.tui.instruments import test_connection
from station.tui.messages import ConnectionTested
from station.tui.remedies import explained
from station.tui.screens.setup_checks import read_ports, read_resolution
from station.tui.text import shown


class ConnectionTestScreen(Screen[None]):
    """A screen with a form naming a gauge line, and F3 to test that line."""

    _testing = False

    def form_value(self, field_id: str) -> str:
        """The text in the form's field ``field_id``, stripped (the screen says how)."""
        raise NotImplementedError

    def refuse(self, errors: dict[str, str]) -> None:
        """Put each sentence under its field (the screen says how)."""
        raise NotImplementedError

    def clear_errors(self) -> None:
        """Take the old sentences away (the screen says how)."""
        raise NotImplementedError

    def show_buttons(self) -> None:
        """Bring the test's output and the buttons into view (the screen says how)."""
        raise NotImplementedError

    def action_test_connection(self) -> None:
        """Open the port and show a few readings; nothing is recorded."""
        errors: dict[str, str] = {}
        self.clear_errors()
        ports = read_ports(self.form_value, errors)
        if errors:
            self.refuse(errors)
            return
        if self._testing:
            return
        self._testing = True
        self.query_one("#test-output", Static).update(
            shown(f"Opening {ports[0].url} ...", style="yellow")
        )
        unit = self.form_value("unit") or None
        self._test_connection(
            ports, self.form_value("trigger"), unit, read_resolution(self.form_value)
        )

    @work(thread=True, group="test-connection", exclusive=True, exit_on_error=False)
    def _test_connection(
        self,
        ports: tuple[Any, ...],
        trigger: str,
        unit: str | None = None,
        resolution: float | None = None,
    ) -> None:
        """Thread worker: a few captures through the real reader, posted line by line, then
        the frames judged against the form's unit and resolution."""
        try:
            for lines in test_connection(ports, trigger, unit=unit, resolution=resolution):
                self.post_message(ConnectionTested(lines=lines))
            self.post_message(ConnectionTested(done=True))
        except StationError as error:
            self.post_message(ConnectionTested(error=explained(error), done=True))

    def on_connection_tested(self, message: ConnectionTested) -> None:
        """Show the readings (or why there are none)."""
        output = self.query_one("#test-output", Static)
        if message.error:
            output.update(shown(message.error, style="bold red"))
        elif message.lines:
            output.update(shown("\n".join(message.lines), style="green"))
        # Keep the readings and the buttons under them in view (once laid out).
        self.call_after_refresh(self.show_buttons)
        if message.done:
            self._testing = False
