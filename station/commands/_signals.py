"""The stop signals (SIGHUP, SIGINT, SIGTERM) of a command that must end with an exit code that
says so (128 + the signal), never be killed by one halfway through a line or a summary.

The command line takes them before it loads the command (:func:`keep_stop_signals`), so even a
signal during the imports is an exit code and one line. Until the command holds them
(:meth:`StopSignals.hold`, once it starts to do what must not be cut short), a signal stops it
at once with :class:`StoppedBySignal`: nothing has been written yet. From then on a signal is
only recorded, for the command to act on where it is safe, and stays so until the process exits.
"""

from __future__ import annotations

import signal
from types import FrameType

STOP_SIGNALS = (signal.SIGHUP, signal.SIGINT, signal.SIGTERM)


class StoppedBySignal(BaseException):
    """A stop signal before the command held them. A BaseException, like KeyboardInterrupt,
    so no ``except Exception`` on the way swallows it."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum

    @property
    def name(self) -> str:
        """``SIGTERM``."""
        return signal.Signals(self.signum).name


class StopSignals:
    """The stop signals taken by this process (see the module)."""

    def __init__(self) -> None:
        self.caught: list[int] = []
        """The signals received since the command held them, first first."""
        self._holding = False
        self._previous: dict[int, object] = {}

    def install(self) -> None:
        """Take the stop signals from now on (on the main thread)."""
        for signum in STOP_SIGNALS:
            self._previous[signum] = signal.signal(signum, self._received)

    def hold(self) -> None:
        """From now on record a signal rather than stop at once."""
        self._holding = True

    def restore(self) -> None:
        """Give the signals back to the handlers they had before :meth:`install`."""
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]
        self._previous.clear()

    def _received(self, signum: int, frame: FrameType | None) -> None:
        if not self._holding:
            raise StoppedBySignal(signum)
        self.caught.append(signum)


_taken: StopSignals | None = None


def keep_stop_signals() -> StopSignals:
    """The process's :class:`StopSignals`, installed on the first call."""
    global _taken
    if _taken is None:
        _taken = StopSignals()
        _taken.install()
    return _taken


def ignore_stop_signals_to_exit() -> None:
    """The command is over: a stop signal from now on has nothing left to stop. Ignored, as
    the interpreter's shutdown would otherwise put back the default action (a raw kill by
    SIGTERM in the last instructions, after the summary was printed whole)."""
    for signum in STOP_SIGNALS:
        signal.signal(signum, signal.SIG_IGN)


def release_stop_signals() -> None:
    """Give the stop signals back (a command run in-process, as the tests do, is over)."""
    global _taken
    if _taken is not None:
        _taken.restore()
        _taken = None
