"""What the engine tells its listener, and the live analysis it computes for it.

A notice goes to the listener as soon as its event is on disk, with the engine's state after
it: a reading set's notice costs no analysis, so the intake keeps up with the devices whatever
the session's length. The live analysis (the kind's snapshot: O(n), with the distribution tests)
is computed apart, on the engine's own *analysis* thread, from a copy of the readings taken
under the lock, and goes out in a notice of its own: at once when the engine was quiet, else at
most once every :data:`ANALYSIS_INTERVAL` (a burst of sets costs one analysis, never a queue
of them). It is the same analysis :meth:`LiveNotices.analysis` returns, computed from the same
readings; only when it is computed changes.

:class:`LiveNotices` is a part of :class:`~station.run.engine.Runner` (its attributes are set
up there).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from station.errors import StationError
from station.run.state import OperatorMessage, RunnerNotice

ANALYSIS_INTERVAL = 0.1
"""Seconds between two live analyses sent to the listener: at most ~10 a second (a display
redraws its charts no more often), however fast the sets come."""


class LiveNotices:
    """The engine's notices and its live analysis (a part of the Runner)."""

    def _start_analysis_thread(self) -> None:
        """Start the thread that sends the live analysis to the listener (none without a
        listener: :meth:`analysis` computes it when asked)."""
        if self._listener is None:
            return
        self._analysis_thread = threading.Thread(
            target=self._send_analyses, name="runner analysis", daemon=True
        )
        self._analysis_thread.start()

    def _stop_analysis_thread(self) -> None:
        """The analysis thread ends (it sends nothing once the file is closed). Lock held."""
        self._analysis_stop = True
        self._analysis_wanted.set()

    def _live_changed(self) -> None:
        """The live analysis took a set, a stroke, a reject or a new zero: the analysis thread
        sends the new analysis. Lock held."""
        self._live_version += 1
        self._analysis_wanted.set()

    def _send_analyses(self) -> None:
        """The analysis thread: whenever the live analysis changed, compute it from a copy of
        its readings (without the lock) and send it with the state of that moment."""
        started_at = float("-inf")
        while True:
            self._analysis_wanted.wait()
            if self._analysis_stop:
                return
            # Coalesce: sets that come meanwhile join this analysis.
            time.sleep(max(0.0, started_at + ANALYSIS_INTERVAL - time.monotonic()))
            self._analysis_wanted.clear()
            if self._analysis_stop:
                return
            started_at = time.monotonic()
            try:
                analysis, result, _ = self._analyse()
            except Exception as error:  # a kind's bug must not stop the notices
                with self.lock:
                    self.say("error", f"the live analysis failed: {error!r}")
                continue
            with self.lock:
                if self._writer.closed:
                    return  # the closing notice carried the final analysis
                self._tell(RunnerNotice(None, self.state(), analysis=analysis, result=result))

    def _analyse(self) -> tuple[Any, Any, StationError | None]:
        """The live analysis, the kind's own result and why there is no analysis (``None``,
        ``None`` and the kind's sentence while there is nothing to analyse): computed from a
        copy of the readings taken under the lock, outside it unless the caller holds it, and
        kept until the live analysis changes again."""
        with self.lock:
            version = self._live_version
            known = self._analysed
            if known is not None and known[0] == version:
                return known[1:]
            copy = self._live.copy()
            rejected = self._rejected_cycles
        problem = None
        try:
            analysis = copy.snapshot()
            if hasattr(analysis, "excluded_cycles"):
                analysis = replace(analysis, excluded_cycles=rejected)
        except StationError as error:
            analysis, problem = None, error
        result = copy.result()
        with self.lock:
            if self._live_version == version:
                self._analysed = (version, analysis, result, problem)
        return analysis, result, problem

    def analysis(self) -> Any:
        """The live analysis of the session so far (the method's; for repeatability equal
        to the batch analysis of the session file). StationError before there is anything."""
        analysis, _, problem = self._analyse()
        if problem is not None:
            raise problem
        return analysis

    def analysis_or_none(self) -> Any:
        """:meth:`analysis`, or ``None`` while there is nothing to analyse."""
        return self._analyse()[0]

    def _notify(self, event: Mapping[str, Any] | None, *, analysis: bool = False) -> None:
        """Tell the listener of ``event`` (None: a change not in the file) with the state now,
        and (``analysis``) the live analysis computed now. Lock held."""
        if self._listener is None:
            return
        live, result, _ = self._analyse() if analysis else (None, None, None)
        self._tell(RunnerNotice(event, self.state(), analysis=live, result=result))

    def _tell(self, notice: RunnerNotice) -> None:
        if self._listener is None:
            return
        try:
            self._listener(notice)
        except Exception as error:  # a display's bug must not undo a recorded event
            self._messages.append(OperatorMessage("error", f"the display failed: {error!r}"))
